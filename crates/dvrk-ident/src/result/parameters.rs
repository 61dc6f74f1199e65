//! The per-parameter parts of a result: each link's standard parameters and
//! consistency, what the data determined of each parameter, and the base parameters.

use serde::{Deserialize, Serialize};

/// Standard parameters of one link (frame axes).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LinkResult {
    /// Index of the link's frame in the model (1-based, the description's frame order).
    pub frame: usize,
    /// The link's name in the robot description.
    pub link: String,
    /// kg
    pub mass: f64,
    /// centre of mass in the link frame, m
    pub com: [f64; 3],
    /// inertia about the centre of mass `[xx, xy, xz, yy, yz, zz]`, kg·m²
    pub inertia_com: [f64; 6],
    /// Which of the link's barycentric quantities the data determined (from
    /// [`FitResult::parameter_status`](crate::FitResult::parameter_status)); `None` in results written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub determined: Option<LinkDetermined>,
}

/// What the data determined of a fitted parameter: the result's `parameter_status`.
///
/// A parameter is `identified` when the data alone fix it: it is a base parameter by
/// itself (the unit vector of its column lies in the row space of the regressor, so no
/// combination of other columns can stand in for it; see `crate::fit::status`), and
/// its standard deviation from the same weighted data is at most
/// `crate::fit::status::DETERMINED_FRACTION` of its plausible magnitude `‖W·τ‖ /
/// ‖W·H·eᵢ‖` (the value at which it alone would produce the whole measured torque).
/// Otherwise its value is set by the regularization, a prior, the physical-consistency
/// constraints or the representative of a least-squares fit: `unidentified`. A
/// semidefinite fit's parameter that sits on one of its linear bounds (mass range,
/// centre-of-mass box, friction and motor-inertia bounds, `Fc + Fs ≥ 0`; to
/// `1e-4·max(1, |bound|)`, `crate::fit::status::BOUND_TOLERANCE`) is `at_lower_bound` or
/// `at_upper_bound` whatever the data say: the bound, not the data, set it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParameterStatus {
    /// The data alone determine it.
    Identified,
    /// It sits on a lower bound of the semidefinite fit.
    AtLowerBound,
    /// It sits on an upper bound of the semidefinite fit.
    AtUpperBound,
    /// Its value is set by something other than the data (see the type's documentation).
    Unidentified,
}

impl ParameterStatus {
    /// The name a result document, the command line and Python use: `identified`,
    /// `at_lower_bound`, `at_upper_bound`, `unidentified`.
    pub fn name(self) -> &'static str {
        match self {
            ParameterStatus::Identified => "identified",
            ParameterStatus::AtLowerBound => "at_lower_bound",
            ParameterStatus::AtUpperBound => "at_upper_bound",
            ParameterStatus::Unidentified => "unidentified",
        }
    }

    /// Identified by the data (not at a bound).
    pub fn identified(self) -> bool {
        self == ParameterStatus::Identified
    }
}

impl std::fmt::Display for ParameterStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Per link, whether the data determined its barycentric quantities (every parameter
/// of the group [`ParameterStatus::Identified`]).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct LinkDetermined {
    /// The mass `m`.
    pub mass: bool,
    /// The first moment `l = m·r` (all three components).
    pub first_moment: bool,
    /// The rotational inertia about the frame origin `L` (all six components).
    pub inertia: bool,
}

impl LinkDetermined {
    /// The centre of mass `r = l/m` is determined when `l` and `m` are.
    pub fn com(&self) -> bool {
        self.mass && self.first_moment
    }

    /// The inertia about the centre of mass `L − m·S(r)ᵀS(r)` is determined when `L`,
    /// `l` and `m` are.
    pub fn inertia_com(&self) -> bool {
        self.inertia && self.com()
    }
}

/// Physical consistency of one link: the smallest eigenvalue of its 4×4 pseudo-inertia.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Consistency {
    /// Index of the link's frame in the model (as in [`LinkResult::frame`]).
    pub frame: usize,
    /// The link's name in the robot description.
    pub link: String,
    /// kg·m²; positive means realizable by a positive mass density
    pub min_eigenvalue: f64,
    /// `min_eigenvalue > 0`: the link's inertial parameters are physically realizable.
    pub consistent: bool,
}

/// One base parameter with its value and standard deviation.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BaseParameterResult {
    /// The name of the base parameter's leading (kept) parameter, e.g. `L2xx`.
    pub name: String,
    /// The base parameter as a combination of standard parameters, e.g.
    /// `L2xy + L6xy + 0.2159*l2x`.
    pub expression: String,
    /// The fitted value of that combination (units of its leading parameter).
    pub value: f64,
    /// Standard deviation from the least-squares fit of the same weighted data.
    pub std: f64,
}

impl BaseParameterResult {
    /// Every base parameter of `base`, with its value (`values[i]`, the projection of
    /// the parameters) and standard deviation (`std[i]`): the rows a fit's result and a
    /// payload's identification write.
    pub(crate) fn all(
        base: &dvrk_model::BaseParameters,
        values: &[f64],
        std: &[f64],
    ) -> Vec<BaseParameterResult> {
        (0..base.rank())
            .map(|i| BaseParameterResult {
                name: base.names[i].clone(),
                expression: base.expressions[i].clone(),
                value: values[i],
                std: std[i],
            })
            .collect()
    }
}
