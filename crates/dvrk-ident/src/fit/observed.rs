//! The training logs reduced to what a fit needs of them ([`Observed`]: each log's
//! factors, all merged, the torque range), and the fit of that reduction
//! ([`fit_observed`]): the one end shared by the in-memory, streamed and
//! observation-state drivers, so that all three give the same document.

use dvrk_model::Model;

use super::document::build_result;
use super::joints::JointMap;
use super::metrics::{MetricSums, TorqueRange};
use crate::error::IdentError;
use crate::estimate::sdp::{PriorMetric, SdpOptions};
use crate::estimate::{estimate, EstimateError, Estimator, Run};
use crate::observation::Observation;
use crate::progress::Progress;
use crate::result::{FitResult, InputInfo, Metrics};
use crate::settings::{FitSettings, Method, Prior};

/// Refuses the delay search where the samples are not in memory (a streamed fit, a fit
/// of observation states): it needs every log processed at many shifts.
pub(crate) fn no_delay_search(settings: &FitSettings, what: &str) -> Result<(), IdentError> {
    match settings.delay_search_s {
        Some(_) => Err(IdentError::Setting {
            name: crate::options::Setting::Delay.into(),
            message: format!(
                "the delay search (delay auto) needs the logs in memory, which {what} does \
                 not hold: estimate the delays on a shorter log and give them fixed"
            ),
        }),
        None => Ok(()),
    }
}

/// One training log reduced: its provenance (role `train`, no metrics yet) and its
/// unweighted per-coordinate factors ([`Observation::assemble_per_coordinate`]), from
/// which its own training metrics come.
#[derive(Clone, Debug)]
pub struct ObservedLog {
    /// The log's provenance (role, path, hash) and, once fitted, its own metrics.
    pub info: InputInfo,
    /// The log's unweighted factors, one per model coordinate.
    pub parts: Vec<Observation>,
}

/// The training logs reduced to everything a fit needs of them: each log's factors,
/// all of them merged, and the running torque range of the WLS weights. What the fit
/// of logs in memory and the streamed fit build before the estimator, and what an
/// observation state file ([`crate::state`]) holds, so that a fit of states equals the
/// fit of their logs.
#[derive(Clone, Debug)]
pub struct Observed {
    /// Each training log's own reduction, in the order given.
    pub logs: Vec<ObservedLog>,
    /// The logs' factors merged, one per coordinate.
    pub parts: Vec<Observation>,
    /// The torque range of all the logs, per coordinate: the WLS and SDP weights.
    pub range: TorqueRange,
}

impl Observed {
    /// One more log after those of `observed` (the first makes it).
    pub(crate) fn push(observed: &mut Option<Observed>, log: ObservedLog, range: TorqueRange) {
        match observed {
            None => {
                *observed = Some(Observed {
                    parts: log.parts.clone(),
                    logs: vec![log],
                    range,
                })
            }
            Some(o) => {
                merge_parts(&mut o.parts, &log.parts);
                o.range.merge(&range);
                o.logs.push(log);
            }
        }
    }

    /// The logs of `other` after these: factors merged (exact up to rounding, in any
    /// order), ranges joined, logs listed in order.
    pub fn merge(&mut self, other: &Observed) {
        merge_parts(&mut self.parts, &other.parts);
        self.range.merge(&other.range);
        self.logs.extend(other.logs.iter().cloned());
    }

    /// Processed samples of all the logs.
    pub fn samples(&self) -> usize {
        self.parts.first().map_or(0, Observation::rows)
    }
}

/// The fit of reduced training logs (the shared end of [`fit_logs`](super::memory::fit_logs),
/// [`stream::fit_stream_logs`](super::stream::fit_stream_logs) and the fit of observation states): the weights, the
/// estimator, the training metrics from each log's factors (no pass over the samples),
/// the test logs' metrics from `test` (given the parameters), the document. `model` is
/// the model of the settings ([`FitSettings::model`]).
pub(crate) fn fit_observed(
    model: &Model,
    observed: &Observed,
    settings: &FitSettings,
    passes: MetricPasses<'_>,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    settings.check_estimator()?;
    let joints = JointMap::new(model, settings.joints)?;
    let base = model.base_parameters()?;
    let n = model.dof();
    let started = std::time::Instant::now();
    let weights = match settings.method {
        Method::Ols | Method::Irls => vec![1.0; n],
        Method::Wls | Method::Sdp => observed.range.weights(),
    };
    let source = joined_sources(observed.logs.iter().map(|l| l.info.source.as_str()));
    let run = Run { started, progress };
    let prior = settings.prior.as_ref();
    let sdp = SdpOptions {
        regularization: settings.sdp_regularization,
        prior: Prior::values_for(prior, model)?,
        prior_weight: prior.map_or(0.0, |p| p.weight),
        prior_metric: prior.map_or(PriorMetric::default(), |p| p.metric),
        ellipsoids: settings.ellipsoids,
        ..SdpOptions::default()
    };
    let how = Estimator {
        method: settings.method,
        irls_iterations: settings.irls_iterations,
        sdp: &sdp,
    };
    // With per-log offsets, every log after the first has its coordinates' offsets
    // projected out of its factors; the estimator and the training errors see those.
    let offsets = match settings.log_offsets {
        true => Some(LogOffsets::new(model, observed, &joints)?),
        false => None,
    };
    let fitted: &Observed = offsets.as_ref().map_or(observed, |o| &o.observed);
    let estimated =
        estimate(model, &base, &fitted.parts, weights, &how, &run).map_err(|e| match e {
            EstimateError::NotExcited(e) => not_excited(&source, e),
            EstimateError::Sdp(e) => e.into(),
        })?;
    // Training metrics from each log's factors, no second pass over the samples; a
    // pass where coupled measured joints need the cross terms the factors lack.
    let train_sums: Vec<MetricSums> = if joints.is_identity() {
        observed
            .logs
            .iter()
            .zip(&fitted.logs)
            .map(|(log, f)| {
                MetricSums::from_fitted_factors(&log.parts, &f.parts, &estimated.params)
            })
            .collect()
    } else {
        match passes.train {
            Some(pass) => pass(&estimated.params)?,
            None => {
                return Err(IdentError::Setting {
                    name: crate::options::Setting::Joints.into(),
                    message: format!(
                        "the training errors in {}'s measured joints need the logs' \
                         samples, which observation states do not hold: fit the states in \
                         model coordinates, then validate on the logs in measured joints",
                        model.name
                    ),
                })
            }
        }
    };
    let tested = (passes.test)(&estimated.params)?;
    let test_sums: Vec<MetricSums> = tested.iter().map(|(_, s)| s.clone()).collect();
    let mut inputs = Vec::with_capacity(observed.logs.len() + tested.len());
    for (k, (log, sums)) in observed.logs.iter().zip(&train_sums).enumerate() {
        let mut info = log.info.clone();
        info.metrics = Some(sums.metrics(&joints)?);
        if let Some(o) = &offsets {
            info.offset = Some(o.offset(k, &log.parts, &estimated.params));
        }
        inputs.push(info);
    }
    for (mut info, sums) in tested {
        info.metrics = Some(sums.metrics(&joints)?);
        inputs.push(info);
    }
    let test_metrics = match test_sums.is_empty() {
        true => None,
        false => Some(summed(model, &test_sums).metrics(&joints)?),
    };
    let mut result = build_result(
        model,
        &base,
        settings,
        estimated,
        Metrics {
            train: summed(model, &train_sums).metrics(&joints)?,
            test: test_metrics,
        },
    )?;
    result.inputs = inputs;
    result.check_finite()?;
    Ok(result)
}

/// The per-log torque offsets of a fit (`FitSettings::log_offsets`): each coordinate's
/// offset column, and the training logs with the offsets of every log after the first
/// projected out of their factors ([`Observation::project_out`]), which is the fit with
/// one free offset per coordinate and log, those eliminated exactly.
struct LogOffsets {
    /// Per coordinate, an `Fo` column and its constant entry `a` in that coordinate's
    /// rows (`None` for a coordinate without an offset parameter: it gets no per-log
    /// offset).
    columns: Vec<Option<(usize, f64)>>,
    /// The training logs, offsets projected out after the first, merged.
    observed: Observed,
}

impl LogOffsets {
    fn new(model: &Model, observed: &Observed, joints: &JointMap) -> Result<Self, IdentError> {
        if !joints.is_identity() {
            return Err(IdentError::Setting {
                name: crate::options::Setting::LogOffsets.into(),
                message: format!(
                    "the per-log offsets are in model coordinates, and the training errors in                      {}'s measured joints would leave them out: fit in model coordinates                      (joints model)",
                    model.name
                ),
            });
        }
        let n = model.dof();
        let mut ws = dvrk_model::Workspace::new(model);
        let zero = vec![0.0; n];
        // The offset columns are constant: any sample shows their entries.
        let y = model.regressor(&mut ws, &zero, &zero, &zero);
        let columns: Vec<Option<(usize, f64)>> = (0..n)
            .map(|c| {
                model
                    .params
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.kind == dvrk_model::ParamKind::Offset)
                    .map(|(k, _)| (k, y[(c, k)]))
                    .find(|(_, a)| *a != 0.0)
            })
            .collect();
        let mut logs = observed.logs.clone();
        for log in logs.iter_mut().skip(1) {
            for (part, col) in log.parts.iter_mut().zip(&columns) {
                if let Some((k, _)) = col {
                    *part = part.project_out(*k);
                }
            }
        }
        let mut parts = logs[0].parts.clone();
        for log in &logs[1..] {
            merge_parts(&mut parts, &log.parts);
        }
        Ok(LogOffsets {
            columns,
            observed: Observed {
                logs,
                parts,
                range: observed.range.clone(),
            },
        })
    }

    /// Log `k`'s own offset over the model's per coordinate, N·m or N (zero for the
    /// first log, whose offsets are the model's): the mean residual of `params` on the
    /// log's rows, `−(R·e_o)ᵀ·R·[π; −1] / (a·rows)` from its factors `parts` (as
    /// measured) since `A·e_o = a·1`.
    fn offset(&self, k: usize, parts: &[Observation], params: &[f64]) -> Vec<f64> {
        let mut x = params.to_vec();
        x.push(-1.0);
        let x = nalgebra::DVector::from_vec(x);
        parts
            .iter()
            .zip(&self.columns)
            .map(|(o, col)| match col {
                Some((c, a)) if k > 0 && o.rows() > 0 => {
                    let rx = o.r() * &x;
                    -o.r().column(*c).dot(&rx) / (a * o.rows() as f64)
                }
                _ => 0.0,
            })
            .collect()
    }
}

/// The passes over the samples a fit's metrics may need, given the parameters: the
/// test logs' sums (with their provenance) always, the training logs' sums (one per
/// log, in order) only for coupled measured joints ([`FitSettings::joints`]); `None`
/// where the samples are not at hand (observation states).
pub(crate) struct MetricPasses<'a> {
    pub train: Option<TrainPass<'a>>,
    pub test: TestPass<'a>,
}

/// The training logs' metric sums for the given parameters.
pub(crate) type TrainPass<'a> = &'a dyn Fn(&[f64]) -> Result<Vec<MetricSums>, IdentError>;
/// The test logs' provenance and metric sums for the given parameters.
pub(crate) type TestPass<'a> =
    &'a dyn Fn(&[f64]) -> Result<Vec<(InputInfo, MetricSums)>, IdentError>;

pub(crate) fn no_training_log() -> IdentError {
    IdentError::Mismatch {
        source_name: "fit".into(),
        message: "no training log".into(),
    }
}

/// The per-coordinate observations of one more log merged into those of the logs
/// before it.
pub(crate) fn merge_parts(total: &mut [Observation], log: &[Observation]) {
    for (o, l) in total.iter_mut().zip(log) {
        o.merge(l);
    }
}

/// The sums of several logs together, in order.
pub(crate) fn summed(model: &Model, logs: &[MetricSums]) -> MetricSums {
    let mut total = MetricSums::new(model);
    for s in logs {
        total.merge(s);
    }
    total
}

/// The logs' names for messages, joined by ` + `.
pub(crate) fn joined_sources<'a>(sources: impl Iterator<Item = &'a str>) -> String {
    sources.collect::<Vec<_>>().join(" + ")
}

/// The error of data that do not determine the base parameters, naming them and the
/// logs (`source`).
fn not_excited(source: &str, e: crate::estimate::ols::NotExcited) -> IdentError {
    IdentError::RankDeficient {
        source_name: source.to_string(),
        message: format!(
            "the data do not determine the base parameters ({} rows); undetermined: {}. \
             Use a longer or more exciting trajectory.",
            e.rows,
            e.parameters.join(", ")
        ),
    }
}
