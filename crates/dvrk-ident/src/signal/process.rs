//! [`process`]: the whole-log reference of the processing, which the fit's block
//! processor ([`super::stream::BlockProcessor`]) is held to.

use nalgebra::DMatrix;

use super::{
    advance, central_difference, resample_linear, select_rows, AccelerationSource, Processed,
    Processing, SignalError, Stencil,
};
use crate::JointLog;

/// A per-column operation: (column samples, joint index) -> new column.
type ColumnFn<'a> = dyn Fn(&[f64], usize) -> Result<Vec<f64>, SignalError> + 'a;

/// The reference processing of a whole log in memory, which the fit does not call: the
/// fit processes every log block by block (`stream::BlockProcessor`, through
/// [`crate::fit::prepare`]), and the tests hold that processor to this definition (1e-12
/// relative; the filters' settling tolerance, `stream::SETTLE_TOLERANCE`). The steps:
/// 1. validate it; resample to `resample_hz` if set, else require a uniform clock;
/// 2. low-pass q (zero phase), and tau with `filter_torque`;
/// 3. dq: the filtered measured velocity, else the derivative of the filtered q;
/// 4. ddq: derivative (`acceleration_stencil`) of the raw measured velocity (2019
///    protocol) or of the processed velocity, then low-passed;
/// 5. trim `trim` samples at each end, keep every `decimate`-th sample, drop samples
///    with some |dq| < `min_speed`.
///
/// ```rust
/// use dvrk_ident::signal::{process, Processing};
/// use dvrk_ident::{Coordinates, JointLog};
/// use dvrk_logs::uniform_time;
/// use nalgebra::DMatrix;
/// let n = 1000;
/// let rate = 200.0;
/// let t = uniform_time(n, rate);
/// let log = JointLog {
///     time: t.clone(),
///     q: DMatrix::from_fn(n, 1, |i, _| t[i].sin()),
///     dq: None,
///     tau: DMatrix::from_fn(n, 1, |i, _| t[i].cos()),
///     joint_names: vec!["q1".into()],
///     coordinates: Coordinates::Model,
///     source: "example".into(),
/// };
/// let p = process(&log, &Processing::default()).unwrap();
/// assert_eq!(p.len(), n - 400);
/// // d/dt sin = cos, d²/dt² sin = -sin, recovered through the filter.
/// let k = 300;
/// let tk = p.time[k];
/// assert!((p.dq[(k, 0)] - tk.cos()).abs() < 1e-6);
/// assert!((p.ddq[(k, 0)] + tk.sin()).abs() < 1e-6);
/// ```
pub fn process(log: &JointLog, settings: &Processing) -> Result<Processed, SignalError> {
    log.validate()?;
    settings.check(log.dof())?;
    let Uniform {
        time,
        q,
        dq: dq_raw,
        tau,
        rate_hz,
    } = uniform_signals(log, settings)?;
    let tau = advanced(tau, &settings.delay_s, rate_hz);
    let n = time.len();
    if 2 * settings.trim >= n {
        return Err(SignalError::TrimTooLong {
            trim: settings.trim,
            len: n,
        });
    }
    let step_s = 1.0 / rate_hz;
    // Errors of a column name the source, the signal and the joint.
    let in_column = |signal: &'static str, j: usize| {
        move |e: SignalError| SignalError::InColumn {
            source_name: log.source.clone(),
            signal,
            joint: log.joint_names[j].clone(),
            inner: Box::new(e),
        }
    };
    let per_column = |m: &DMatrix<f64>,
                      signal: &'static str,
                      f: &ColumnFn<'_>|
     -> Result<DMatrix<f64>, SignalError> {
        let mut out = DMatrix::zeros(m.nrows(), m.ncols());
        for j in 0..m.ncols() {
            let col: Vec<f64> = m.column(j).iter().copied().collect();
            let y = f(&col, j).map_err(in_column(signal, j))?;
            out.column_mut(j).copy_from_slice(&y);
        }
        Ok(out)
    };
    let filt = |m: &DMatrix<f64>, signal: &'static str| match &settings.filter {
        None => Ok(m.clone()),
        Some(f) => per_column(m, signal, &|col, j| {
            let fc = f.cutoff_hz.for_joint(j).unwrap_or(f64::NAN);
            f.apply_slice(col, fc, rate_hz)
        }),
    };
    let diff = |m: &DMatrix<f64>, stencil: Stencil, signal: &'static str| {
        per_column(m, signal, &|col, _| {
            central_difference(col, step_s, stencil)
        })
    };

    let q_f = filt(&q, "position")?;
    let tau_f = if settings.filter_torque {
        filt(&tau, "effort")?
    } else {
        tau.clone()
    };
    let dq_f = match &dq_raw {
        Some(d) => filt(d, "velocity")?,
        None => diff(&q_f, settings.velocity_stencil, "velocity")?,
    };
    let acc_base = match (settings.acceleration_from, &dq_raw) {
        (AccelerationSource::RawVelocity, Some(d)) => d,
        _ => &dq_f,
    };
    let ddq_f = filt(
        &diff(acc_base, settings.acceleration_stencil, "acceleration")?,
        "acceleration",
    )?;

    let rows = kept_rows(settings, n, &dq_f, &log.source)?;
    Ok(Processed {
        time: rows.iter().map(|&i| time[i]).collect(),
        q: select_rows(&q_f, &rows),
        dq: select_rows(&dq_f, &rows),
        ddq: select_rows(&ddq_f, &rows),
        tau: select_rows(&tau_f, &rows),
        joint_names: log.joint_names.clone(),
        coordinates: log.coordinates,
        rate_hz,
        dq_measured: dq_raw.is_some(),
        source: log.source.clone(),
    })
}

/// A log's signals on a uniform clock.
struct Uniform {
    /// s.
    time: Vec<f64>,
    q: DMatrix<f64>,
    /// The measured velocities, if any.
    dq: Option<DMatrix<f64>>,
    tau: DMatrix<f64>,
    rate_hz: f64,
}

/// The signals on a uniform clock: resampled to `settings.resample_hz`, or checked
/// uniform.
fn uniform_signals(log: &JointLog, settings: &Processing) -> Result<Uniform, SignalError> {
    Ok(match settings.resample_hz {
        Some(rate) => {
            let (t, q) = resample_linear(&log.time, &log.q, rate)?;
            let (_, tau) = resample_linear(&log.time, &log.tau, rate)?;
            let dq = match &log.dq {
                Some(d) => Some(resample_linear(&log.time, d, rate)?.1),
                None => None,
            };
            Uniform {
                time: t,
                q,
                dq,
                tau,
                rate_hz: rate,
            }
        }
        None => {
            let rate = log.check_uniform(settings.uniform_tolerance)?;
            Uniform {
                time: log.time.clone(),
                q: log.q.clone(),
                dq: log.dq.clone(),
                tau: log.tau.clone(),
                rate_hz: rate,
            }
        }
    })
}

/// The torques advanced by each coordinate's measurement delay (`delay_s`, s), unchanged
/// without delays.
fn advanced(tau: DMatrix<f64>, delay_s: &[f64], rate_hz: f64) -> DMatrix<f64> {
    match advance::Advance::new(delay_s, rate_hz) {
        Some(mut a) => {
            let mut out = Vec::with_capacity(tau.len());
            let mut row = vec![0.0; tau.ncols()];
            for k in 0..tau.nrows() {
                for (j, r) in row.iter_mut().enumerate() {
                    *r = tau[(k, j)];
                }
                a.push(&row, &mut out);
            }
            a.finish(&mut out);
            DMatrix::from_row_slice(tau.nrows(), tau.ncols(), &out)
        }
        None => tau,
    }
}

/// The samples kept: trimmed at both ends, decimated, and (with a minimum speed) those
/// whose every joint moves at least that fast.
fn kept_rows(
    settings: &Processing,
    n: usize,
    dq_f: &DMatrix<f64>,
    source: &str,
) -> Result<Vec<usize>, SignalError> {
    let mut rows: Vec<usize> = (settings.trim..n - settings.trim)
        .step_by(settings.decimate)
        .collect();
    if let Some(min_speed) = settings.min_speed {
        rows.retain(|&i| dq_f.row(i).iter().all(|v| v.abs() >= min_speed));
        if rows.is_empty() {
            return Err(SignalError::NoSamplesLeft {
                source_name: source.to_owned(),
                min_speed,
            });
        }
    }
    Ok(rows)
}
