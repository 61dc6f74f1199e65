//! The fit of logs in memory ([`fit_logs`], run by [`crate::FitRequest`]): each log prepared on its own, reduced,
//! and fitted through the shared end ([`super::observed::fit_observed`]).

use dvrk_model::Model;

use super::delay;
use super::metrics::MetricSums;
use super::metrics::TorqueRange;
use super::observed::{fit_observed, no_training_log, MetricPasses, Observed, ObservedLog};
use super::prepare::{prepare, LogData, Prepared};
use crate::error::IdentError;
use crate::observation::Observation;
use crate::progress::Progress;
use crate::result::{FitResult, InputInfo};
use crate::settings::FitSettings;
use crate::signal::Processing;

/// The fit of logs in memory (the driver [`crate::FitRequest::run`] picks for logs it
/// does not stream): each log is processed on its own (filters, trimming and differentiation never cross a
/// log boundary), then the observations of the training logs are merged, the WLS
/// weights come from all their torques, and the metrics are summed over the logs. The
/// test metrics cover the first `settings.test_window` samples of each test log. The
/// result's `inputs` lists every log (training first) with its hash and its own
/// metrics; `metrics` holds those of all the training (test) logs together.
///
/// [`super::stream::fit_stream_logs`] reads the same logs from disk with the same result.
pub(crate) fn fit_logs(
    model: &Model,
    train: &[LogData<'_>],
    test: &[LogData<'_>],
    settings: &FitSettings,
    progress: &dyn Progress,
) -> Result<FitResult, IdentError> {
    if train.is_empty() {
        return Err(no_training_log());
    }
    let model_cow = settings.model(model)?;
    let model: &Model = &model_cow;
    let mut settings = std::borrow::Cow::Borrowed(settings);
    let delays = match settings.delay_search_s {
        Some(max_s) => {
            progress.stage("estimating the measurement delays", None);
            let found = delay::estimate_delays(model, train, &settings, max_s)?;
            progress.finish();
            settings.to_mut().processing.delay_s = found.delay_s.clone();
            Some(found)
        }
        None => None,
    };
    let settings: &FitSettings = &settings;
    progress.stage("processing", None);
    let data = prepare_logs(model, train, &settings.processing)?;
    let test_data = prepare_logs(model, test, &settings.processing)?;
    progress.finish();
    let observed = observe_prepared(model, train, &data, progress)?;
    let train_pass = |params: &[f64]| Ok(MetricSums::of_logs(model, params, &data));
    let test_pass =
        |params: &[f64]| test_inputs(model, test, &test_data, params, settings.test_window);
    let passes = MetricPasses {
        train: Some(&train_pass),
        test: &test_pass,
    };
    let mut result = fit_observed(model, &observed, settings, passes, progress)?;
    result.delay = delays;
    result.check_finite()?;
    Ok(result)
}

/// Each log prepared ([`prepare`]) on its own.
pub(crate) fn prepare_logs(
    model: &Model,
    logs: &[LogData<'_>],
    processing: &Processing,
) -> Result<Vec<Prepared>, IdentError> {
    logs.iter()
        .map(|l| prepare(model, l.samples, processing))
        .collect()
}

/// The test logs' provenance and the metrics of `params` on them (the first `window`
/// samples of each).
pub(crate) fn test_inputs(
    model: &Model,
    logs: &[LogData<'_>],
    prepared: &[Prepared],
    params: &[f64],
    window: Option<usize>,
) -> Result<Vec<(InputInfo, MetricSums)>, IdentError> {
    logs.iter()
        .zip(prepared)
        .map(|(log, p)| {
            let sums = MetricSums::of_samples(model, params, p.samples(), window);
            Ok((log_info("test", log, &p.source)?, sums))
        })
        .collect()
}

/// The provenance of a log: its file hashed, or its samples when it has none.
fn log_info(role: &str, log: &LogData<'_>, source: &str) -> Result<InputInfo, IdentError> {
    let mut info = match log.file {
        Some(file) => InputInfo::from_file(role, file)?,
        None => InputInfo::from_samples(role, log.samples),
    };
    info.source = source.to_string();
    Ok(info)
}

/// Logs prepared in memory ([`prepare`]), reduced one after the other.
pub(crate) fn observe_prepared(
    model: &Model,
    logs: &[LogData<'_>],
    prepared: &[Prepared],
    progress: &dyn Progress,
) -> Result<Observed, IdentError> {
    let total: usize = prepared.iter().map(Prepared::len).sum();
    progress.stage("assembling the observation", Some(total as u64));
    let mut observed: Option<Observed> = None;
    for (log, d) in logs.iter().zip(prepared) {
        let mut range = TorqueRange::new(model.dof());
        range.add(&d.tau);
        let parts = Observation::assemble_per_coordinate(model, d.samples(), progress);
        let info = log_info("train", log, &d.source)?;
        Observed::push(&mut observed, ObservedLog { info, parts }, range);
    }
    progress.finish();
    observed.ok_or_else(no_training_log)
}
