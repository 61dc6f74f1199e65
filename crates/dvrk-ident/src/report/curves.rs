//! Binned curves of a processed log: the friction each joint shows (measured torque
//! minus the model's non-friction part, against velocity) beside the fitted friction
//! model, and the prediction error against velocity and position.
//!
//! Samples are grouped into bins of equal width over the abscissa; each bin keeps the
//! median and the quartiles of its ordinates, so a curve of thousands of samples is a
//! few dozen numbers (small figures, robust to the torque spikes of real logs). Bins with
//! fewer than [`MIN_BIN_SAMPLES`] samples are left out.

use dvrk_model::{Model, ParamKind};
use nalgebra::DMatrix;

use crate::fit::{predict, JointMap, Prepared};

/// Bins over each abscissa.
pub const BINS: usize = 32;

/// Fewest samples a bin needs to be shown (its median then has a standard error of about
/// a quarter of the spread of its samples).
pub const MIN_BIN_SAMPLES: usize = 20;

/// Whether a parameter belongs to friction: Coulomb, viscous, offset, Stribeck and
/// quadratic viscous and monotone friction terms (not the links, motor inertias or springs).
pub fn is_friction(kind: ParamKind) -> bool {
    matches!(
        kind,
        ParamKind::Coulomb
            | ParamKind::Viscous
            | ParamKind::Offset
            | ParamKind::Stribeck
            | ParamKind::QuadraticViscous
            | ParamKind::MonotoneFriction
    )
}

/// Median and quartiles of a bin's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quartiles {
    /// 25th percentile.
    pub lower: f64,
    /// 50th percentile.
    pub median: f64,
    /// 75th percentile.
    pub upper: f64,
}

impl Quartiles {
    /// Of `values` (sorted here; linear interpolation between order statistics, as
    /// numpy's default); `None` when empty.
    pub fn of(values: &mut [f64]) -> Option<Quartiles> {
        if values.is_empty() {
            return None;
        }
        values.sort_by(f64::total_cmp);
        let at = |p: f64| {
            let pos = p * (values.len() - 1) as f64;
            let (i, f) = (pos.floor() as usize, pos - pos.floor());
            let next = values[(i + 1).min(values.len() - 1)];
            values[i] + f * (next - values[i])
        };
        Some(Quartiles {
            lower: at(0.25),
            median: at(0.5),
            upper: at(0.75),
        })
    }
}

/// One bin of a curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Bin {
    /// Samples in the bin.
    pub count: usize,
    /// The bin's edges on the abscissa.
    pub edges: (f64, f64),
    /// Median abscissa of its samples.
    pub x: f64,
    /// The measured ordinates (friction seen, or prediction error).
    pub measured: Quartiles,
    /// Median of the model's ordinate over the same samples (the fitted friction), when
    /// the curve has one.
    pub model: Option<f64>,
}

/// A binned curve of one coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The coordinate's name.
    pub coordinate: String,
    /// The bins with at least [`MIN_BIN_SAMPLES`] samples, in order of the abscissa.
    pub bins: Vec<Bin>,
}

/// The sample indices of each of about `bins` bins of equal width over the range of `x`
/// (non-finite values left out). With `zero_edge`, 0 is an edge when the range spans it,
/// so no bin mixes the two directions of motion (Coulomb friction changes sign there).
pub fn bin_indices(x: &[f64], bins: usize, zero_edge: bool) -> Vec<((f64, f64), Vec<usize>)> {
    let finite = x.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if lo > hi {
        return Vec::new();
    }
    if lo == hi || bins < 2 {
        let all = (0..x.len()).filter(|&i| x[i].is_finite()).collect();
        return vec![((lo, hi), all)];
    }
    let width = (hi - lo) / bins as f64;
    let start = if zero_edge && lo < 0.0 && hi > 0.0 {
        (lo / width).floor() * width
    } else {
        lo
    };
    let count = (((hi - start) / width).ceil() as usize).max(1);
    let mut out: Vec<((f64, f64), Vec<usize>)> = (0..count)
        .map(|b| {
            let a = start + b as f64 * width;
            ((a, a + width), Vec::new())
        })
        .collect();
    for (i, &v) in x.iter().enumerate() {
        if v.is_finite() {
            let b = (((v - start) / width).floor().max(0.0) as usize).min(count - 1);
            out[b].1.push(i);
        }
    }
    out
}

/// The curve of `y` (and of `model`, if given) against `x` for coordinate `name`.
pub fn binned(name: &str, x: &[f64], y: &[f64], model: Option<&[f64]>, zero_edge: bool) -> Curve {
    let bins = bin_indices(x, BINS, zero_edge)
        .into_iter()
        .filter(|(_, idx)| idx.len() >= MIN_BIN_SAMPLES)
        .filter_map(|(edges, idx)| {
            let mut xs: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
            let mut ys: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
            let model = model.and_then(|m| {
                let mut ms: Vec<f64> = idx.iter().map(|&i| m[i]).collect();
                Quartiles::of(&mut ms).map(|q| q.median)
            });
            Some(Bin {
                count: idx.len(),
                edges,
                x: Quartiles::of(&mut xs)?.median,
                measured: Quartiles::of(&mut ys)?,
                model,
            })
        })
        .collect();
    Curve {
        coordinate: name.into(),
        bins,
    }
}

/// The torques of `data` split for the friction curves, samples × coordinates:
/// `(measured − model without friction, model's friction)`. The model is linear in the
/// parameters, so its friction is the inverse dynamics with only the friction parameters
/// ([`is_friction`]) and the rest is the inverse dynamics with them zeroed (links, motor
/// inertias, springs).
pub fn friction_torques(
    model: &Model,
    params: &[f64],
    data: &Prepared,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let split = |keep_friction: bool| -> Vec<f64> {
        model
            .params
            .iter()
            .zip(params)
            .map(|(p, &v)| {
                if is_friction(p.kind) == keep_friction {
                    v
                } else {
                    0.0
                }
            })
            .collect()
    };
    let rest = predict(model, &split(false), data);
    let friction = predict(model, &split(true), data);
    (&data.tau - rest, friction)
}

fn column(m: &DMatrix<f64>, j: usize) -> Vec<f64> {
    m.column(j).iter().copied().collect()
}

/// Per joint of `joints`, the friction the log shows (measured torque minus the model
/// without friction) binned over the joint's velocity, with the fitted friction (the
/// model's friction torque on the same samples) per bin. `data` in model coordinates;
/// in coupled measured joints the fitted friction of a joint mixes its coordinates'
/// friction laws, so its bins are those of the samples rather than one curve.
pub fn friction_curves(
    model: &Model,
    params: &[f64],
    data: &Prepared,
    joints: &JointMap,
) -> Vec<Curve> {
    let (seen, fitted) = friction_torques(model, params, data);
    let (seen, fitted, dq) = (
        joints.torque(&seen),
        joints.torque(&fitted),
        joints.motion(&data.dq),
    );
    (0..joints.dof())
        .map(|j| {
            let fitted = column(&fitted, j);
            binned(
                &joints.names[j],
                &column(&dq, j),
                &column(&seen, j),
                Some(&fitted),
                true,
            )
        })
        .collect()
}

/// What the prediction error is drawn against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Against {
    /// The coordinate's velocity.
    Velocity,
    /// The coordinate's position.
    Position,
}

/// Per joint of `joints`, the prediction error `measured − predicted` binned over the
/// joint's velocity or position; `data` and `predicted` already in those joints
/// ([`JointMap::prepared`], [`JointMap::torque`]).
pub fn residual_curves(
    joints: &JointMap,
    data: &Prepared,
    predicted: &DMatrix<f64>,
    against: Against,
) -> Vec<Curve> {
    let error = &data.tau - predicted;
    let x = match against {
        Against::Velocity => &data.dq,
        Against::Position => &data.q,
    };
    (0..joints.dof())
        .map(|j| {
            binned(
                &joints.names[j],
                &column(x, j),
                &column(&error, j),
                None,
                against == Against::Velocity,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_interpolate_like_numpy() {
        let q = Quartiles::of(&mut [4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((q.lower, q.median, q.upper), (1.75, 2.5, 3.25));
        assert!(Quartiles::of(&mut []).is_none());
    }

    #[test]
    fn zero_is_an_edge_and_every_finite_sample_is_binned_once() {
        let x: Vec<f64> = (0..1000).map(|i| -1.3 + 2.9 * i as f64 / 999.0).collect();
        let bins = bin_indices(&x, 10, true);
        assert!(bins.iter().any(|((a, _), _)| a.abs() < 1e-12));
        let total: usize = bins.iter().map(|(_, i)| i.len()).sum();
        assert_eq!(total, 1000);
        for ((a, b), idx) in &bins {
            for &i in idx {
                assert!(x[i] >= a - 1e-12 && x[i] <= b + 1e-12);
            }
        }
        // No bin holds samples of both signs.
        for (_, idx) in &bins {
            let pos = idx.iter().filter(|&&i| x[i] > 0.0).count();
            assert!(pos == 0 || pos == idx.len());
        }
        let mut with_nan = x.clone();
        with_nan[3] = f64::NAN;
        let total: usize = bin_indices(&with_nan, 10, false)
            .iter()
            .map(|(_, i)| i.len())
            .sum();
        assert_eq!(total, 999);
    }

    #[test]
    fn sparse_bins_are_left_out() {
        // 100 samples at 0..1, 5 far away at 10: the far bin is too thin to show.
        let mut x: Vec<f64> = (0..100).map(|i| i as f64 / 100.0).collect();
        x.extend([10.0; 5]);
        let y = x.clone();
        let c = binned("q1", &x, &y, None, false);
        assert!(c.bins.iter().all(|b| b.count >= MIN_BIN_SAMPLES));
        assert!(!c.bins.is_empty() && c.bins.iter().all(|b| b.x < 2.0));
    }
}
