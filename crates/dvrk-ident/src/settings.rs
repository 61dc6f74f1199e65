//! What a fit is asked to do: the estimator ([`Method`]), the bounds set, the processing
//! and the model options ([`FitSettings`]). A leaf: the pipeline (`fit`), the result
//! document (`result`), observation states and the front ends all read these, and it
//! reads none of them.

use dvrk_model::Model;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::IdentError;
pub use crate::estimate::sdp::PriorMetric;
use crate::estimate::sdp::SdpOptions;
pub use crate::estimate::Method;
use crate::options::Setting;
use crate::options::ValueError;
use crate::signal::Processing;

/// Which joints a fit's errors, figures and predictions are reported in: the model's
/// coordinates (the math's, default) or the arm's measured joints by their names (the
/// dVRK's `outer_wrist_pitch`… rather than the PSM's motor-side `q5..q7`). The
/// estimator always works in model coordinates; this only chooses how its results are
/// shown, through the coupling `q_measured = M·q`, `τ_measured = M⁻ᵀ·τ`
/// ([`crate::fit::JointMap`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Joints {
    /// The model coordinates `q1..qn`.
    #[default]
    Model,
    /// The robot's measured joints (the description's `[measured] joints`).
    Measured,
}

/// Frame names, comma-separated in a flag's text (`upper_arm,forearm`), a list in a
/// document or a Python call.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct FrameNames(pub Vec<String>);

impl std::str::FromStr for FrameNames {
    type Err = crate::options::ValueError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let names: Vec<String> = s.split(',').map(|n| n.trim().to_string()).collect();
        if names.iter().any(String::is_empty) {
            return Err(crate::options::ValueError::NotFrameNames(s.to_string()));
        }
        Ok(FrameNames(names))
    }
}

impl Joints {
    /// The name the command line, Python and results use (see [`crate::names`]).
    pub fn name(self) -> &'static str {
        crate::names::Named::name(self)
    }

    /// Whether these are the model coordinates (the default, left out of documents).
    pub fn is_model(&self) -> bool {
        *self == Joints::Model
    }
}

impl crate::names::Named for Joints {
    const WHAT: &'static str = "joints";
    const NAMES: &'static [(&'static str, Self)] =
        &[("model", Joints::Model), ("measured", Joints::Measured)];
    const CANONICAL: usize = 2;
}

impl std::str::FromStr for Joints {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// A named set of the global lower bounds of the semidefinite fit
/// ([`dvrk_model::GlobalBounds`]), replacing the description's `[bounds]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoundsSet {
    /// `Fc, Fv ≥ 0`, `Ia ≥ 1e-6`: physical ([`dvrk_model::GlobalBounds::PHYSICAL`]).
    #[serde(rename = "physical")]
    Physical,
    /// `Fc, Fv, Ia ≥ 0.001`, to reproduce the 2019 fit
    /// ([`dvrk_model::GlobalBounds::WANG_2019`]).
    #[serde(rename = "2019")]
    Wang2019,
}

impl BoundsSet {
    /// The bounds of the set.
    pub fn bounds(self) -> dvrk_model::GlobalBounds {
        match self {
            BoundsSet::Physical => dvrk_model::GlobalBounds::PHYSICAL,
            BoundsSet::Wang2019 => dvrk_model::GlobalBounds::WANG_2019,
        }
    }
}

impl crate::names::Named for BoundsSet {
    const WHAT: &'static str = "bounds";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("physical", BoundsSet::Physical),
        ("2019", BoundsSet::Wang2019),
        ("wang2019", BoundsSet::Wang2019),
    ];
    const CANONICAL: usize = 2;
}

impl std::str::FromStr for BoundsSet {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// What the semidefinite fit is regularized toward, and how hard (see
/// `estimate::sdp`, "Priors"). The values are kept here by name so a result records
/// exactly what its fit used, and a fit from its settings repeats it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prior {
    /// Where the values came from: `nominal` (the description's nominal parameters)
    /// or the result file they were read from.
    pub source: String,
    /// The divergence the weight multiplies.
    pub metric: PriorMetric,
    /// Weight relative to the data term, which is scaled to at most 1 (no units).
    pub weight: f64,
    /// The values by parameter name (model units): every parameter of the fitted model,
    /// or, for a partial prior (e.g. `nominal` on a robot whose maker publishes only
    /// link masses), those it has a value for; the others are left free (see
    /// `estimate::sdp`, "Priors").
    pub parameters: indexmap::IndexMap<String, f64>,
}

impl Prior {
    /// The weight when none is given: see docs/book/src/fit.md (priors) for the
    /// measurements behind it.
    pub const DEFAULT_WEIGHT: f64 = 1e-3;

    /// The values in `model`'s parameter order, NaN where a partial prior has none;
    /// `None` without a prior. Errors name the prior's source and the parameters that
    /// are not `model`'s or not finite.
    pub fn values_for(
        prior: Option<&Prior>,
        model: &Model,
    ) -> Result<Option<Vec<f64>>, IdentError> {
        let Some(p) = prior else { return Ok(None) };
        let setting = |message: String| IdentError::Setting {
            name: crate::options::Setting::Prior.into(),
            message: format!("prior {}: {message}", p.source),
        };
        let mut values = vec![f64::NAN; model.n_params()];
        let mut unknown = Vec::new();
        for (name, &v) in &p.parameters {
            match model.param_index(name) {
                Some(_) if !v.is_finite() => {
                    return Err(setting(format!("parameter {name} is {v}")))
                }
                Some(k) => values[k] = v,
                None => unknown.push(name.as_str()),
            }
        }
        if !unknown.is_empty() {
            return Err(setting(format!(
                "parameters not in model {}: {}",
                model.name,
                unknown.join(", ")
            )));
        }
        if values.iter().all(|v| v.is_nan()) {
            return Err(setting("it has no value for any parameter".into()));
        }
        Ok(Some(values))
    }

    /// Checks what a fit needs of a prior: a weight the solver resolves and the
    /// semidefinite estimator (the least-squares estimators have no prior term).
    pub fn check(&self, method: Method) -> Result<(), IdentError> {
        let setting = |name: Setting, message: String| IdentError::Setting {
            name: name.into(),
            message,
        };
        if let Some(message) = crate::estimate::sdp::prior_weight_problem(self.weight) {
            return Err(setting(Setting::PriorWeight, message));
        }
        if method != Method::Sdp {
            return Err(setting(
                Setting::Prior,
                format!(
                    "only the semidefinite fit (method sdp) has a prior term, not method {}",
                    method.name()
                ),
            ));
        }
        Ok(())
    }
}

/// Settings of a fit. Defaults: SDP, the processing defaults, metrics over whole logs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FitSettings {
    /// The estimator (`ols`, `wls`, `irls`, `sdp`; default `sdp`).
    pub method: Method,
    /// How the logs are filtered, differentiated, trimmed and decimated before the fit.
    pub processing: Processing,
    /// Metrics on the first N processed samples of the test log only (the 2019 protocol
    /// uses the first period). `None`: all samples.
    pub test_window: Option<usize>,
    /// Re-weighting passes of IRLS.
    pub irls_iterations: usize,
    /// Tikhonov weight of the SDP toward zero, relative (see `estimate::sdp`).
    pub sdp_regularization: f64,
    /// Adds a Stribeck term `Fs·sign(ṡ)·exp(−(ṡ/vs)²)` with this velocity (rad/s or
    /// m/s) to every friction element of the model that has none (see
    /// [`FitSettings::model`]). `None`: the model as described.
    pub stribeck_velocity: Option<f64>,
    /// Adds Dahl friction `Fd·z` (rate-independent hysteresis, [`dvrk_model::Dahl`]) of
    /// this stiffness `σ` (1/rad or 1/m) to every frame with friction and no Dahl element
    /// (see [`FitSettings::model`]); its state is integrated from the processed positions
    /// in time order. `None`: the model as described.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dahl_sigma: Option<f64>,
    /// Adds a position-dependent torque, a Fourier series of this order in the joint
    /// angle ([`dvrk_model::PositionTorque`], period one turn, no constant term: that is
    /// the offset `Fo`), to every revolute frame with friction and none yet (see
    /// [`FitSettings::model`]). `None`: the model as described.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_torque_order: Option<usize>,
    /// The frames (by name) of [`FitSettings::position_torque_order`]'s torque; empty:
    /// every revolute frame with friction (see
    /// [`dvrk_model::Model::with_position_torque_on`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub position_torque_frames: Vec<String>,
    /// Adds load-dependent Coulomb friction `Fl·|τ|·sign(q̇)` ([`dvrk_model::LoadFriction`],
    /// the load the coordinate's measured torque in the fit, the predicted one in the
    /// metrics) to every frame with friction whose joint value is one coordinate's
    /// multiple, one per coordinate (see [`FitSettings::model`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub load_friction: bool,
    /// The arm's mounting pitch, degrees: gravity in the base frame becomes
    /// `(0, −9.81·sin p, −9.81·cos p)` m/s² (as the dVRK's `mounting_pitch`, see
    /// [`dvrk_model::Model::mounting_pitch_gravity`]) in the model of the fit and of every
    /// use of the result (see [`FitSettings::model`]). `None`: the description's
    /// `gravity`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mounting_pitch_deg: Option<f64>,
    /// Lower bounds on Fc, Fv, Ia of the semidefinite fit in place of the description's
    /// (see [`FitSettings::model`]). `None`: the description's `[bounds]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<BoundsSet>,
    /// Keep each link with a bounding ellipsoid in its description inside it (the
    /// semidefinite fit's `tr(Q·J) ≥ 0`, see `estimate::sdp`); `false` ignores them.
    #[serde(skip_serializing_if = "is_true")]
    pub ellipsoids: bool,
    /// Estimate the torques' measurement delays over `[0, this]` s and fit
    /// with them (they replace `processing.delay_s`, where the result records them; see
    /// `fit::delay`).
    /// `None`: the delays of `processing.delay_s`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delay_search_s: Option<f64>,
    /// Regularize the semidefinite fit toward a prior. `None`: only the small Tikhonov
    /// term of `sdp_regularization`, toward zero.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior: Option<Prior>,
    /// The joints the metrics (and validate's, report's and predict's output) are in;
    /// the fit itself is the same ([`Joints`]).
    #[serde(skip_serializing_if = "Joints::is_model")]
    pub joints: Joints,
    /// Give every training log after the first its own torque offset per model
    /// coordinate (the arm is re-homed between recordings): eliminated from the fit
    /// exactly (`Observation::project_out`), recorded in each log's `inputs[].offset`;
    /// the model's `Fo` are the first log's, which every use of the result (validate,
    /// residual on a new log) applies.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub log_offsets: bool,
    /// Choose the friction model among these candidates by cross-validated (held-out)
    /// error before fitting (`crate::fit::select`): the result's `selection` holds the
    /// table, `stribeck_velocity` and `dahl_sigma` the winner's terms. `None`: no
    /// selection.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub select: Option<Candidates>,
}

impl FitSettings {
    /// Most IRLS re-weighting passes a fit accepts: the weights settle in a handful
    /// (the default is 5; on the bundled PSM log the weights after 5 passes and after
    /// 20 differ by 1.2e-14 relative), and each pass solves the least squares again,
    /// so a mistyped `1e8` would run for hours instead of failing.
    pub const MAX_IRLS_ITERATIONS: usize = 100;
    /// Largest relative Tikhonov weight of the semidefinite fit: 1 weighs the pull
    /// toward zero like the data's strongest direction, beyond which the fit is the
    /// regularization's, not the data's.
    pub const MAX_SDP_REGULARIZATION: f64 = 1.0;

    /// Refuses estimator settings outside their ranges, naming the setting (the
    /// processing and the prior check their own).
    pub fn check_estimator(&self) -> Result<(), IdentError> {
        let setting = |name: Setting, message: String| {
            Err(IdentError::Setting {
                name: name.into(),
                message,
            })
        };
        if self.irls_iterations > Self::MAX_IRLS_ITERATIONS {
            return setting(
                Setting::IrlsIterations,
                format!(
                    "at most {} re-weighting passes, got {} (the weights settle in a handful)",
                    Self::MAX_IRLS_ITERATIONS,
                    self.irls_iterations
                ),
            );
        }
        let r = self.sdp_regularization;
        if !(r.is_finite() && (0.0..=Self::MAX_SDP_REGULARIZATION).contains(&r)) {
            return setting(
                Setting::SdpRegularization,
                format!(
                    "must be in [0, {}] (relative to the data), got {}",
                    Self::MAX_SDP_REGULARIZATION,
                    dvrk_model::input::show(r)
                ),
            );
        }
        Ok(())
    }

    /// The model these settings fit: `model` itself, or a copy with the Stribeck terms
    /// of [`FitSettings::stribeck_velocity`], the Dahl friction of
    /// [`FitSettings::dahl_sigma`], the position torques of
    /// [`FitSettings::position_torque_order`], the load friction of
    /// [`FitSettings::load_friction`], the gravity of
    /// [`FitSettings::mounting_pitch_deg`] and the bounds of [`FitSettings::bounds`].
    /// Everything that reads a result back (validate, report, export) goes through here
    /// so the parameters line up.
    pub fn model<'m>(&self, model: &'m Model) -> Result<std::borrow::Cow<'m, Model>, IdentError> {
        let mut m = match self.stribeck_velocity {
            // A model that has its Stribeck terms already (e.g. a result's own model) is
            // used as it is.
            Some(v) => match model.with_stribeck(v)? {
                extended if extended.n_params() != model.n_params() => {
                    std::borrow::Cow::Owned(extended)
                }
                _ => std::borrow::Cow::Borrowed(model),
            },
            None => std::borrow::Cow::Borrowed(model),
        };
        if let Some(sigma) = self.dahl_sigma {
            // As for Stribeck: a model with its Dahl elements already is kept.
            let extended = m.with_dahl(sigma)?;
            if extended.n_params() != m.n_params() {
                m = std::borrow::Cow::Owned(extended);
            }
        }
        if let Some(order) = self.position_torque_order {
            // As for Stribeck: a model with its position torques already is kept.
            let extended = m.with_position_torque_on(order, &self.position_torque_frames)?;
            if extended.n_params() != m.n_params() {
                m = std::borrow::Cow::Owned(extended);
            }
        }
        if self.load_friction {
            // As for Stribeck: a model with its load friction already is kept.
            let extended = m.with_load_friction();
            if extended.n_params() != m.n_params() {
                m = std::borrow::Cow::Owned(extended);
            }
        }
        if let Some(pitch) = self.mounting_pitch_deg {
            let gravity =
                Model::mounting_pitch_gravity(pitch).map_err(|e| IdentError::Setting {
                    name: crate::options::Setting::MountingPitch.into(),
                    message: e.to_string(),
                })?;
            if m.gravity != gravity {
                m.to_mut().gravity = gravity;
            }
        }
        if let Some(set) = self.bounds {
            // The set's sign bounds; the description's `pseudo_inertia_eps` stays.
            let wanted = dvrk_model::GlobalBounds {
                pseudo_inertia_eps: m.bounds.pseudo_inertia_eps,
                ..set.bounds()
            };
            if m.bounds != wanted {
                m.to_mut().bounds = wanted;
            }
        }
        Ok(m)
    }
}

/// A leaf of two documents (two results' settings) whose values differ: its place,
/// e.g. `processing.filter.cutoff_hz`, and both values (`null` where one has none).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Difference {
    /// The leaf's place: object keys joined by `.`, array positions as `[i]`.
    pub path: String,
    /// Its value in the first document.
    pub a: serde_json::Value,
    /// Its value in the second.
    pub b: serde_json::Value,
}

impl Difference {
    /// Both values as a reader wants them: a name without JSON quotes, `none` for an
    /// unset setting, numbers and lists as JSON writes them.
    ///
    /// ```
    /// use dvrk_ident::Difference;
    /// let d = Difference { path: "joints".into(), a: "measured".into(), b: serde_json::Value::Null };
    /// assert_eq!(d.shown(), ("measured".to_string(), "none".to_string()));
    /// ```
    pub fn shown(&self) -> (String, String) {
        let show = |v: &serde_json::Value| match v {
            serde_json::Value::String(s) => s.clone(),
            serde_json::Value::Null => "none".into(),
            other => other.to_string(),
        };
        (show(&self.a), show(&self.b))
    }
}

impl FitSettings {
    /// Every setting of `self` (`a`) that differs from `other` (`b`): walked over the
    /// serialized documents, so a setting added later is compared without code here.
    /// What `validate` prints when its flags change the fit's processing, and what
    /// `compare` lists.
    ///
    /// ```rust
    /// use dvrk_ident::FitSettings;
    /// let fit = FitSettings::default();
    /// let mut other = fit.clone();
    /// other.processing.trim = 20;
    /// let d = other.differences(&fit);
    /// assert_eq!(d.len(), 1);
    /// assert_eq!((d[0].path.as_str(), d[0].a.as_u64(), d[0].b.as_u64()), ("processing.trim", Some(20), Some(200)));
    /// assert!(fit.differences(&fit).is_empty());
    /// ```
    pub fn differences(&self, other: &FitSettings) -> Vec<Difference> {
        let value = |s: &FitSettings| serde_json::to_value(s).unwrap_or_default();
        json_differences(&value(self), &value(other))
    }
}

/// Every leaf where `a` and `b` differ, walked together: objects key by key (a missing
/// key is `null`, as an unset optional setting), arrays of the same length element by
/// element; anything else that differs is one leaf.
pub fn json_differences(a: &serde_json::Value, b: &serde_json::Value) -> Vec<Difference> {
    let mut out = Vec::new();
    walk("", a, b, &mut out);
    out
}

fn walk(path: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<Difference>) {
    use serde_json::Value;
    let join = |key: &str| {
        if path.is_empty() {
            key.to_string()
        } else {
            format!("{path}.{key}")
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys = x.keys().chain(y.keys().filter(|k| !x.contains_key(*k)));
            for k in keys {
                let (va, vb) = (
                    x.get(k).unwrap_or(&Value::Null),
                    y.get(k).unwrap_or(&Value::Null),
                );
                walk(&join(k), va, vb, out);
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (va, vb)) in x.iter().zip(y).enumerate() {
                walk(&format!("{path}[{i}]"), va, vb, out);
            }
        }
        _ if a != b => out.push(Difference {
            path: path.to_string(),
            a: a.clone(),
            b: b.clone(),
        }),
        _ => {}
    }
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            method: Method::default(),
            processing: Processing::default(),
            test_window: None,
            irls_iterations: 5,
            sdp_regularization: SdpOptions::default().regularization,
            stribeck_velocity: None,
            dahl_sigma: None,
            position_torque_order: None,
            position_torque_frames: Vec::new(),
            load_friction: false,
            mounting_pitch_deg: None,
            bounds: None,
            ellipsoids: true,
            delay_search_s: None,
            prior: None,
            joints: Joints::Model,
            log_offsets: false,
            select: None,
        }
    }
}

/// Serde's `skip_serializing_if` for a field whose default is `true`.
fn is_true(b: &bool) -> bool {
    *b
}

// The friction models `--select` chooses from (fit::select runs the choice).

/// The Stribeck velocity of a candidate named `stribeck` without a value, rad/s or m/s
/// (the dVRK preset's).
pub const DEFAULT_STRIBECK: f64 = 0.3;

/// The Dahl stiffness of a candidate named `dahl` without a value, 1/rad or 1/m (the
/// dVRK preset's).
pub const DEFAULT_DAHL: f64 = 20.0;

/// One candidate friction model: the description's Coulomb, viscous and offset friction
/// (`coulomb`), with a Stribeck term, Dahl friction, or both. Every other setting is the
/// fit's own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The Stribeck velocity (rad/s or m/s), as `stribeck_velocity`.
    pub stribeck_velocity: Option<f64>,
    /// The Dahl stiffness (1/rad or 1/m), as `dahl_sigma`.
    pub dahl_sigma: Option<f64>,
}

impl Candidate {
    /// The candidate's name: `coulomb`, or its terms joined by `+` (`stribeck`,
    /// `dahl:10`, `stribeck:0.2+dahl`), a value shown when it is not the default.
    pub fn name(&self) -> String {
        let term = |what: &str, v: Option<f64>, default: f64| {
            v.map(|v| match v == default {
                true => what.to_string(),
                false => format!("{what}:{v}"),
            })
        };
        let terms: Vec<String> = [
            term("stribeck", self.stribeck_velocity, DEFAULT_STRIBECK),
            term("dahl", self.dahl_sigma, DEFAULT_DAHL),
        ]
        .into_iter()
        .flatten()
        .collect();
        match terms.is_empty() {
            true => "coulomb".into(),
            false => terms.join("+"),
        }
    }

    /// `settings` with this candidate's friction terms (and no selection).
    pub fn settings(&self, settings: &FitSettings) -> FitSettings {
        FitSettings {
            stribeck_velocity: self.stribeck_velocity,
            dahl_sigma: self.dahl_sigma,
            select: None,
            ..settings.clone()
        }
    }
}

impl std::str::FromStr for Candidate {
    type Err = ValueError;

    /// `coulomb`, or `+`-joined terms `stribeck[:VS]` and `dahl[:SIGMA]`.
    fn from_str(s: &str) -> Result<Self, ValueError> {
        let mut c = Candidate {
            stribeck_velocity: None,
            dahl_sigma: None,
        };
        if s == "coulomb" {
            return Ok(c);
        }
        for term in s.split('+') {
            let (what, value) = match term.split_once(':') {
                Some((w, v)) => (w, Some(v)),
                None => (term, None),
            };
            let value = |default: f64| -> Result<f64, ValueError> {
                let Some(v) = value else { return Ok(default) };
                match v.parse::<f64>() {
                    Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
                    _ => Err(ValueError::CandidateValue {
                        candidate: s.to_string(),
                        term: what.to_string(),
                        value: v.to_string(),
                    }),
                }
            };
            let slot = match what {
                "stribeck" => (&mut c.stribeck_velocity, value(DEFAULT_STRIBECK)?),
                "dahl" => (&mut c.dahl_sigma, value(DEFAULT_DAHL)?),
                _ => {
                    return Err(ValueError::UnknownCandidateTerm {
                        candidate: s.to_string(),
                        term: term.to_string(),
                    })
                }
            };
            if slot.0.replace(slot.1).is_some() {
                return Err(ValueError::TermTwice {
                    candidate: s.to_string(),
                    term: what.to_string(),
                });
            }
        }
        Ok(c)
    }
}

/// The candidates of a selection, in the order given (ties go to the earlier).
///
/// ```rust
/// use dvrk_ident::Candidates;
///
/// let builtin: Candidates = "builtin".parse().unwrap();
/// assert_eq!(builtin.to_string(), "coulomb,stribeck,dahl,stribeck+dahl");
/// let mine: Candidates = "coulomb,stribeck:0.2+dahl:10".parse().unwrap();
/// assert_eq!(mine.0[1].stribeck_velocity, Some(0.2));
/// assert!("coulomb".parse::<Candidates>().is_err()); // nothing to choose from
/// assert!("coulomb,coulomb".parse::<Candidates>().is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Candidates(pub Vec<Candidate>);

impl Candidates {
    /// The built-in list: Coulomb + viscous, + Stribeck (0.3 rad/s), + Dahl (20/rad),
    /// + both (the dVRK preset's friction), simplest first.
    pub fn builtin() -> Candidates {
        let c = |s: Option<f64>, d: Option<f64>| Candidate {
            stribeck_velocity: s,
            dahl_sigma: d,
        };
        let (s, d) = (Some(DEFAULT_STRIBECK), Some(DEFAULT_DAHL));
        Candidates(vec![c(None, None), c(s, None), c(None, d), c(s, d)])
    }
}

impl std::str::FromStr for Candidates {
    type Err = ValueError;

    /// `builtin`, or candidate names separated by commas (at least two, distinct).
    fn from_str(s: &str) -> Result<Self, ValueError> {
        if s == "builtin" {
            return Ok(Candidates::builtin());
        }
        let list = s
            .split(',')
            .map(|c| c.trim().parse())
            .collect::<Result<Vec<Candidate>, ValueError>>()?;
        if list.len() < 2 {
            return Err(ValueError::TooFewCandidates(s.to_string()));
        }
        for (i, c) in list.iter().enumerate() {
            if list[..i].contains(c) {
                return Err(ValueError::CandidateTwice {
                    list: s.to_string(),
                    candidate: c.name(),
                });
            }
        }
        Ok(Candidates(list))
    }
}

impl std::fmt::Display for Candidates {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self.0.iter().map(Candidate::name).collect();
        f.write_str(&names.join(","))
    }
}

/// As the flag reads: the names joined by commas.
impl Serialize for Candidates {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// The flag's text, a list of names, or `true` (the built-in list).
impl<'de> Deserialize<'de> for Candidates {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(s) => s.parse().map_err(D::Error::custom),
            serde_json::Value::Bool(true) => Ok(Candidates::builtin()),
            serde_json::Value::Array(a) => {
                let names: Option<Vec<&str>> = a.iter().map(|v| v.as_str()).collect();
                match names {
                    Some(n) => n.join(",").parse().map_err(D::Error::custom),
                    None => Err(D::Error::custom("expected candidate names")),
                }
            }
            _ => Err(D::Error::custom(
                "expected `builtin` (or true), or candidate names (a list, or joined by commas)",
            )),
        }
    }
}
