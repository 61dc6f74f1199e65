//! Progress reporting for steps that can take seconds (reading a long log, assembling
//! the observation, solving, optimizing trajectories).
//!
//! The library only announces stages and counts work; how (or whether) that is shown is
//! the caller's choice: the CLI draws indicatif bars, the Python module and the tests
//! stay silent. The trait is `Sync` because the observation is assembled by rayon
//! workers that report from several threads.

/// Receiver of progress events. Every method has an empty default, so an observer
/// implements only what it shows.
///
/// ```
/// use dvrk_ident::{Progress, Silent};
/// use std::sync::atomic::{AtomicU64, Ordering};
///
/// /// Counts the work units reported, e.g. to check a pipeline reports all samples.
/// #[derive(Default)]
/// struct Counter(AtomicU64);
/// impl Progress for Counter {
///     fn advance(&self, units: u64) {
///         self.0.fetch_add(units, Ordering::Relaxed);
///     }
/// }
///
/// let counter = Counter::default();
/// counter.stage("assembling", Some(10));
/// counter.advance(4);
/// counter.advance(6);
/// counter.finish();
/// assert_eq!(counter.0.load(Ordering::Relaxed), 10);
/// Silent.stage("nothing shown", None);
/// ```
pub trait Progress: Sync {
    /// A new stage begins; `total` work units if known (samples, iterations, bytes).
    fn stage(&self, _name: &str, _total: Option<u64>) {}
    /// `units` more work units of the current stage are done.
    fn advance(&self, _units: u64) {}
    /// The current stage is done.
    fn finish(&self) {}
}

/// Shows nothing: the default for library callers.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}
