//! The fit of logs larger than memory: the fit of logs in memory with the logs read from disk
//! block by block, in memory independent of their length.
//!
//! Each pass reads a log from its file in blocks ([`LogReader::blocks`]), maps each
//! block to model coordinates, subtracts the known forces and processes it
//! ([`BlockProcessor`]); nothing of the log is kept but running sums. The passes:
//!
//! 1. a timing survey of each log (validation, median step; an extra pass only for
//!    timing with very many distinct steps, see `median`);
//! 2. the observation: one R factor per coordinate ([`crate::observation::PerCoordinate::add`],
//!    fed batches of whole chunks counted from the log's start, so that the factors
//!    are those of the log in memory to the last bit), and the range of each processed
//!    torque. The weights are only known at the end of the log (WLS, SDP: the torque
//!    ranges), so the weighted observation is formed afterwards from the
//!    per-coordinate factors ([`crate::observation::Observation::weighted`], exact);
//! 3. IRLS only: one pass per re-weighting for the residuals (the weights are then
//!    applied to the same factors, without assembling again);
//! 4. the metrics on the test log (sums of squares, stopping after the test window);
//!    the training log's come from its factors, except in coupled measured joints
//!    ([`crate::settings::Joints`]), whose cross terms the factors lack: one more pass
//!    over the training log then.
//!
//! The fit of the logs in memory processes them with the same block processor
//! and reduces them with the same chunks, so the two give the same result to the last
//! bit (the tests require 1e-9 relative); both differ from the exact whole-log
//! [`crate::signal::process`] only by the filters' settling tolerance
//! (`SETTLE_TOLERANCE` of `signal/stream/processor.rs`).

use std::ops::ControlFlow;

use dvrk_model::Model;
use nalgebra::DMatrix;

use super::metrics::{MetricSums, TorqueRange};
use super::observed::{
    fit_observed, no_delay_search, no_training_log, MetricPasses, Observed, ObservedLog,
};
use super::prepare::{subtract_known_forces, to_model_coordinates};
use crate::error::IdentError;
use crate::log::LogReader;
use crate::observation::{PerCoordinate, Samples, CHUNK_SAMPLES};
use crate::progress::{Progress, Silent};
use crate::result::{FitResult, InputInfo};
use crate::settings::FitSettings;
use crate::signal::stream::{BlockProcessor, LogTiming, TimingSurvey};
use crate::signal::Processed;
use crate::{Coordinates, JointLog};

/// Samples per block read from a file: 4096 samples of a 7-joint log are about 1 MB
/// through the processing, and each block's observation is assembled in parallel.
pub const BLOCK_SAMPLES: usize = 4096;

/// A log on disk and how to read it for a streamed fit.
struct Source<'a> {
    reader: &'a LogReader,
    model: &'a Model,
    block: usize,
}

impl Source<'_> {
    /// The next block in model coordinates with the known forces subtracted (what
    /// [`super::prepare`](fn@super::prepare) processes).
    fn model_blocks(
        &self,
    ) -> Result<impl Iterator<Item = Result<JointLog, IdentError>> + '_, IdentError> {
        Ok(self.reader.blocks(self.block)?.map(move |b| {
            let mut t = to_model_coordinates(self.model, &b?)?;
            subtract_known_forces(self.model, &mut t);
            Ok(t)
        }))
    }

    fn signal_error(source: &str) -> impl Fn(crate::signal::SignalError) -> IdentError + '_ {
        move |error| IdentError::Signal {
            source_name: source.to_string(),
            error,
        }
    }

    /// The timing survey: every block validated, the median step.
    fn timing(&self, progress: &dyn Progress) -> Result<(LogTiming, String), IdentError> {
        let mut survey = TimingSurvey::new();
        let mut source = self.reader.path().display().to_string();
        progress.stage(
            &format!("reading {}", self.reader.path().display()),
            self.reader.samples().map(|n| n as u64),
        );
        loop {
            for block in self.model_blocks()? {
                let block = block?;
                source.clone_from(&block.source);
                progress.advance(block.len() as u64);
                survey
                    .observe(&block)
                    .map_err(|e| Self::signal_error(&block.source)(e.into()))?;
            }
            if let Some(timing) = survey
                .end_pass()
                .map_err(|e| Self::signal_error(&source)(e.into()))?
            {
                progress.finish();
                return Ok((timing, source));
            }
        }
    }

    /// The processor of a pass; its errors are the settings' and the log length's.
    fn processor(
        &self,
        settings: &FitSettings,
        (timing, source): &(LogTiming, String),
    ) -> Result<BlockProcessor, IdentError> {
        BlockProcessor::new(
            &settings.processing,
            &self.model.coordinates,
            Coordinates::Model,
            self.reader.has_velocity(),
            source,
            timing,
        )
        .map_err(Self::signal_error(source))
    }

    /// One pass: every processed block to `f`, until it breaks (the whole log is read
    /// anyway when its clock is not uniform, so that the gap is reported as by
    /// [`super::prepare`](fn@super::prepare)). Errors when no sample is left, as [`super::prepare`](fn@super::prepare).
    fn processed(
        &self,
        settings: &FitSettings,
        timing: &(LogTiming, String),
        stage: &str,
        progress: &dyn Progress,
        mut f: impl FnMut(&Processed) -> ControlFlow<()>,
    ) -> Result<(), IdentError> {
        let mut p = self.processor(settings, timing)?;
        let (timing, source) = timing;
        let fail = Self::signal_error(source);
        let may_stop = settings.processing.resample_hz.is_some()
            || timing.is_uniform(settings.processing.uniform_tolerance);
        progress.stage(stage, Some(timing.samples as u64));
        let mut kept = 0;
        let mut go = |out: &Processed| {
            kept += out.len();
            if out.is_empty() {
                ControlFlow::Continue(())
            } else {
                f(out)
            }
        };
        let mut stopped = false;
        for block in self.model_blocks()? {
            let block = block?;
            progress.advance(block.len() as u64);
            if go(&p.push(&block).map_err(&fail)?).is_break() && may_stop {
                stopped = true;
                break;
            }
        }
        if !stopped {
            let _ = go(&p.finish().map_err(&fail)?);
        }
        progress.finish();
        if kept == 0 {
            return Err(IdentError::Mismatch {
                source_name: source.clone(),
                message: "no sample left after processing (log too short for the trimming?)".into(),
            });
        }
        Ok(())
    }

    /// The metrics of `params` over the first `window` processed samples (all: `None`).
    fn metrics(
        &self,
        settings: &FitSettings,
        timing: &(LogTiming, String),
        params: &[f64],
        window: Option<usize>,
        stage: &str,
        progress: &dyn Progress,
    ) -> Result<MetricSums, IdentError> {
        let mut sums = MetricSums::new(self.model);
        self.processed(settings, timing, stage, progress, |p| {
            sums.add(self.model, params, samples(p), window);
            if window.is_some_and(|w| sums.samples() >= w) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })?;
        Ok(sums)
    }
}

/// Processed samples gathered into batches of whole observation chunks
/// ([`CHUNK_SAMPLES`], counted from the log's first sample): the streamed observation
/// then merges the very chunk factors, in the same order, as the log in memory.
struct Batches {
    joints: usize,
    rows: usize,
    /// Row-major q, dq, ddq, tau.
    values: [Vec<f64>; 4],
}

/// Samples per batch: whole chunks.
const BATCH_SAMPLES: usize = 16 * CHUNK_SAMPLES;

impl Batches {
    fn new(joints: usize) -> Batches {
        Batches {
            joints,
            rows: 0,
            values: Default::default(),
        }
    }

    fn push(&mut self, p: &Processed) {
        for k in 0..p.len() {
            for (out, m) in self.values.iter_mut().zip([&p.q, &p.dq, &p.ddq, &p.tau]) {
                out.extend(m.row(k).iter());
            }
        }
        self.rows += p.len();
    }

    /// The whole batches gathered (every sample with `all`: the log's end), removed.
    fn take(&mut self, all: bool) -> Option<[DMatrix<f64>; 4]> {
        let rows = if all {
            self.rows
        } else {
            self.rows / BATCH_SAMPLES * BATCH_SAMPLES
        };
        if rows == 0 {
            return None;
        }
        let n = self.joints;
        self.rows -= rows;
        Some(self.values.each_mut().map(|v| {
            let m = DMatrix::from_row_slice(rows, n, &v[..rows * n]);
            v.drain(..rows * n);
            m
        }))
    }
}

fn samples(p: &Processed) -> Samples<'_> {
    Samples {
        q: &p.q,
        dq: &p.dq,
        ddq: &p.ddq,
        tau: &p.tau,
    }
}

/// [`super::fit_logs`] of logs read from their files block by block (see the module
/// docs for the passes): each log processed on its own, the observations merged, the
/// same result to the last bit (the inputs hashed from the files). `block_samples` is
/// the block size ([`BLOCK_SAMPLES`], [`crate::FitRequest::block_samples`]); `progress`
/// hears a stage per pass, counted in the log's samples.
pub(crate) fn fit_stream_logs(
    model: &Model,
    train: &[&LogReader],
    test: &[&LogReader],
    settings: &FitSettings,
    block_samples: usize,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    if train.is_empty() {
        return Err(no_training_log());
    }
    no_delay_search(settings, "a streamed fit")?;
    // The model options of the settings (Stribeck terms), as the in-memory fit.
    let model_cow = settings.model(model)?;
    let model: &Model = &model_cow;
    let train_logs = sources(train, model, block_samples);
    let test_logs = sources(test, model, block_samples);
    let train_timing = timings(&train_logs, progress)?;
    let test_timing = timings(&test_logs, progress)?;
    // Setting and length errors before the long passes, as the whole-log fit reports
    // them before fitting.
    for (log, timing) in train_logs
        .iter()
        .zip(&train_timing)
        .chain(test_logs.iter().zip(&test_timing))
    {
        log.processor(settings, timing)?;
    }
    let observed = observe(&train_logs, &train_timing, settings, progress)?;
    let train_pass = |params: &[f64]| {
        train_logs
            .iter()
            .zip(&train_timing)
            .map(|(log, timing)| {
                log.metrics(
                    settings,
                    timing,
                    params,
                    None,
                    "metrics (training)",
                    progress,
                )
            })
            .collect()
    };
    let test_pass = |params: &[f64]| {
        test_logs
            .iter()
            .zip(&test_timing)
            .map(|(log, timing)| {
                let sums = log.metrics(
                    settings,
                    timing,
                    params,
                    settings.test_window,
                    "metrics (test)",
                    progress,
                )?;
                let mut info = InputInfo::from_file("test", log.reader.path())?;
                info.source.clone_from(&timing.1);
                Ok((info, sums))
            })
            .collect()
    };
    let passes = MetricPasses {
        train: Some(&train_pass),
        test: &test_pass,
    };
    fit_observed(model, &observed, settings, passes, progress)
}

/// The training logs of a streamed fit reduced, without the estimator: what the
/// streamed fit builds before it, for an observation state
/// ([`crate::state::ObservationState`]). `model` is the model of the settings
/// ([`FitSettings::model`]).
pub fn observe_stream_logs(
    model: &Model,
    train: &[&LogReader],
    settings: &FitSettings,
    block_samples: usize,
    progress: &dyn Progress,
) -> Result<Observed, IdentError> {
    if train.is_empty() {
        return Err(no_training_log());
    }
    let logs = sources(train, model, block_samples);
    let timing = timings(&logs, progress)?;
    for (log, timing) in logs.iter().zip(&timing) {
        log.processor(settings, timing)?;
    }
    observe(&logs, &timing, settings, progress)
}

fn sources<'a>(logs: &[&'a LogReader], model: &'a Model, block: usize) -> Vec<Source<'a>> {
    logs.iter()
        .map(|&reader| Source {
            reader,
            model,
            block,
        })
        .collect()
}

fn timings(
    logs: &[Source],
    progress: &dyn Progress,
) -> Result<Vec<(LogTiming, String)>, IdentError> {
    logs.iter().map(|l| l.timing(progress)).collect()
}

/// The observation pass over every training log: each log's factors (in batches of
/// whole chunks, as in memory) and torque range.
fn observe(
    logs: &[Source],
    timings: &[(LogTiming, String)],
    settings: &FitSettings,
    progress: &dyn Progress,
) -> Result<Observed, IdentError> {
    let mut observed: Option<Observed> = None;
    for (log, timing) in logs.iter().zip(timings) {
        let model = log.model;
        let n = model.dof();
        let add = |reduction: &mut PerCoordinate, [q, dq, ddq, tau]: [DMatrix<f64>; 4]| {
            let s = Samples {
                q: &q,
                dq: &dq,
                ddq: &ddq,
                tau: &tau,
            };
            reduction.add(model, s, &Silent);
        };
        let mut range = TorqueRange::new(n);
        let mut reduction = PerCoordinate::new(model);
        let mut batches = Batches::new(n);
        log.processed(
            settings,
            timing,
            "assembling the observation",
            progress,
            |block| {
                range.add(&block.tau);
                batches.push(block);
                if let Some(batch) = batches.take(false) {
                    add(&mut reduction, batch);
                }
                ControlFlow::Continue(())
            },
        )?;
        if let Some(batch) = batches.take(true) {
            add(&mut reduction, batch);
        }
        let mut info = InputInfo::from_file("train", log.reader.path())?;
        info.source.clone_from(&timing.1);
        let parts = reduction.finish();
        Observed::push(&mut observed, ObservedLog { info, parts }, range);
    }
    observed.ok_or_else(no_training_log)
}
