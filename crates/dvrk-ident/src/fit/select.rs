//! Choosing the friction model by held-out error (`--select`, Python `select=`): each
//! candidate is fitted on part of the training logs and scored on the rest, over folds
//! that cover every sample once, and the candidate with the lowest mean held-out error
//! is fitted on all of them. A richer friction law always lowers the training error;
//! only data it was not fitted on tell whether it describes the arm or the noise.
//!
//! **Folds.** With several training logs, leave one log out: each log is held out in
//! turn and the candidates are fitted on the others (what a model must do: hold on a
//! recording it has not seen, at another speed or load). With one log,
//! [`BLOCKED_FOLDS`] contiguous blocks in time, each held out in turn: never shuffled
//! samples, whose neighbours (a few milliseconds away, through the filter nearly the
//! same sample) would sit in the training data and score a model that memorizes noise
//! as if it generalized.
//!
//! **Processing once, and the guard band.** Every log is processed (filtered,
//! differentiated, trimmed) once, as the fit processes it; the folds cut the processed
//! samples. The zero-phase low-pass filter spreads each raw sample over its neighbours
//! in both directions, so processed training samples next to a held-out block carry
//! some of that block's raw data: the training side drops the samples within
//! [`guard_s`] of the block (the time the filter's slowest pole takes to decay to 10⁻³,
//! plus the largest torque delay and two samples of the difference stencils). Each
//! contiguous piece is reduced on its own, so the Dahl states restart at zero at a cut,
//! as they do at the start of a log.
//!
//! **Score.** Each fold's held-out sums of squared errors and torques are added over the
//! folds ([`MetricSums`]): per joint `‖τ − τ̂‖ / ‖τ‖` over every held-out sample, the
//! metric of a result's test logs, and their mean over the joints ranks the candidates
//! (ties go to the candidate listed first: list the simpler first).

use dvrk_model::Model;

use super::joints::JointMap;
use super::metrics::MetricSums;
use super::observed::{fit_observed, MetricPasses, Observed, ObservedLog};
use super::prepare::{prepare, LogData, Prepared};
use crate::error::IdentError;
use crate::observation::Observation;
use crate::progress::{Progress, Silent};
use crate::result::{CandidateScore, Folds, InputInfo, Selection};
use crate::settings::{Candidate, Candidates, FitSettings};
use crate::signal::Cutoff;

/// Folds in time when a single log is given.
pub const BLOCKED_FOLDS: usize = 4;

/// The guard band of the blocked folds, s: the time the slowest pole of the motion's
/// Butterworth low-pass (order N, effective cut-off fc; the lowest of per-joint
/// cut-offs) takes to decay to 10⁻³, `ln(1000) / (2π·fc·sin(π/2N))`, plus the largest
/// torque delay, plus two samples (`dt`, s) of the difference stencils. 0.26 s for the
/// PSM's 2019 filter (6th order, 16.965 Hz) and 200 Hz.
pub fn guard_s(settings: &FitSettings, dt: f64) -> f64 {
    let p = &settings.processing;
    let filter = p.filter.as_ref().map_or(0.0, |lp| {
        let fc = match &lp.cutoff_hz {
            Cutoff::All(v) => *v,
            Cutoff::PerJoint(v) => v.iter().copied().fold(f64::INFINITY, f64::min),
        };
        let fc = lp.convention.effective_cutoff_hz(fc);
        let n = lp.order.max(1) as f64;
        1000f64.ln() / (2.0 * std::f64::consts::PI * fc * (std::f64::consts::PI / (2.0 * n)).sin())
    });
    let delay = p.delay_s.iter().copied().fold(0.0, f64::max);
    filter + delay + 2.0 * dt
}

/// Rows `rows` of a prepared log (a fold's piece).
fn piece(p: &Prepared, rows: std::ops::Range<usize>) -> Prepared {
    let n = rows.len();
    let cut = |m: &nalgebra::DMatrix<f64>| m.rows(rows.start, n).into_owned();
    Prepared {
        source: p.source.clone(),
        time: p.time[rows.clone()].to_vec(),
        q: cut(&p.q),
        dq: cut(&p.dq),
        ddq: cut(&p.ddq),
        tau: cut(&p.tau),
    }
}

/// One fold: the training pieces and the held-out pieces.
struct Fold {
    train: Vec<Prepared>,
    test: Vec<Prepared>,
}

/// The folds of `logs` (processed): leave one log out for several, else
/// [`BLOCKED_FOLDS`] blocks with the guard band of [`guard_s`].
fn folds(logs: &[Prepared], settings: &FitSettings) -> Result<(Folds, Vec<Fold>), IdentError> {
    if logs.len() > 1 {
        let folds = (0..logs.len())
            .map(|k| Fold {
                train: logs
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != k)
                    .map(|(_, l)| l.clone())
                    .collect(),
                test: vec![logs[k].clone()],
            })
            .collect();
        return Ok((Folds::LeaveOneLogOut { logs: logs.len() }, folds));
    }
    let log = &logs[0];
    let n = log.len();
    let dt = match n {
        0 | 1 => 0.0,
        _ => (log.time[n - 1] - log.time[0]) / (n - 1) as f64,
    };
    let guard = guard_s(settings, dt);
    let k = BLOCKED_FOLDS;
    let mut out = Vec::with_capacity(k);
    for b in 0..k {
        let (lo, hi) = (b * n / k, (b + 1) * n / k);
        let (t_lo, t_hi) = (log.time[lo], log.time[hi - 1]);
        // Training rows before the block end `guard` s before its first sample; after
        // it, start `guard` s after its last.
        let before = log.time[..lo].partition_point(|&t| t < t_lo - guard);
        let after = hi + log.time[hi..].partition_point(|&t| t <= t_hi + guard);
        let train: Vec<Prepared> = [0..before, after..n]
            .into_iter()
            .filter(|r| !r.is_empty())
            .map(|r| piece(log, r))
            .collect();
        if train.is_empty() {
            return Err(IdentError::Mismatch {
                source_name: log.source.clone(),
                message: format!(
                    "too short for {k} folds in time with a guard band of {guard:.3} s \
                     ({n} processed samples): give a longer log, or several logs"
                ),
            });
        }
        out.push(Fold {
            train,
            test: vec![piece(log, lo..hi)],
        });
    }
    Ok((
        Folds::Blocked {
            folds: k,
            guard_s: guard,
        },
        out,
    ))
}

/// The held-out errors of every candidate on the training logs `train` of `robot` (the
/// model as described: each candidate adds its terms), `settings` the fit's with its
/// delays fixed; the candidate chosen.
pub(crate) fn select(
    robot: &Model,
    train: &[LogData<'_>],
    settings: &FitSettings,
    candidates: &Candidates,
    progress: &dyn Progress,
) -> Result<(Selection, Candidate), IdentError> {
    crate::fit::no_delay_search(settings, "the selection's folds").map_err(|_| {
        IdentError::Setting {
            name: crate::options::Setting::Select.into(),
            message: "the delay search (delay auto) would see the held-out samples: \
                      estimate the delays first and give them fixed"
                .into(),
        }
    })?;
    progress.stage("processing (selection)", None);
    let prepared = train
        .iter()
        .map(|l| prepare(robot, l.samples, &settings.processing))
        .collect::<Result<Vec<_>, _>>()?;
    progress.finish();
    let (how, folds) = folds(&prepared, settings)?;
    let joints = JointMap::new(robot, settings.joints)?;
    let mut scores = Vec::with_capacity(candidates.0.len());
    for (i, c) in candidates.0.iter().enumerate() {
        progress.stage(
            &format!(
                "candidate {} of {} ({}), {} folds",
                i + 1,
                candidates.0.len(),
                c.name(),
                folds.len()
            ),
            None,
        );
        let mut s = c.settings(settings);
        // Pieces of one log are no separate recordings.
        s.log_offsets &= matches!(how, Folds::LeaveOneLogOut { .. });
        let model = s.model(robot)?.into_owned();
        let mut held_out = MetricSums::new(&model);
        for (f, fold) in folds.iter().enumerate() {
            let params = fit_pieces(&model, &fold.train, &s).map_err(|e| IdentError::Setting {
                name: crate::options::Setting::Select.into(),
                message: format!("candidate {}, fold {}: {e}", c.name(), f + 1),
            })?;
            for t in &fold.test {
                // Each piece's own sums (the Dahl states start at zero in each).
                held_out.merge(&MetricSums::of_samples(&model, &params, t.samples(), None));
            }
        }
        progress.finish();
        let m = held_out.metrics(&joints)?;
        m.check_finite(&format!("candidate {}'s held-out samples", c.name()))
            .map_err(|e| IdentError::Setting {
                name: crate::options::Setting::Select.into(),
                message: e.to_string(),
            })?;
        let mean = m.relative_error.iter().sum::<f64>() / m.relative_error.len().max(1) as f64;
        scores.push(CandidateScore {
            candidate: c.name(),
            relative_error: m.relative_error,
            mean,
        });
    }
    let best = (0..scores.len())
        .min_by(|&a, &b| scores[a].mean.total_cmp(&scores[b].mean))
        .unwrap_or(0);
    Ok((
        Selection {
            folds: how,
            joints: joints.names.clone(),
            candidates: scores.clone(),
            chosen: scores[best].candidate.clone(),
        },
        candidates.0[best],
    ))
}

/// The parameters fitted on the pieces `train` (each reduced as a log of its own), by
/// the fit's own estimator end ([`fit_observed`]).
fn fit_pieces(
    model: &Model,
    train: &[Prepared],
    settings: &FitSettings,
) -> Result<Vec<f64>, IdentError> {
    let mut observed: Option<Observed> = None;
    for p in train {
        let mut range = super::metrics::TorqueRange::new(model.dof());
        range.add(&p.tau);
        let parts = Observation::assemble_per_coordinate(model, p.samples(), &Silent);
        let info = InputInfo {
            role: "train".into(),
            path: String::new(),
            sha256: String::new(),
            bytes: 0,
            source: p.source.clone(),
            metrics: None,
            offset: None,
        };
        Observed::push(&mut observed, ObservedLog { info, parts }, range);
    }
    let observed = observed.ok_or_else(super::observed::no_training_log)?;
    let train_pass = |params: &[f64]| Ok(MetricSums::of_logs(model, params, train));
    let result = fit_observed(
        model,
        &observed,
        settings,
        MetricPasses {
            train: Some(&train_pass),
            test: &|_| Ok(Vec::new()),
        },
        &Silent,
    )?;
    Ok(model.params_from_named(
        result.parameters.iter().map(|(k, v)| (k.as_str(), *v)),
        "the fold's fit",
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::LowPass;

    /// The guard band covers the filter's reach: an impulse through the 2019 PSM filter
    /// (zero-phase, 6th order, 16.965 Hz effective, 200 Hz) has decayed below 10⁻³ of
    /// its peak beyond the guard (0.26 s), and not at a third of it.
    #[test]
    fn the_guard_band_outlasts_the_filters_impulse_response() {
        let mut settings = FitSettings::default();
        settings.processing.filter = Some(LowPass::wpi(5.4));
        let dt = 1.0 / 200.0;
        let guard = guard_s(&settings, dt);
        assert!((guard - 0.2604).abs() < 1e-3, "{guard}");
        let n = 401;
        let mut x = vec![0.0; n];
        x[n / 2] = 1.0;
        let y = LowPass::wpi(5.4).apply_slice(&x, 5.4, 200.0).unwrap();
        let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let beyond = |s: f64| {
            let k = (s / dt).round() as usize;
            y.iter()
                .enumerate()
                .filter(|(i, _)| i.abs_diff(n / 2) >= k)
                .fold(0.0f64, |m, (_, v)| m.max(v.abs()))
                / peak
        };
        assert!(beyond(guard) < 1e-3, "{}", beyond(guard));
        assert!(beyond(guard / 3.0) > 1e-3, "{}", beyond(guard / 3.0));
    }

    #[test]
    fn candidate_names_read_back() {
        for name in [
            "coulomb",
            "stribeck",
            "dahl:10",
            "stribeck:0.2+dahl",
            "stribeck+dahl",
        ] {
            assert_eq!(name.parse::<Candidate>().unwrap().name(), name);
        }
        use crate::options::ValueError;
        let e = "coulomb,viscous".parse::<Candidates>().unwrap_err();
        assert_eq!(
            e,
            ValueError::UnknownCandidateTerm {
                candidate: "viscous".into(),
                term: "viscous".into()
            }
        );
        assert!(
            e.to_string().contains("unknown candidate term `viscous`"),
            "{e}"
        );
        let e = "stribeck:-1,coulomb".parse::<Candidates>().unwrap_err();
        assert!(
            e.to_string().contains("`-1` is not a positive number"),
            "{e}"
        );
        let e = "dahl+dahl:5,coulomb".parse::<Candidates>().unwrap_err();
        assert_eq!(
            e,
            ValueError::TermTwice {
                candidate: "dahl+dahl:5".into(),
                term: "dahl".into()
            }
        );
        assert_eq!(
            "coulomb,coulomb"
                .parse::<Candidates>()
                .unwrap_err()
                .to_string(),
            "`coulomb,coulomb`: candidate coulomb is given twice"
        );
    }
}
