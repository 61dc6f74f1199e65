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
            name: "delay".into(),
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

/// The fit of reduced training logs (the shared end of [`fit_logs`],
/// [`stream::fit_stream_logs`] and the fit of observation states): the weights, the
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
    let estimated =
        estimate(model, &base, &observed.parts, weights, &how, &run).map_err(|e| match e {
            EstimateError::NotExcited(e) => not_excited(&source, e),
            EstimateError::Sdp(e) => e.into(),
        })?;
    // Training metrics from each log's factors, no second pass over the samples; a
    // pass where coupled measured joints need the cross terms the factors lack.
    let train_sums: Vec<MetricSums> = if joints.is_identity() {
        observed
            .logs
            .iter()
            .map(|log| MetricSums::from_factors(&log.parts, &estimated.params))
            .collect()
    } else {
        match passes.train {
            Some(pass) => pass(&estimated.params)?,
            None => {
                return Err(IdentError::Setting {
                    name: "joints".into(),
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
    for (log, sums) in observed.logs.iter().zip(&train_sums) {
        let mut info = log.info.clone();
        info.metrics = Some(sums.metrics(&joints)?);
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
