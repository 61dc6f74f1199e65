//! What a caller sets of the semidefinite fit: its options and the prior's metric.

/// Options of [`solve_sdp`](super::solve_sdp).
#[derive(Clone, Debug, PartialEq)]
pub struct SdpOptions {
    /// Tikhonov weight toward `prior`, relative to the data (no units; default 1e-12; see
    /// the module documentation). 0 disables it, only sensible when R11 has full rank
    /// (otherwise the solver typically ends `AlmostSolved`).
    pub regularization: f64,
    /// Values the regularization and the prior term pull toward, one per parameter
    /// (model units); `None` means zero. E.g. the model's nominal (CAD) parameters or
    /// an earlier fit. NaN: the prior has no value for that parameter (a partial prior,
    /// see the module documentation): the prior term leaves it free and only the
    /// regularization pulls it, toward zero.
    pub prior: Option<Vec<f64>>,
    /// Weight of the prior term (no units, relative to the data term scaled to at most 1;
    /// see the module documentation). 0: no prior term, only the regularization.
    pub prior_weight: f64,
    /// The divergence the prior weight multiplies.
    pub prior_metric: PriorMetric,
    /// Clarabel's iteration limit.
    pub max_iter: u32,
    /// Clarabel's gap and feasibility tolerances, in the scaled problem whose objective
    /// (the residual norm divided by `‖W·τ‖`) is at most about 1.
    pub tolerance: f64,
    /// `false`: apply the model's per-frame bounds ([`dvrk_model::FrameBounds`]: mass,
    /// com box, friction maxima, `ia_max`, spring range). `true`: ignore them, keeping
    /// only physical consistency (`J ⪰ eps·I`) and the global lower bounds
    /// ([`dvrk_model::GlobalBounds`]: `fc_min`, `fv_min`, `ia_min`).
    pub override_bounds: bool,
    /// `true`: keep every link with a bounding ellipsoid in its description inside it
    /// (see the module documentation); `false`: ignore the ellipsoids.
    pub ellipsoids: bool,
}

impl Default for SdpOptions {
    fn default() -> Self {
        SdpOptions {
            regularization: 1e-12,
            prior: None,
            prior_weight: 0.0,
            prior_metric: PriorMetric::default(),
            max_iter: 200,
            tolerance: 1e-8,
            override_bounds: false,
            ellipsoids: true,
        }
    }
}

/// How a prior's weight measures the distance from the prior (see the module
/// documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PriorMetric {
    /// Squared differences of the equilibrated parameters: a weighted Tikhonov term.
    Euclidean,
    /// Log-det divergence of each link's pseudo-inertia from the prior's (physically
    /// meaningful for every link size and frame); Euclidean for the other parameters.
    #[default]
    Entropic,
}

impl crate::names::Named for PriorMetric {
    const WHAT: &'static str = "prior metric";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("euclidean", PriorMetric::Euclidean),
        ("entropic", PriorMetric::Entropic),
    ];
    const CANONICAL: usize = 2;
}

impl PriorMetric {
    /// The name the command line, Python and results use.
    pub fn name(self) -> &'static str {
        crate::names::Named::name(self)
    }
}

impl std::str::FromStr for PriorMetric {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}
