//! Exact medians of sequences too long to keep in memory.
//!
//! The timing checks compare every time step of a log with the median step, and the
//! processing's sampling rate is the inverse median step; a log streamed in blocks
//! cannot keep its steps to sort them. The steps can be read again, though (the log is
//! a file), so the median is found in passes: the first pass counts the distinct
//! values (a uniform log has one step value, or a few that differ by rounding) and, if
//! there are too many to count, each further pass narrows the range holding each of
//! the two middle ranks by a histogram of [`BUCKETS`] buckets. Memory is bounded by
//! [`DISTINCT_LIMIT`] and [`BUCKETS`], and a 64-bit key range is narrowed to a single
//! value in at most four further passes.
//!
//! Values are `u64` keys whose order is the order of the values: a positive integer
//! step in nanoseconds as it is, a positive `f64` step by its bit pattern
//! ([`f64::to_bits`] is monotonic on positive numbers).

use std::collections::BTreeMap;

/// Distinct values counted exactly in the first pass before falling back to histograms.
pub const DISTINCT_LIMIT: usize = 1 << 14;

/// Buckets of each refinement histogram.
pub const BUCKETS: u64 = 1 << 16;

/// What a pass found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MedianPass {
    /// The two middle values in order (equal for an odd count); `None` for no value.
    Done(Option<(u64, u64)>),
    /// Read the sequence again, calling [`ExactMedian::observe`] for every value.
    Again,
}

/// The narrowing search for one rank: its value lies in `lo..=hi`, and `below` values
/// are smaller than `lo`.
#[derive(Clone, Debug)]
struct Target {
    rank: u64,
    lo: u64,
    hi: u64,
    below: u64,
    width: u64,
    histogram: Vec<u64>,
}

impl Target {
    fn new(rank: u64, lo: u64, hi: u64) -> Target {
        let mut t = Target {
            rank,
            lo,
            hi,
            below: 0,
            width: 1,
            histogram: Vec::new(),
        };
        t.reset();
        t
    }

    fn resolved(&self) -> bool {
        self.lo == self.hi
    }

    /// Buckets for the next pass over `lo..=hi`.
    fn reset(&mut self) {
        let span = u128::from(self.hi - self.lo) + 1;
        self.width = span.div_ceil(u128::from(BUCKETS)) as u64;
        let buckets = span.div_ceil(u128::from(self.width)) as usize;
        self.histogram.clear();
        self.histogram
            .resize(if self.resolved() { 0 } else { buckets }, 0);
    }

    fn observe(&mut self, key: u64) {
        if !self.resolved() && (self.lo..=self.hi).contains(&key) {
            self.histogram[((key - self.lo) / self.width) as usize] += 1;
        }
    }

    /// Narrows to the bucket holding the rank.
    fn narrow(&mut self) {
        if self.resolved() {
            return;
        }
        let mut seen = self.below;
        for (b, &c) in self.histogram.iter().enumerate() {
            if seen + c > self.rank {
                self.below = seen;
                self.lo += b as u64 * self.width;
                self.hi = self.hi.min(self.lo.saturating_add(self.width - 1));
                break;
            }
            seen += c;
        }
        self.reset();
    }
}

/// Exact median of a sequence read in one or more passes (see the module docs).
#[derive(Clone, Debug)]
pub struct ExactMedian {
    first_pass: bool,
    count: u64,
    min: u64,
    max: u64,
    /// Exact counts while there are at most [`DISTINCT_LIMIT`] distinct values.
    distinct: Option<BTreeMap<u64, u64>>,
    targets: Vec<Target>,
}

impl Default for ExactMedian {
    fn default() -> Self {
        ExactMedian {
            first_pass: true,
            count: 0,
            min: u64::MAX,
            max: 0,
            distinct: Some(BTreeMap::new()),
            targets: Vec::new(),
        }
    }
}

impl ExactMedian {
    /// One value of the sequence (every pass must give the same values).
    pub fn observe(&mut self, key: u64) {
        if self.first_pass {
            self.count += 1;
            self.min = self.min.min(key);
            self.max = self.max.max(key);
            if let Some(d) = &mut self.distinct {
                *d.entry(key).or_insert(0) += 1;
                if d.len() > DISTINCT_LIMIT {
                    self.distinct = None;
                }
            }
        } else {
            for t in &mut self.targets {
                t.observe(key);
            }
        }
    }

    /// Number of values of the sequence.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The smallest and largest values (after the first pass; `None` for no value).
    pub fn range(&self) -> Option<(u64, u64)> {
        (self.count > 0).then_some((self.min, self.max))
    }

    /// Ends a pass over the sequence.
    pub fn end_pass(&mut self) -> MedianPass {
        let ranks = [(self.count.max(1) - 1) / 2, self.count / 2];
        if self.first_pass {
            self.first_pass = false;
            if self.count == 0 {
                return MedianPass::Done(None);
            }
            if let Some(d) = &self.distinct {
                let mut found = [0u64; 2];
                for (i, rank) in ranks.iter().enumerate() {
                    let mut seen = 0;
                    for (&v, &c) in d {
                        seen += c;
                        if seen > *rank {
                            found[i] = v;
                            break;
                        }
                    }
                }
                self.distinct = None;
                return MedianPass::Done(Some((found[0], found[1])));
            }
            self.targets = ranks
                .iter()
                .map(|&r| Target::new(r, self.min, self.max))
                .collect();
        } else {
            for t in &mut self.targets {
                t.narrow();
            }
        }
        if self.targets.iter().all(Target::resolved) {
            MedianPass::Done(Some((self.targets[0].lo, self.targets[1].lo)))
        } else {
            MedianPass::Again
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs passes over `values` until done, counting them.
    fn median_of(values: &[u64]) -> (Option<(u64, u64)>, usize) {
        let mut m = ExactMedian::default();
        let mut passes = 0;
        loop {
            passes += 1;
            for &v in values {
                m.observe(v);
            }
            if let MedianPass::Done(r) = m.end_pass() {
                return (r, passes);
            }
        }
    }

    fn sorted_middle(values: &[u64]) -> (u64, u64) {
        let mut s = values.to_vec();
        s.sort_unstable();
        let n = s.len();
        (s[(n - 1) / 2], s[n / 2])
    }

    #[test]
    fn few_distinct_values_take_one_pass() {
        let v: Vec<u64> = (0..10_001).map(|k| 5_000_000 + (k % 3)).collect();
        assert_eq!(median_of(&v), (Some(sorted_middle(&v)), 1));
        assert_eq!(median_of(&[7]), (Some((7, 7)), 1));
        assert_eq!(median_of(&[9, 2]), (Some((2, 9)), 1));
        assert_eq!(median_of(&[]), (None, 1));
    }

    #[test]
    fn many_distinct_values_are_narrowed_exactly() {
        // Jittered nanosecond steps, a few huge gaps, and f64 bit patterns: every case
        // needs the histograms, and the result must equal sorting.
        let mut rng = dvrk_test_support::Rng::new(0x2545_F491_4F6C_DD1D);
        let mut next = move || rng.next_u64();
        let jitter: Vec<u64> = (0..50_001).map(|_| 4_900_000 + next() % 200_000).collect();
        let mut gaps = jitter.clone();
        gaps[10] = u64::MAX - 3;
        gaps[20] = 1;
        let floats: Vec<u64> = (0..40_000)
            .map(|_| (0.005 + (next() % 1_000_000) as f64 * 1e-12).to_bits())
            .collect();
        for v in [&jitter, &gaps, &floats, &jitter[..50_000].to_vec()] {
            let (got, passes) = median_of(v);
            assert_eq!(got, Some(sorted_middle(v)));
            assert!((2..=5).contains(&passes), "{passes} passes");
        }
    }
}
