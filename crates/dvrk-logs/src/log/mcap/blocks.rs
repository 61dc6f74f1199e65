//! The samples of an MCAP log, block by block: the chosen topics' messages in file
//! order, merged on the first topic's clock as they come, resampled if asked.
//!
//! A clock sample waits until every other topic has a sample at or after its stamp,
//! then takes each topic's value at that stamp (the sample with the same stamp, or the
//! linear interpolation between the two around it); each other topic keeps only the
//! samples that can still be needed. Memory is bounded by how far the topics are apart
//! in the file (a recorder writes them interleaved), not by the log.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::bag::Bag;
use super::container::Scanner;
use super::problem::mcap_error;
use super::survey::{seconds_between, Plan};
use super::topic::{decode, is_joint_state, JointRow, TopicState};
use super::McapProblem;
use crate::joint_log::{Coordinates, JointLog};
use crate::log::LogError;
use crate::resample::Resampler;

/// Clock samples waiting for the other topics, and the other topics' recent samples.
struct Merge {
    span: (i64, i64),
    widths: Vec<usize>,
    with_velocity: bool,
    pending: VecDeque<JointRow>,
    /// The latest clock stamp read: later clock samples come after it.
    clock_last: Option<i64>,
    others: Vec<VecDeque<JointRow>>,
}

impl Merge {
    fn dof(&self) -> usize {
        self.widths.iter().sum()
    }

    /// The earliest stamp a clock sample can still need.
    fn needed(&self) -> i64 {
        match self.pending.front() {
            Some(r) => r.stamp,
            None => self
                .clock_last
                .map_or(self.span.0, |t| self.span.0.max(t.saturating_add(1))),
        }
    }

    fn add(&mut self, topic: usize, row: &JointRow) {
        if topic == 0 {
            self.clock_last = Some(row.stamp);
            if (self.span.0..=self.span.1).contains(&row.stamp) {
                self.pending.push_back(row.clone());
            }
        } else {
            let needed = self.needed();
            let w = &mut self.others[topic - 1];
            w.push_back(row.clone());
            while w.len() >= 2 && w[1].stamp <= needed {
                w.pop_front();
            }
        }
    }

    /// Merges the waiting clock samples that every topic can give (all of them at
    /// the end of the file), calling `out(stamp, q | dq | tau)`.
    fn drain(&mut self, at_end: bool, out: &mut impl FnMut(i64, &[f64])) {
        let dof = self.dof();
        let mut merged = vec![0.0; 3 * dof];
        while let Some(clock) = self.pending.front() {
            let t = clock.stamp;
            let ready = self
                .others
                .iter()
                .all(|w| w.back().is_some_and(|s| s.stamp >= t));
            if !ready && !at_end {
                return;
            }
            let clock = self.pending.pop_front().expect("front");
            let put = |merged: &mut [f64], col: usize, values: [&[f64]; 3]| {
                for (signal, v) in values.into_iter().enumerate() {
                    let at = signal * dof + col;
                    merged[at..at + v.len()].copy_from_slice(v);
                }
            };
            put(
                &mut merged,
                0,
                [&clock.position, &clock.velocity, &clock.effort],
            );
            let mut col = self.widths[0];
            for (k, w) in self.others.iter_mut().enumerate() {
                // The last sample at or before t, then the sample with t's stamp or
                // the interpolation towards the next one.
                while w.len() >= 2 && w[1].stamp <= t {
                    w.pop_front();
                }
                match (w.front(), w.get(1)) {
                    (Some(a), Some(b)) if a.stamp != t => {
                        let f = seconds_between(a.stamp, t) / seconds_between(a.stamp, b.stamp);
                        let mix = |x: &[f64], y: &[f64]| -> Vec<f64> {
                            x.iter()
                                .zip(y)
                                .map(|(x, y)| (1.0 - f) * x + f * y)
                                .collect()
                        };
                        let values = [
                            mix(&a.position, &b.position),
                            mix(&a.velocity, &b.velocity),
                            mix(&a.effort, &b.effort),
                        ];
                        put(&mut merged, col, [&values[0], &values[1], &values[2]]);
                    }
                    (Some(a), _) => put(&mut merged, col, [&a.position, &a.velocity, &a.effort]),
                    // Not reached: the plan keeps clock samples within every topic's span.
                    (None, _) => {}
                }
                col += self.widths[k + 1];
            }
            if !self.with_velocity {
                merged[dof..2 * dof].fill(0.0);
            }
            out(t, &merged);
        }
    }
}

fn resample_error(path: &Path, plan: &Plan, e: crate::resample::ResampleError) -> LogError {
    mcap_error(
        path,
        Some(&plan.topics[0]),
        McapProblem::Resample {
            reason: e.to_string(),
        },
    )
}

/// The blocks of samples of an MCAP log, in order (see [`super::McapReader::blocks`]).
pub struct McapBlocks<'a> {
    path: PathBuf,
    plan: &'a Plan,
    scanner: Scanner,
    states: Vec<TopicState>,
    merge: Merge,
    resampler: Option<Resampler>,
    /// Samples ready to go out: times (s) and `q | dq | tau` rows.
    times: VecDeque<f64>,
    rows: VecDeque<f64>,
    block: usize,
    /// Samples given out so far, and the last one's time.
    given: usize,
    last_time: Option<f64>,
    source: String,
    at_end: bool,
    failed: bool,
}

impl<'a> McapBlocks<'a> {
    pub(super) fn new(bag: &Arc<Bag>, plan: &'a Plan, block: usize) -> Result<Self, LogError> {
        let path = bag.path.as_path();
        let widths: Vec<usize> = plan.joints.iter().map(Vec::len).collect();
        let resampler = match plan.resample_hz {
            Some(rate) => Some(
                Resampler::new(3 * widths.iter().sum::<usize>(), rate)
                    .map_err(|e| resample_error(path, plan, e))?,
            ),
            None => None,
        };
        Ok(McapBlocks {
            path: path.to_path_buf(),
            scanner: Scanner::open(bag)?,
            states: plan.topics.iter().map(|t| TopicState::new(t)).collect(),
            merge: Merge {
                span: plan.span,
                clock_last: None,
                with_velocity: plan.with_velocity,
                pending: VecDeque::new(),
                others: vec![VecDeque::new(); widths.len() - 1],
                widths,
            },
            resampler,
            times: VecDeque::new(),
            rows: VecDeque::new(),
            block: block.max(1),
            given: 0,
            last_time: None,
            source: format!("{} ({})", path.display(), plan.topics.join(" + ")),
            plan,
            at_end: false,
            failed: false,
        })
    }

    /// One merged sample at `t` (s from the start), resampled if asked.
    fn emit(&mut self, t: f64, values: &[f64]) -> Result<(), LogError> {
        match &mut self.resampler {
            Some(r) => {
                let (mut grid, mut out) = (Vec::new(), Vec::new());
                r.push(t, values, &mut grid, &mut out)
                    .map_err(|e| resample_error(&self.path, self.plan, e))?;
                self.times.extend(grid);
                self.rows.extend(out);
            }
            None => {
                self.times.push_back(t);
                self.rows.extend(values);
            }
        }
        Ok(())
    }

    /// Reads messages until a block is ready or the file ends.
    fn fill(&mut self) -> Result<(), LogError> {
        let plan = self.plan;
        let mut row = JointRow::default();
        while self.times.len() < self.block && !self.at_end {
            let path = &self.path;
            let states = &mut self.states;
            let got = self.scanner.next_message(|m| {
                let Some(k) = plan.topics.iter().position(|t| *t == m.channel.topic) else {
                    return Ok(None);
                };
                if !is_joint_state(m.channel) {
                    return Ok(None);
                }
                let named = |problem| LogError::Mcap {
                    path: path.clone(),
                    topic: Some(plan.topics[k].clone()),
                    problem,
                };
                let state = &mut states[k];
                let (msg, stamp) = decode(&m, state.count, plan.time_source).map_err(named)?;
                state.check(msg, stamp, false, &mut row).map_err(named)?;
                Ok(Some(k))
            })?;
            let mut merged: Vec<(i64, Vec<f64>)> = Vec::new();
            match got {
                None => {
                    self.at_end = true;
                    self.merge
                        .drain(true, &mut |t, r| merged.push((t, r.to_vec())));
                }
                Some(None) => continue,
                Some(Some(k)) => {
                    self.merge.add(k, &row);
                    self.merge
                        .drain(false, &mut |t, r| merged.push((t, r.to_vec())));
                }
            }
            for (stamp, values) in merged {
                self.emit(seconds_between(plan.start_time_ns, stamp), &values)?;
            }
            if self.at_end {
                if let Some(r) = &mut self.resampler {
                    let (mut grid, mut out) = (Vec::new(), Vec::new());
                    r.finish(&mut grid, &mut out)
                        .map_err(|e| resample_error(&self.path, plan, e))?;
                    self.times.extend(grid);
                    self.rows.extend(out);
                }
            }
        }
        Ok(())
    }

    /// The next block, validated like the whole trajectory.
    fn next_block(&mut self) -> Result<Option<JointLog>, LogError> {
        self.fill()?;
        let n = self.times.len().min(self.block);
        if n == 0 {
            return Ok(None);
        }
        let dof = self.merge.dof();
        let time: Vec<f64> = self.times.drain(..n).collect();
        let values: Vec<f64> = self.rows.drain(..n * 3 * dof).collect();
        let all = nalgebra::DMatrix::from_row_slice(n, 3 * dof, &values);
        let block = JointLog {
            q: all.columns(0, dof).into_owned(),
            dq: self
                .plan
                .with_velocity
                .then(|| all.columns(dof, dof).into_owned()),
            tau: all.columns(2 * dof, dof).into_owned(),
            joint_names: self.plan.joints.concat(),
            coordinates: Coordinates::Measured,
            source: self.source.clone(),
            time,
        };
        block
            .validate_rows(self.given, self.last_time)
            .map_err(|e| {
                mcap_error(
                    &self.path,
                    Some(&self.plan.topics[0]),
                    McapProblem::Invalid(e),
                )
            })?;
        self.given += n;
        self.last_time = block.time.last().copied();
        Ok(Some(block))
    }
}

impl Iterator for McapBlocks<'_> {
    type Item = Result<JointLog, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        let r = self.next_block().transpose();
        self.failed = matches!(r, Some(Err(_)));
        r
    }
}
