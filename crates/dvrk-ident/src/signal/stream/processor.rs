//! [`crate::signal::process`](fn@crate::signal::process) for a log given block by block.

use std::collections::VecDeque;

use nalgebra::DMatrix;

use super::difference::Difference;
use super::timing::LogTiming;
use super::zero_phase::{settle_margin, ZeroPhase};
use super::Resampler;
use crate::signal::advance::Advance;
use crate::signal::{AccelerationSource, Processed, Processing, SignalError};
use crate::{Coordinates, JointLog, JointLogError};

/// Relative size of the backward passes' start error within a block (see
/// `settle_margin`): far below the 1e-9 agreement promised with the whole-log
/// processing.
pub const SETTLE_TOLERANCE: f64 = 1e-12;

/// A signal stage: a zero-phase filter, or the identity.
#[derive(Clone, Debug)]
enum Stage {
    Pass,
    Filter(ZeroPhase),
}

impl Stage {
    fn push(&mut self, row: &[f64], out: &mut Vec<f64>) {
        match self {
            Stage::Pass => out.extend_from_slice(row),
            Stage::Filter(z) => z.push(row, out),
        }
    }

    fn finish(&mut self, out: &mut Vec<f64>) -> Result<(), SignalError> {
        match self {
            Stage::Pass => Ok(()),
            Stage::Filter(z) => z.finish(out),
        }
    }
}

/// Processes a log fed in blocks (in order) into the samples [`crate::signal::process`](fn@crate::signal::process)
/// gives for the whole log, block by block, in memory independent of the log's length.
///
/// Every step reproduces the whole-log one: resampling and differences exactly, the
/// zero-phase filters to [`SETTLE_TOLERANCE`] relative inside the log and exactly at
/// its ends (the same odd padding and initial conditions; see `zero_phase`); the
/// trimming, the decimation phase and the speed threshold are decided on the sample's
/// index in the whole log. The log's timing comes from a first pass
/// ([`super::TimingSurvey`]): the sampling rate (inverse median step), the length that
/// the trimming and the filters' padding are checked against. Errors are those of
/// [`crate::signal::process`](fn@crate::signal::process) on the whole log, in the same order.
#[derive(Clone, Debug)]
pub struct BlockProcessor {
    settings: Processing,
    dof: usize,
    source: String,
    joint_names: Vec<String>,
    coordinates: Coordinates,
    dq_measured: bool,
    rate_hz: f64,
    /// Median step for the uniformity check (not when resampling).
    median_step_s: Option<f64>,
    resampler: Option<Resampler>,
    q_stage: Stage,
    dq_stage: Stage,
    /// The torques' measurement delays, before `tau_stage`.
    advance: Option<Advance>,
    tau_stage: Stage,
    acc_stage: Stage,
    /// Differentiates the filtered positions when the log has no velocities.
    velocity: Option<Difference>,
    acceleration: Difference,
    /// Accelerations from the raw measured velocity (else from the processed one).
    acc_from_raw: bool,
    /// Processed rows waiting for the other signals (row-major).
    time_out: VecDeque<f64>,
    q_out: VecDeque<f64>,
    dq_out: VecDeque<f64>,
    ddq_out: VecDeque<f64>,
    tau_out: VecDeque<f64>,
    /// The last `trim` assembled rows: `(index, time, q|dq|ddq|tau)`.
    held: VecDeque<(usize, f64, Vec<f64>)>,
    assembled: usize,
    kept: usize,
    /// Input samples seen and the previous input time.
    inputs: usize,
    previous_time: Option<f64>,
    scratch: [Vec<f64>; 4],
}

impl BlockProcessor {
    /// A processor for a log whose blocks have `joint_names` (in `coordinates`),
    /// velocities if `dq_measured`, and the timing `timing` (from a first pass).
    pub fn new(
        settings: &Processing,
        joint_names: &[String],
        coordinates: Coordinates,
        dq_measured: bool,
        source: &str,
        timing: &LogTiming,
    ) -> Result<BlockProcessor, SignalError> {
        let dof = joint_names.len();
        settings.check(dof)?;
        let (resampler, rate_hz, samples, median_step_s) = match settings.resample_hz {
            Some(rate) => {
                let r = Resampler::new(3 * dof, rate)?;
                if timing.samples < 2 {
                    return Err(SignalError::TooFewSamples {
                        len: timing.samples,
                        needed: 2,
                    });
                }
                let n = r.grid_len(timing.first_s, timing.last_s);
                (Some(r), rate, n, None)
            }
            None => {
                let median = timing
                    .median_step_s
                    .ok_or_else(|| JointLogError::TooFewSamples {
                        source_name: source.to_string(),
                        samples: timing.samples,
                    })?;
                (None, 1.0 / median, timing.samples, Some(median))
            }
        };
        let mut p = BlockProcessor {
            settings: settings.clone(),
            dof,
            source: source.to_string(),
            joint_names: joint_names.to_vec(),
            coordinates,
            dq_measured,
            rate_hz,
            median_step_s,
            resampler,
            q_stage: Stage::Pass,
            dq_stage: Stage::Pass,
            advance: Advance::new(&settings.delay_s, rate_hz),
            tau_stage: Stage::Pass,
            acc_stage: Stage::Pass,
            velocity: None,
            acceleration: Difference::new(dof, 1.0 / rate_hz, settings.acceleration_stencil),
            acc_from_raw: settings.acceleration_from == AccelerationSource::RawVelocity
                && dq_measured,
            time_out: VecDeque::new(),
            q_out: VecDeque::new(),
            dq_out: VecDeque::new(),
            ddq_out: VecDeque::new(),
            tau_out: VecDeque::new(),
            held: VecDeque::new(),
            assembled: 0,
            kept: 0,
            inputs: 0,
            previous_time: None,
            scratch: Default::default(),
        };
        // A log with a gap fails at the gap, before these whole-log length checks.
        let uniform = median_step_s.is_none() || timing.is_uniform(settings.uniform_tolerance);
        if uniform {
            if 2 * settings.trim >= samples {
                return Err(SignalError::TrimTooLong {
                    trim: settings.trim,
                    len: samples,
                });
            }
            p.build_stages(samples)?;
        } else {
            p.build_stages(usize::MAX)?;
        }
        Ok(p)
    }

    fn in_column(&self, signal: &'static str, j: usize, e: SignalError) -> SignalError {
        SignalError::InColumn {
            source_name: self.source.clone(),
            signal,
            joint: self.joint_names[j].clone(),
            inner: Box::new(e),
        }
    }

    /// Designs the filters and differences, checking that `samples` suffice in the
    /// order the whole-log processing meets the columns.
    fn build_stages(&mut self, samples: usize) -> Result<(), SignalError> {
        let step_s = 1.0 / self.rate_hz;
        let diff_check = |p: &Self, signal| {
            if samples < 3 {
                Err(p.in_column(
                    signal,
                    0,
                    SignalError::TooFewSamples {
                        len: samples,
                        needed: 3,
                    },
                ))
            } else {
                Ok(())
            }
        };
        let filter = match self.settings.filter.clone() {
            Some(f) => {
                let mut steppers = Vec::with_capacity(self.dof);
                let mut margin = 0;
                for j in 0..self.dof {
                    let fc = f.cutoff_hz.for_joint(j).unwrap_or(f64::NAN);
                    let (stepper, sections) = f
                        .stepper(fc, self.rate_hz)
                        .map_err(|e| self.in_column("position", j, e))?;
                    margin = margin.max(settle_margin(&sections, SETTLE_TOLERANCE));
                    steppers.push(stepper);
                    if j == 0 {
                        let padlen = f.padlen.unwrap_or_else(|| steppers[0].default_padlen());
                        if samples <= padlen {
                            let e = SignalError::TooShort {
                                len: samples,
                                padlen,
                            };
                            return Err(self.in_column("position", 0, e));
                        }
                    }
                }
                Some(ZeroPhase::new(steppers, f.padlen, margin)?)
            }
            None => None,
        };
        let stage = || filter.clone().map_or(Stage::Pass, Stage::Filter);
        self.q_stage = stage();
        if self.settings.filter_torque {
            self.tau_stage = stage();
        }
        if self.dq_measured {
            self.dq_stage = stage();
        } else {
            diff_check(self, "velocity")?;
            self.velocity = Some(Difference::new(
                self.dof,
                step_s,
                self.settings.velocity_stencil,
            ));
        }
        diff_check(self, "acceleration")?;
        self.acc_stage = stage();
        Ok(())
    }

    /// Processes the next block of the log; the samples that are done (possibly none).
    pub fn push(&mut self, block: &JointLog) -> Result<Processed, SignalError> {
        let n = self.dof;
        if block.dof() != n || block.dq.is_some() != self.dq_measured {
            return Err(SignalError::InvalidSetting {
                name: "block",
                reason: format!(
                    "{}: a block with {} joints{} in a log of {n} joints{}",
                    self.source,
                    block.dof(),
                    if block.dq.is_some() {
                        " and velocities"
                    } else {
                        ""
                    },
                    if self.dq_measured {
                        " with velocities"
                    } else {
                        ""
                    }
                ),
            });
        }
        let mut out = Output::default();
        let mut row = vec![0.0; 3 * n];
        for k in 0..block.len() {
            block.stacked_row(k, &mut row);
            self.input(block.time[k], &row, &mut out)?;
        }
        Ok(self.collect(out))
    }

    /// The end of the log: the last samples.
    pub fn finish(mut self) -> Result<Processed, SignalError> {
        let mut out = Output::default();
        let mut scratch = std::mem::take(&mut self.scratch);
        if let Some(mut r) = self.resampler.take() {
            let (mut times, mut rows) = (Vec::new(), Vec::new());
            r.finish(&mut times, &mut rows)?;
            for (k, &t) in times.iter().enumerate() {
                let row = rows[k * 3 * self.dof..(k + 1) * 3 * self.dof].to_vec();
                self.sample(t, &row, &mut out)?;
            }
        }
        let [a, b, c, d] = &mut scratch;
        a.clear();
        self.q_stage.finish(a)?;
        self.after_q(a, b, c, d);
        if let Some(mut v) = self.velocity.take() {
            a.clear();
            v.finish(a)?;
            self.after_dq(a, b, c);
        }
        a.clear();
        self.dq_stage.finish(a)?;
        self.after_dq(a, b, c);
        a.clear();
        self.acceleration.finish(a)?;
        self.after_acc(a, b);
        a.clear();
        self.acc_stage.finish(a)?;
        self.ddq_out.extend(a.iter());
        if let Some(mut advance) = self.advance.take() {
            a.clear();
            advance.finish(a);
            b.clear();
            for r in a.chunks_exact(self.dof) {
                self.tau_stage.push(r, b);
            }
            self.tau_out.extend(b.iter());
            b.clear();
        }
        a.clear();
        self.tau_stage.finish(a)?;
        self.tau_out.extend(a.iter());
        self.assemble(&mut out);
        self.held.clear();
        if let Some(min_speed) = self.settings.min_speed {
            if self.kept == 0 {
                return Err(SignalError::NoSamplesLeft {
                    source_name: self.source.clone(),
                    min_speed,
                });
            }
        }
        Ok(self.collect(out))
    }

    /// One input sample (before resampling).
    fn input(&mut self, time: f64, row: &[f64], out: &mut Output) -> Result<(), SignalError> {
        if let Some(median) = self.median_step_s {
            if let Some(p) = self.previous_time {
                let step = time - p;
                let tolerance = self.settings.uniform_tolerance;
                if (step - median).abs() > tolerance * median {
                    return Err(JointLogError::NonUniform {
                        source_name: self.source.clone(),
                        row: self.inputs,
                        step_s: step,
                        median_step_s: median,
                        tolerance,
                    }
                    .into());
                }
            }
        }
        self.previous_time = Some(time);
        self.inputs += 1;
        match self.resampler.take() {
            Some(mut r) => {
                let (mut times, mut rows) = (Vec::new(), Vec::new());
                let pushed = r.push(time, row, &mut times, &mut rows);
                self.resampler = Some(r);
                pushed?;
                let w = 3 * self.dof;
                for (k, &t) in times.iter().enumerate() {
                    self.sample(t, &rows[k * w..(k + 1) * w], out)?;
                }
                Ok(())
            }
            None => self.sample(time, row, out),
        }
    }

    /// One sample on the processing clock: `q | dq | tau`.
    fn sample(&mut self, time: f64, row: &[f64], out: &mut Output) -> Result<(), SignalError> {
        let n = self.dof;
        let (q, dq, tau) = (&row[..n], &row[n..2 * n], &row[2 * n..]);
        let [mut a, mut b, mut c, mut d] = std::mem::take(&mut self.scratch);
        self.time_out.push_back(time);
        a.clear();
        self.q_stage.push(q, &mut a);
        self.after_q(&a, &mut b, &mut c, &mut d);
        if self.dq_measured {
            a.clear();
            self.dq_stage.push(dq, &mut a);
            self.after_dq(&a, &mut b, &mut c);
            if self.acc_from_raw {
                a.clear();
                self.acceleration.push(dq, &mut a);
                self.after_acc(&a, &mut b);
            }
        }
        a.clear();
        match &mut self.advance {
            Some(advance) => {
                b.clear();
                advance.push(tau, &mut b);
                for r in b.chunks_exact(n) {
                    self.tau_stage.push(r, &mut a);
                }
            }
            None => self.tau_stage.push(tau, &mut a),
        }
        self.tau_out.extend(a.iter());
        self.scratch = [a, b, c, d];
        self.assemble(out);
        Ok(())
    }

    /// Processed positions: kept, and differentiated when the log has no velocities.
    fn after_q(&mut self, rows: &[f64], b: &mut Vec<f64>, c: &mut Vec<f64>, d: &mut Vec<f64>) {
        self.q_out.extend(rows.iter());
        if let Some(v) = &mut self.velocity {
            b.clear();
            for r in rows.chunks_exact(self.dof) {
                v.push(r, b);
            }
            self.after_dq(b, c, d);
        }
    }

    /// Processed velocities: kept, and differentiated unless accelerations come from
    /// the raw measurement.
    fn after_dq(&mut self, rows: &[f64], c: &mut Vec<f64>, d: &mut Vec<f64>) {
        self.dq_out.extend(rows.iter());
        if !self.acc_from_raw {
            c.clear();
            for r in rows.chunks_exact(self.dof) {
                self.acceleration.push(r, c);
            }
            self.after_acc(c, d);
        }
    }

    /// Raw accelerations: filtered.
    fn after_acc(&mut self, rows: &[f64], d: &mut Vec<f64>) {
        d.clear();
        for r in rows.chunks_exact(self.dof) {
            self.acc_stage.push(r, d);
        }
        self.ddq_out.extend(d.iter());
    }

    /// Rows whose four signals are done: trimmed, decimated and thinned into `out`.
    fn assemble(&mut self, out: &mut Output) {
        let n = self.dof;
        let ready = [&self.q_out, &self.dq_out, &self.ddq_out, &self.tau_out]
            .iter()
            .map(|q| q.len() / n)
            .min()
            .unwrap_or(0)
            .min(self.time_out.len());
        let trim = self.settings.trim;
        for _ in 0..ready {
            let time = self.time_out.pop_front().expect("ready");
            let mut values = Vec::with_capacity(4 * n);
            for q in [
                &mut self.q_out,
                &mut self.dq_out,
                &mut self.ddq_out,
                &mut self.tau_out,
            ] {
                values.extend(q.drain(..n));
            }
            self.held.push_back((self.assembled, time, values));
            self.assembled += 1;
            if self.held.len() > trim {
                let (i, t, v) = self.held.pop_front().expect("held");
                let phase = i >= trim && (i - trim) % self.settings.decimate == 0;
                let moving = self
                    .settings
                    .min_speed
                    .is_none_or(|s| v[n..2 * n].iter().all(|x| x.abs() >= s));
                if phase && moving {
                    out.time.push(t);
                    out.values.extend(v);
                    self.kept += 1;
                }
            }
        }
    }

    fn collect(&self, out: Output) -> Processed {
        let n = self.dof;
        let rows = out.time.len();
        let all = DMatrix::from_row_slice(rows, 4 * n, &out.values);
        Processed {
            time: out.time,
            q: all.columns(0, n).into_owned(),
            dq: all.columns(n, n).into_owned(),
            ddq: all.columns(2 * n, n).into_owned(),
            tau: all.columns(3 * n, n).into_owned(),
            joint_names: self.joint_names.clone(),
            coordinates: self.coordinates,
            rate_hz: self.rate_hz,
            dq_measured: self.dq_measured,
            source: self.source.clone(),
        }
    }
}

/// Kept rows of one call: times and `q | dq | ddq | tau` rows.
#[derive(Default)]
struct Output {
    time: Vec<f64>,
    values: Vec<f64>,
}
