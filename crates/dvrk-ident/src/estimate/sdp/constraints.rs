//! The constraint rows of the semidefinite program: each link's pseudo-inertia LMI
//! (`J(π) ⪰ eps·I`, scaled by the link's length), and the linear rows of the bounds and
//! the bounding ellipsoids (`tr(Q·J) ≥ 0`), in Clarabel's form `s = b − A·x ∈ cones`.

use clarabel::solver::SupportedConeT;
use dvrk_model::{BoundOrigin, Model};

use super::error::SdpError;
use super::options::SdpOptions;

/// The conic program's constraint rows `s = b − A·x ∈ cones`, as triplets, in the order
/// they are added.
#[derive(Default)]
pub(super) struct Rows {
    pub(super) ai: Vec<usize>,
    pub(super) aj: Vec<usize>,
    pub(super) av: Vec<f64>,
    pub(super) b: Vec<f64>,
    pub(super) cones: Vec<SupportedConeT<f64>>,
}

type SvecEntry = (usize, usize, &'static [(usize, f64)]);

/// Coefficients of the pseudo-inertia in Clarabel's triangle order: entry k of
/// `svec(J)` (upper triangle, column-major: (0,0), (0,1), (1,1), (0,2), (1,2), (2,2),
/// (0,3), (1,3), (2,3), (3,3)) as `(row, col, [(barycentric index, coefficient)])`,
/// barycentric order `[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]`, before the √2.
const PSEUDO_INERTIA_SVEC: [SvecEntry; 10] = [
    (0, 0, &[(0, -0.5), (3, 0.5), (5, 0.5)]),
    (0, 1, &[(1, -1.0)]),
    (1, 1, &[(0, 0.5), (3, -0.5), (5, 0.5)]),
    (0, 2, &[(2, -1.0)]),
    (1, 2, &[(4, -1.0)]),
    (2, 2, &[(0, 0.5), (3, 0.5), (5, -0.5)]),
    (0, 3, &[(6, 1.0)]),
    (1, 3, &[(7, 1.0)]),
    (2, 3, &[(8, 1.0)]),
    (3, 3, &[(9, 1.0)]),
];

/// Rows `s = b − A·π ∈ PSD(4)` (in π, before variable scaling) that encode
/// `T·(J(π) − eps·I)·T ⪰ 0`, `T = diag(1, 1, 1, tau)`, for the link whose `Lxx` is
/// parameter `p0`. Returns, per svec entry, the `(parameter, coefficient of A)` list and
/// `b`.
pub(super) fn lmi_rows(p0: usize, eps: f64, tau: f64) -> Vec<(Vec<(usize, f64)>, f64)> {
    PSEUDO_INERTIA_SVEC
        .iter()
        .map(|&(i, j, coefs)| {
            let t = |k: usize| if k == 3 { tau } else { 1.0 };
            let w = t(i)
                * t(j)
                * if i == j {
                    1.0
                } else {
                    std::f64::consts::SQRT_2
                };
            let a = coefs.iter().map(|&(k, c)| (p0 + k, -w * c)).collect();
            let b = if i == j { -w * eps } else { 0.0 };
            (a, b)
        })
        .collect()
}

/// Linear constraints `Σ a·π ≤ c` collected per frame.
#[derive(Default)]
struct Linear {
    rows: Vec<(Vec<(usize, f64)>, f64)>,
}

impl Linear {
    /// `Σ a·π ≤ c`; an infinite `c = +∞` is no constraint.
    fn le(&mut self, a: Vec<(usize, f64)>, c: f64, what: &str) -> Result<(), SdpError> {
        if c == f64::INFINITY {
            return Ok(());
        }
        if !c.is_finite() || a.iter().any(|(_, v)| !v.is_finite()) {
            return Err(SdpError::NonFinite {
                what: what.to_string(),
            });
        }
        self.rows.push((a, c));
        Ok(())
    }
}

/// The linear rows of the frame bounds, the elements' bounds ([`Model::bound_rows`]) and
/// (with `ellipsoids`) the bounding ellipsoids' `tr(Q·J) ≥ 0`.
fn bounds_rows(model: &Model, override_bounds: bool, ellipsoids: bool) -> Result<Linear, SdpError> {
    let mut lin = Linear::default();
    for (fi, row) in model.bound_rows(!override_bounds) {
        let what = match row.origin {
            BoundOrigin::Global(field) => format!("global bound {field}"),
            BoundOrigin::Frame(field) => format!(
                "bounds of frame {} ({}): {field}",
                fi + 1,
                model.frames[fi].name
            ),
            BoundOrigin::Physical(constraint) => constraint.to_string(),
        };
        lin.le(row.coefficients, row.limit, &what)?;
    }
    if ellipsoids && !override_bounds {
        for (fi, f) in model.frames.iter().enumerate() {
            let (Some(p0), Some(e)) = (f.inertia, f.bounds.ellipsoid.as_ref()) else {
                continue;
            };
            // −tr(Q·J(π)) ≤ 0.
            let what = format!("bounds of frame {} ({}): ellipsoid", fi + 1, f.name);
            let coefs = e.barycentric_coefficients();
            if coefs.iter().any(|c| !c.is_finite()) {
                return Err(SdpError::NonFinite { what });
            }
            let row = (0..10).map(|k| (p0 + k, -coefs[k])).collect();
            lin.le(row, 0.0, &what)?;
        }
    }
    Ok(lin)
}

/// Length (m) balancing a link's pseudo-inertia: the largest com-box bound, clamped to
/// [0.01, 10] m, or 0.1 m without a box.
pub(super) fn link_length(model: &Model, frame_index: usize, override_bounds: bool) -> f64 {
    let f = &model.frames[frame_index];
    match f.bounds.com {
        Some(com) if !override_bounds => {
            let r = com
                .iter()
                .flat_map(|b| b.iter())
                .fold(0.0f64, |a, &x| a.max(x.abs()));
            if r.is_finite() {
                r.clamp(0.01, 10.0)
            } else {
                0.1
            }
        }
        _ => 0.1,
    }
}

/// Linear bounds, each row scaled to a unit largest coefficient.
pub(super) fn linear_rows(
    rows: &mut Rows,
    model: &Model,
    s: &[f64],
    options: &SdpOptions,
) -> Result<(), SdpError> {
    let lin = bounds_rows(model, options.override_bounds, options.ellipsoids)?;
    for (coefs, c) in &lin.rows {
        let scaled: Vec<(usize, f64)> = coefs.iter().map(|&(k, a)| (k, a * s[k])).collect();
        let w = scaled.iter().fold(0.0f64, |m, &(_, a)| m.max(a.abs()));
        let w = if w > 0.0 { w } else { 1.0 };
        let row = rows.b.len();
        for (k, a) in scaled {
            rows.ai.push(row);
            rows.aj.push(k);
            rows.av.push(a / w);
        }
        rows.b.push(c / w);
    }
    if !lin.rows.is_empty() {
        rows.cones
            .push(SupportedConeT::NonnegativeConeT(lin.rows.len()));
    }
    Ok(())
}

/// Pseudo-inertia LMIs, one 4×4 block per link.
pub(super) fn lmi_rows_of_links(
    rows: &mut Rows,
    model: &Model,
    s: &[f64],
    eps: f64,
    override_bounds: bool,
) {
    for (fi, f) in model.frames.iter().enumerate() {
        let Some(p0) = f.inertia else { continue };
        let tau = link_length(model, fi, override_bounds);
        let block = lmi_rows(p0, eps, tau);
        // Normalize the block so its largest scaled coefficient is 1.
        let w = block
            .iter()
            .flat_map(|(a, _)| a.iter().map(|&(k, v)| (v * s[k]).abs()))
            .fold(0.0f64, f64::max);
        let w = if w > 0.0 { w } else { 1.0 };
        for (coefs, bv) in block {
            let row = rows.b.len();
            for (k, a) in coefs {
                rows.ai.push(row);
                rows.aj.push(k);
                rows.av.push(a * s[k] / w);
            }
            rows.b.push(bv / w);
        }
        rows.cones.push(SupportedConeT::PSDTriangleConeT(4));
    }
}
