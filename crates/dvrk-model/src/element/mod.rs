//! A frame's elements: what acts on its joint value besides the links — friction (with
//! an optional Stribeck term), a motor inertia, a spring, a known force, a quadratic viscous
//! friction, a monotone friction, a Dahl friction, a position-dependent torque, a load-dependent Coulomb friction. Each is a value of [`Element`], and each variant's module holds everything
//! about it: its parameters (names, kinds, unit classes), its regressor columns, its
//! torque, its share of the mass matrix, its nominal values, its bounds for the
//! physically consistent fit, its consistency test and its export notes. Its description
//! syntax is read in `description/elements.rs`, with the rest of what the `description`
//! feature compiles, into the [`ElementSpec`] a model built from numbers takes, so a
//! controller without that feature builds the same elements. The model, the estimator,
//! the result and the exports iterate over [`Frame::elements`](crate::Frame::elements)
//! and call these, as Pinocchio's algorithms visit joint models; an enum rather than
//! trait objects keeps the per-sample loops free of allocation and indirect calls (one
//! `match` per element).
//!
//! A new element is one module implementing [`Law`], plus its variant in [`Element`]
//! (and the `each!` dispatch below), its variant in [`ElementSpec`] (the numeric
//! constructor's) and its description field in `description/elements.rs`.

/// [`Law::add_torque`] and [`Law::add_static`] of an element whose torque is a function of
/// the position alone, its `push(value, q, params, tau)`: the same torque in motion as
/// held at rest, whatever the direction of the next motion.
macro_rules! position_law {
    () => {
        #[inline(always)]
        fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
            self.push(s.value, s.q, params, tau);
        }

        #[inline(always)]
        fn add_static(&self, value: &Affine, q: &[f64], _: f64, params: &[f64], tau: &mut [f64]) {
            self.push(value, q, params, tau);
        }
    };
}

mod dahl;
mod friction;
mod known_force;
mod load_friction;
mod monotone_friction;
mod motor_inertia;
mod position_torque;
mod quadratic_viscous;
mod spring;
mod stribeck;

use crate::error::ModelError;
use crate::expr::Affine;
use crate::param::{FrameBounds, GlobalBounds, Nominal, Param, ParamKind};

pub use dahl::Dahl;
pub use friction::Friction;
pub use known_force::KnownForce;
pub use load_friction::{LoadFriction, MAX_LOAD_RATIO};
pub use monotone_friction::MonotoneFriction;
pub use motor_inertia::MotorInertia;
pub use position_torque::PositionTorque;
pub use quadratic_viscous::QuadraticViscous;
pub use spring::{Deflection, Spring};
pub use stribeck::Stribeck;

/// One sample as an element sees it: the joint value `s = a·q + b` of its frame and the
/// coordinates' positions, rates and accelerations (rad or m, per s, per s²).
#[derive(Clone, Copy)]
pub struct Sample<'a> {
    /// The frame's joint value `s = a·q + b` (rad or m), whose coefficients `a` map the
    /// element's force into the coordinates.
    pub value: &'a Affine,
    /// Coordinate positions (rad or m).
    pub q: &'a [f64],
    /// Coordinate rates (rad/s or m/s).
    pub dq: &'a [f64],
    /// Coordinate accelerations (rad/s² or m/s²).
    pub ddq: &'a [f64],
    /// Hysteresis states (dimensionless) indexed by parameter column: a
    /// [`Dahl`] element reads its `z` at its `Fd`'s index (the
    /// [`Workspace`](crate::Workspace)'s, advanced by
    /// [`Model::advance_hysteresis`](crate::Model::advance_hysteresis)).
    pub hysteresis: &'a [f64],
    /// Each coordinate's load (N·m or N, `≥ 0`): the magnitude of its measured torque
    /// ([`Model::set_load`](crate::Model::set_load)) or of the predicted one
    /// ([`Model::loaded_inverse_dynamics`](crate::Model::loaded_inverse_dynamics)), read
    /// by a [`LoadFriction`] element.
    pub load: &'a [f64],
}

/// What an export's note on an element names: the parameter values and names, the
/// coordinates, the frame's name and its joint value as text.
pub struct Note<'a> {
    /// The whole parameter vector (SI units per parameter kind).
    pub params: &'a [f64],
    /// Names and kinds of the parameters, indexed like `params`.
    pub names: &'a [Param],
    /// The model's coordinate names, for writing expressions.
    pub coordinates: &'a [String],
    /// Name of the frame the element is on.
    pub frame: &'a str,
    /// The frame's joint value as an expression text (e.g. `q2 - q3`), what the element
    /// acts along.
    pub on: &'a str,
}

/// `sign` with `sign(0) = 0` (numpy's convention, used by the 2019 package), so that a
/// joint at rest gets no Coulomb force.
#[inline]
pub fn sign0(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// What the physically consistent fit may assume of an element's parameters.
#[derive(Clone, Copy)]
pub struct BoundsContext<'a> {
    /// Lower bounds of every element (the model's [`GlobalBounds`]).
    pub global: &'a GlobalBounds,
    /// The frame's own bounds (maxima, ranges).
    pub frame: &'a FrameBounds,
    /// `false` ignores the frame's bounds (`SdpOptions::override_bounds`), keeping the
    /// global and physical ones.
    pub use_frame: bool,
}

/// Where a bound comes from, for messages: a global lower bound, a field of the frame's
/// `bounds`, or a physical constraint of the element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundOrigin {
    /// A field of the model's [`GlobalBounds`], e.g. `fc_min`.
    Global(&'static str),
    /// A field of the frame's bounds, e.g. `fc_max`.
    Frame(&'static str),
    /// A constraint of the element itself, e.g. `Fc + Fs ≥ 0`.
    Physical(&'static str),
}

/// One linear bound `Σ a·π ≤ limit` of the physically consistent fit (`limit = +∞` is
/// no bound).
#[derive(Clone, Debug, PartialEq)]
pub struct BoundRow {
    /// `(parameter index, coefficient)` pairs. The first is the parameter the row
    /// bounds, the others set where ([`BoundRow::bound_on_first`]): `l` before `m` in a
    /// centre-of-mass row `m·r_min ≤ l`, `Fs` before `Fc` in `Fc + Fs ≥ 0`.
    pub coefficients: Vec<(usize, f64)>,
    /// Right-hand side of the bound, in the unit of the combination (`+∞`: no bound).
    pub limit: f64,
    /// Which field or constraint the bound comes from, so messages can name it.
    pub origin: BoundOrigin,
}

impl BoundRow {
    /// `lo ≤ π[k]`.
    pub fn at_least(k: usize, lo: f64, origin: BoundOrigin) -> BoundRow {
        BoundRow {
            coefficients: vec![(k, -1.0)],
            limit: -lo,
            origin,
        }
    }

    /// `π[k] ≤ hi`.
    pub fn at_most(k: usize, hi: f64, origin: BoundOrigin) -> BoundRow {
        BoundRow {
            coefficients: vec![(k, 1.0)],
            limit: hi,
            origin,
        }
    }

    /// The rows of a parameter bounded on its own: `lo ≤ π[k]` and, when `hi` is given,
    /// `π[k] ≤ hi`, each bound with its origin.
    pub fn interval(
        k: usize,
        lo: (f64, BoundOrigin),
        hi: Option<(f64, BoundOrigin)>,
        rows: &mut Vec<BoundRow>,
    ) {
        rows.push(BoundRow::at_least(k, lo.0, lo.1));
        if let Some((hi, origin)) = hi {
            rows.push(BoundRow::at_most(k, hi, origin));
        }
    }

    /// The bound the row puts on its first parameter `k` given the others' values in
    /// `params`: `(k, b, Side::Upper)` for `π[k] ≤ b`, `(k, b, Side::Lower)` for
    /// `π[k] ≥ b` (`b = (limit − Σ_{j>0} aⱼ·πⱼ) / a₀`). `None` for no bound: an infinite
    /// limit, a zero first coefficient or a non-finite `b`.
    pub fn bound_on_first(&self, params: &[f64]) -> Option<(usize, f64, Side)> {
        let (&(k, a0), rest) = self.coefficients.split_first()?;
        if a0 == 0.0 || !self.limit.is_finite() {
            return None;
        }
        let others: f64 = rest.iter().map(|&(j, a)| a * params[j]).sum();
        let b = (self.limit - others) / a0;
        let side = if a0 > 0.0 { Side::Upper } else { Side::Lower };
        b.is_finite().then_some((k, b, side))
    }
}

/// Which side of a parameter a bound is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// `π ≥ bound`.
    Lower,
    /// `π ≤ bound`.
    Upper,
}

/// Moves `v` onto `[lo, hi]` when it misses by at most `1e-6·max(1, |bound|)` (a
/// solver's feasibility tolerance): a larger miss is left visible.
pub(crate) fn clamp_near(v: &mut f64, lo: f64, hi: Option<f64>) {
    if let Some(hi) = hi.filter(|&hi| hi >= lo) {
        if *v > hi && near(*v, hi) {
            *v = hi;
        }
    }
    if *v < lo && near(*v, lo) {
        *v = lo;
    }
}

/// `v` within `1e-6·max(1, |bound|)` of `bound`.
pub(crate) fn near(v: f64, bound: f64) -> bool {
    (v - bound).abs() <= 1e-6 * bound.abs().max(1.0)
}

/// What an element is and does; implemented by each variant of [`Element`], in its
/// module. Parameters of an element are consecutive columns from [`Law::first`].
pub(crate) trait Law {
    /// Names of the element in summaries (`friction`, `spring`...; a friction with a
    /// Stribeck term is both `friction` and `stribeck`).
    fn labels(&self) -> &'static [&'static str];
    /// Each parameter's column, name prefix (the frame index follows: `Fc3`) and kind,
    /// in the order the element adds them to the parameter vector.
    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>);
    /// Adds the element's regressor columns of one sample into `out` (row-major, `p`
    /// columns per coordinate).
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]);
    /// Adds the element's generalized force (its part of `H·π`) into `tau`.
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]);
    /// Whether the torque is an acceleration term, which forward dynamics moves into
    /// the mass matrix ([`Law::add_mass`]) instead.
    #[inline(always)]
    fn inertial(&self) -> bool {
        false
    }
    /// Adds the element's share of the mass matrix (`n×n`, column-major).
    #[inline(always)]
    fn add_mass(&self, _params: &[f64], _n: usize, _out: &mut [f64]) {}
    /// Adds what the element holds at rest at `q` when the motion starts in the
    /// direction of sign `onset` along its frame's joint value (`0`: at rest).
    #[inline(always)]
    fn add_static(
        &self,
        _value: &Affine,
        _q: &[f64],
        _onset: f64,
        _params: &[f64],
        _tau: &mut [f64],
    ) {
    }
    /// Adds a known (not identified) generalized force, e.g. a cable.
    fn add_known(&self, _q: &[f64], _tau: &mut [f64]) {}
    /// Writes the nominal values of the parameters into `pi`; `None` if one is unknown.
    fn nominal(&self, nominal: &Nominal, pi: &mut [f64]) -> Option<()>;
    /// The bounds of the physically consistent fit.
    fn bound_rows(&self, _b: &BoundsContext, _rows: &mut Vec<BoundRow>) {}
    /// Moves parameters that miss their bounds by a solver's tolerance onto them.
    fn clamp(&self, _b: &BoundsContext, _params: &mut [f64]) {}
    /// The element's sign conditions, to `tol` (negative: the rounding allowed).
    fn consistent(&self, _params: &[f64], _tol: f64) -> bool {
        true
    }
    /// A sentence for the exports that cannot hold the element (URDF), or `None`.
    fn note(&self, _n: &Note) -> Option<String> {
        None
    }
    /// Numbers and words that make the element's regressor, for model hashes.
    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>);
    /// The 2019 package's `params.json` fields (`Fc Fv Fo Im K`) it fills.
    fn wpi_fields(&self, _params: &[f64]) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// The column that is `sign(ṡ)` along the frame's joint value, which a smooth
    /// optimizer replaces by a smooth step.
    fn sign_column(&self) -> Option<usize> {
        None
    }
    /// The element's line in a description file (`robots/README.md`).
    fn description(&self, coordinates: &[String]) -> String;
}

/// One element of a frame (see the module documentation).
#[derive(Clone, Debug)]
pub enum Element {
    /// Coulomb, viscous and offset friction, with an optional Stribeck term.
    Friction(Friction),
    /// A motor (rotor) inertia reflected onto one coordinate.
    MotorInertia(MotorInertia),
    /// A linear spring on a (possibly nonlinear) deflection.
    Spring(Spring),
    /// A known force without parameters (e.g. the MTM's cable polynomial), subtracted
    /// before a fit.
    KnownForce(KnownForce),
    /// Friction quadratic in the joint rate.
    QuadraticViscous(QuadraticViscous),
    /// Monotone friction: saturating steps of several widths, forward and backward.
    MonotoneFriction(MonotoneFriction),
    /// Dahl friction: rate-independent hysteresis with a state carried along the path.
    Dahl(Dahl),
    /// A position-dependent torque: a Fourier series in the joint value.
    PositionTorque(PositionTorque),
    /// Coulomb friction proportional to the coordinate's measured torque (its load).
    LoadFriction(LoadFriction),
}

/// Runs `$body` with `$e` bound to the variant's value.
macro_rules! each {
    ($self:expr, $e:ident => $body:expr) => {
        match $self {
            Element::Friction($e) => $body,
            Element::MotorInertia($e) => $body,
            Element::Spring($e) => $body,
            Element::KnownForce($e) => $body,
            Element::QuadraticViscous($e) => $body,
            Element::MonotoneFriction($e) => $body,
            Element::Dahl($e) => $body,
            Element::PositionTorque($e) => $body,
            Element::LoadFriction($e) => $body,
        }
    };
}

impl Element {
    /// Names in summaries: `friction` (and `stribeck`), `motor_inertia`, `spring`,
    /// `known_force`, `quadratic_viscous`, `monotone_friction`, `dahl`, `position_torque`, `load_friction`.
    pub fn labels(&self) -> &'static [&'static str] {
        each!(self, e => e.labels())
    }

    /// The element's parameter columns.
    pub fn columns(&self) -> Vec<usize> {
        let mut out = Vec::new();
        each!(self, e => e.columns(&mut out));
        out.into_iter().map(|(c, _, _)| c).collect()
    }

    /// The parameters of this element on frame `frame` (names in the 2019 convention),
    /// in column order.
    pub fn params(&self, frame: usize) -> Vec<Param> {
        let mut out = Vec::new();
        each!(self, e => e.columns(&mut out));
        out.into_iter()
            .map(|(_, prefix, kind)| Param {
                name: format!("{prefix}{frame}"),
                kind,
                frame,
            })
            .collect()
    }

    /// Adds the regressor columns of one sample into `out` (row-major, `p` columns).
    #[inline(always)]
    pub fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        each!(self, e => e.add_regressor(s, p, out))
    }

    /// Adds the element's part of `H·π` into `tau` (N·m or N).
    #[inline(always)]
    pub fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        each!(self, e => e.add_torque(s, params, tau))
    }

    /// Whether the torque is an acceleration term (in the mass matrix instead).
    #[inline(always)]
    pub fn inertial(&self) -> bool {
        each!(self, e => e.inertial())
    }

    /// Adds the element's share of the mass matrix (`n×n`, column-major).
    #[inline(always)]
    pub fn add_mass(&self, params: &[f64], n: usize, out: &mut [f64]) {
        each!(self, e => e.add_mass(params, n, out))
    }

    /// Adds the static torque at `q` for a motion starting with sign `onset` along the
    /// frame's joint value `value` (see `Model::static_torque`).
    #[inline(always)]
    pub fn add_static(
        &self,
        value: &Affine,
        q: &[f64],
        onset: f64,
        params: &[f64],
        tau: &mut [f64],
    ) {
        each!(self, e => e.add_static(value, q, onset, params, tau))
    }

    /// Adds a known generalized force (not identified: the MTM's cable) into `tau`.
    #[inline(always)]
    pub fn add_known(&self, q: &[f64], tau: &mut [f64]) {
        each!(self, e => e.add_known(q, tau))
    }

    /// Whether the element is a known force.
    pub fn is_known(&self) -> bool {
        matches!(self, Element::KnownForce(_))
    }

    /// Writes the nominal parameter values from the frame's `nominal` into `pi`; `None`
    /// when one is missing.
    pub fn nominal(&self, nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        each!(self, e => e.nominal(nominal, pi))
    }

    /// Appends the linear bounds of the physically consistent fit.
    pub fn bound_rows(&self, b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        each!(self, e => e.bound_rows(b, rows))
    }

    /// Moves parameters within `1e-6·max(1, |bound|)` outside their bounds onto them.
    pub fn clamp(&self, b: &BoundsContext, params: &mut [f64]) {
        each!(self, e => e.clamp(b, params))
    }

    /// The element's physical sign conditions, to `tol` (e.g. `Fc ≥ tol`).
    pub fn consistent(&self, params: &[f64], tol: f64) -> bool {
        each!(self, e => e.consistent(params, tol))
    }

    /// The note an export that cannot hold this element writes, or `None`.
    pub fn note(&self, n: &Note) -> Option<String> {
        each!(self, e => e.note(n))
    }

    /// Numbers and words that make the element's regressor (model hashes).
    pub fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        each!(self, e => e.fingerprint(numbers, words))
    }

    /// Its fields of the 2019 `params.json` layout (`Fc Fv Fo Im K`).
    pub fn wpi_fields(&self, params: &[f64]) -> Vec<(&'static str, f64)> {
        each!(self, e => e.wpi_fields(params))
    }

    /// The column that is `sign(ṡ)` along the frame's joint value, if any.
    pub fn sign_column(&self) -> Option<usize> {
        each!(self, e => e.sign_column())
    }

    /// The element's line in a description file, e.g. `friction = true`.
    pub fn description(&self, coordinates: &[String]) -> String {
        each!(self, e => e.description(coordinates))
    }
}

/// An element as the numeric constructor ([`ModelBuilder`](crate::ModelBuilder)) takes
/// it: what a description's element fields say, in numbers. Its parameters are
/// allocated by the constructor (names `Fc{i}`, `Ia{i}`... of the frame's index `i`).
#[derive(Clone, Debug)]
pub enum ElementSpec {
    /// Coulomb, viscous and offset friction (`Fc Fv Fo`), with a Stribeck term of this
    /// velocity (rad/s or m/s, positive) when given (its `Fs` comes after every other
    /// parameter, as [`Model::with_stribeck`](crate::Model::with_stribeck) adds it).
    Friction {
        /// Stribeck velocity (rad/s or m/s), or no Stribeck term.
        stribeck_velocity: Option<f64>,
    },
    /// A motor inertia `Ia`: the frame's joint value must be one coordinate's multiple.
    MotorInertia,
    /// A spring `K` on this deflection (m or rad).
    Spring(Deflection),
    /// A known force: the polynomial's coefficients, highest degree first (N·m or N),
    /// along an affine function of the coordinates (`None`: the frame's joint value).
    KnownForce {
        /// What the force acts along (rad or m); `None` for the frame's joint value.
        along: Option<Affine>,
        /// Coefficients, highest degree first (N·m or N).
        polynomial: Vec<f64>,
    },
    /// Quadratic viscous friction `Fq` with its nominal value and upper bound
    /// (N·m·s²/rad² or N·s²/m²).
    QuadraticViscous {
        /// Nominal `Fq` (`None`: 0).
        nominal: Option<f64>,
        /// Upper bound of `Fq` for the physically consistent fit.
        max: Option<f64>,
    },
    /// Monotone friction with steps of these velocities (rad/s or m/s; 1 to 4,
    /// positive, increasing).
    MonotoneFriction {
        /// The steps' velocities (rad/s or m/s).
        velocities: Vec<f64>,
    },
    /// Dahl friction `Fd` with this stiffness `σ` (1/rad or 1/m, positive).
    Dahl {
        /// `σ` (1/rad or 1/m).
        sigma: f64,
    },
    /// A position-dependent torque: a Fourier series of this order (1 to 3) and period
    /// (rad or m; `None`: one turn, 2π, on a revolute frame) in the joint value.
    PositionTorque {
        /// The series' order.
        order: usize,
        /// The series' period (rad or m).
        period: Option<f64>,
    },
    /// Load-dependent Coulomb friction `Fl`: the frame's joint value must be one
    /// coordinate's multiple, whose measured torque is the load.
    LoadFriction,
}

/// The frame an element is built for.
pub(crate) struct FrameContext<'a> {
    /// The description file or the numeric model's source, for messages.
    pub file: &'a str,
    /// `frame 3 (name)`, for messages.
    pub place: &'a str,
    pub index: usize,
    pub value: &'a Affine,
    pub moving: bool,
    /// Whether the frame turns (its joint value is an angle, rad) rather than slides (m).
    pub revolute: bool,
    /// Number of coordinates of the model.
    pub n_coordinates: usize,
}

impl FrameContext<'_> {
    pub(crate) fn error(&self, field: &str, message: impl std::fmt::Display) -> ModelError {
        ModelError::field(self.file, self.place, field, message)
    }

    /// Errors unless the frame moves: friction, springs... act along its joint value.
    pub(crate) fn need_motion(&self, field: &str) -> Result<(), ModelError> {
        if self.moving {
            Ok(())
        } else {
            Err(self.error(
                field,
                "needs a moving frame (theta or d depending on the coordinates)",
            ))
        }
    }
}

/// A frame's elements as built: the elements, with their parameters pushed.
#[derive(Default)]
pub(crate) struct FrameElements {
    pub elements: Vec<Element>,
    /// Stribeck velocity (rad/s or m/s): the term is added after every frame, its `Fs`
    /// parameter last, as `Model::with_stribeck` adds it.
    pub stribeck_velocity: Option<f64>,
}

impl FrameElements {
    /// Adds `e`, pushing its parameters onto `params`.
    fn push(&mut self, fx: &FrameContext, e: Element, params: &mut Vec<Param>) {
        params.extend(e.params(fx.index));
        self.elements.push(e);
    }
}

impl ElementSpec {
    /// Checks the element against its frame and adds it to `out`, its parameters to
    /// `params`.
    pub(crate) fn build(
        &self,
        fx: &FrameContext,
        params: &mut Vec<Param>,
        out: &mut FrameElements,
    ) -> Result<(), ModelError> {
        match self {
            ElementSpec::Friction { stribeck_velocity } => {
                let f = Friction::on(fx, params.len())?;
                if let Some(v) = stribeck_velocity {
                    out.stribeck_velocity = Some(Stribeck::check_velocity(fx, *v)?);
                }
                out.push(fx, Element::Friction(f), params);
            }
            ElementSpec::MotorInertia => {
                let m = MotorInertia::on(fx, params.len())?;
                out.push(fx, Element::MotorInertia(m), params);
            }
            ElementSpec::Spring(d) => {
                let s = Spring::on(fx, d.clone(), params.len())?;
                out.push(fx, Element::Spring(s), params);
            }
            ElementSpec::KnownForce { along, polynomial } => {
                let k = KnownForce::on(fx, along.clone(), polynomial)?;
                out.push(fx, Element::KnownForce(k), params);
            }
            ElementSpec::QuadraticViscous { nominal, max } => {
                let q = QuadraticViscous::on(fx, *nominal, *max, params.len())?;
                out.push(fx, Element::QuadraticViscous(q), params);
            }
            ElementSpec::MonotoneFriction { velocities } => {
                let f = MonotoneFriction::on(fx, velocities, params.len())?;
                out.push(fx, Element::MonotoneFriction(f), params);
            }
            ElementSpec::Dahl { sigma } => {
                let d = Dahl::on(fx, *sigma, params.len())?;
                out.push(fx, Element::Dahl(d), params);
            }
            ElementSpec::PositionTorque { order, period } => {
                let t = PositionTorque::on(fx, *order, *period, params.len())?;
                out.push(fx, Element::PositionTorque(t), params);
            }
            ElementSpec::LoadFriction => {
                let l = LoadFriction::on(fx, params.len())?;
                out.push(fx, Element::LoadFriction(l), params);
            }
        }
        Ok(())
    }
}
