//! The parameter layout (names, kinds) and what a description says of a frame's
//! parameters: nominal values and bounds. A leaf module: the model, its elements and the
//! estimators all read these.

/// The kind of a parameter, for estimators that treat them differently (bounds, LMIs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    /// One of the 10 barycentric link parameters; `index` 0..10 in
    /// `[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]`.
    Inertia {
        /// Position in the block of 10 (0..6 inertia about the frame origin, kg·m²; 6..9
        /// first moment, kg·m; 9 mass, kg).
        index: usize,
    },
    /// Coulomb friction `Fc` (N·m or N).
    Coulomb,
    /// Viscous friction `Fv` (N·m·s/rad or N·s/m).
    Viscous,
    /// Constant force offset `Fo` (N·m or N), independent of the motion.
    Offset,
    /// Motor (rotor) inertia `Ia` reflected on a coordinate (kg·m²).
    MotorInertia,
    /// Spring stiffness `K` (N·m or N per unit of deflection, m or rad).
    Spring,
    /// Stribeck friction `Fs` (see [`Stribeck`](crate::Stribeck)).
    Stribeck,
    /// Quadratic viscous friction `Fq` (see [`QuadraticViscous`](crate::QuadraticViscous)).
    QuadraticViscous,
    /// A weight of monotone friction (N·m or N; see
    /// [`MonotoneFriction`](crate::MonotoneFriction)).
    MonotoneFriction,
    /// Dahl friction `Fd` (N·m or N; see [`Dahl`](crate::Dahl)).
    Dahl,
    /// A coefficient of a position-dependent torque (N·m or N; see
    /// [`PositionTorque`](crate::PositionTorque)).
    PositionTorque,
    /// Load-dependent Coulomb friction `Fl`, the ratio of friction to the coordinate's
    /// torque (dimensionless; see [`LoadFriction`](crate::LoadFriction)).
    LoadFriction,
}

impl ParamKind {
    /// The parameter's unit class (estimators scale per class).
    pub fn unit_class(self) -> UnitClass {
        match self {
            ParamKind::Inertia { index } if index < 6 => UnitClass::LinkInertia,
            ParamKind::Inertia { index } if index < 9 => UnitClass::FirstMoment,
            ParamKind::Inertia { .. } => UnitClass::Mass,
            ParamKind::Coulomb
            | ParamKind::Offset
            | ParamKind::Stribeck
            | ParamKind::MonotoneFriction
            | ParamKind::Dahl
            | ParamKind::PositionTorque => UnitClass::Force,
            ParamKind::Viscous => UnitClass::Viscous,
            ParamKind::QuadraticViscous => UnitClass::QuadraticViscous,
            ParamKind::MotorInertia => UnitClass::MotorInertia,
            ParamKind::Spring => UnitClass::Stiffness,
            ParamKind::LoadFriction => UnitClass::Ratio,
        }
    }
}

/// Name, kind and owning frame of one parameter.
#[derive(Clone, Debug)]
pub struct Param {
    /// The name used in reports and descriptions, e.g. `L3xx`, `Fc4`, `m2`.
    pub name: String,
    /// What the parameter is, which decides its unit and the bounds applied to it.
    pub kind: ParamKind,
    /// Frame index (1-based, base = 0).
    pub frame: usize,
}

/// Suffixes of the 10 barycentric parameters, in order.
pub const INERTIA_SUFFIXES: [&str; 10] = ["xx", "xy", "xz", "yy", "yz", "zz", "x", "y", "z", ""];

impl Param {
    /// The 10 link parameters of frame `frame`, named in the 2019 convention:
    /// `L{i}xx … L{i}zz` (inertia about the origin), `l{i}x l{i}y l{i}z`, `m{i}`.
    pub fn inertia_block(frame: usize) -> impl Iterator<Item = Param> {
        INERTIA_SUFFIXES
            .iter()
            .enumerate()
            .map(move |(k, suffix)| Param {
                name: match k {
                    0..=5 => format!("L{frame}{suffix}"),
                    6..=8 => format!("l{frame}{suffix}"),
                    _ => format!("m{frame}"),
                },
                kind: ParamKind::Inertia { index: k },
                frame,
            })
    }
}

/// Prior (nominal) values of one frame's parameters, standard (centre-of-mass) form.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(deny_unknown_fields)
)]
pub struct Nominal {
    /// kg
    pub mass: Option<f64>,
    /// centre of mass in the frame (m)
    pub com: Option<[f64; 3]>,
    /// inertia about the centre of mass, frame axes: xx, xy, xz, yy, yz, zz (kg·m²)
    pub inertia: Option<[f64; 6]>,
    /// Coulomb friction `Fc` (N·m or N).
    pub fc: Option<f64>,
    /// Viscous friction `Fv` (N·m·s/rad or N·s/m).
    pub fv: Option<f64>,
    /// Offset `Fo` (N·m or N).
    pub fo: Option<f64>,
    /// Stribeck friction (N·m or N), for frames with a Stribeck term.
    pub fs: Option<f64>,
    /// Motor inertia `Ia` (kg·m²).
    pub ia: Option<f64>,
    /// Spring stiffness `K` (N·m or N per unit of deflection, m or rad).
    pub k: Option<f64>,
}

/// Per-frame bounds for the physically consistent fit.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(deny_unknown_fields)
)]
pub struct FrameBounds {
    /// kg
    pub mass: Option<[f64; 2]>,
    /// centre of mass box in the frame, per axis [min, max] (m)
    pub com: Option<[[f64; 2]; 3]>,
    /// Upper bound on Coulomb friction `Fc` (N·m or N).
    pub fc_max: Option<f64>,
    /// Upper bound on viscous friction `Fv` (N·m·s/rad or N·s/m).
    pub fv_max: Option<f64>,
    /// Bound on the offset's magnitude, `|Fo| ≤ fo_max` (N·m or N).
    pub fo_max: Option<f64>,
    /// Upper bound on motor inertia `Ia` (kg·m²).
    pub ia_max: Option<f64>,
    /// Spring stiffness range `[min, max]` (N·m or N per unit of deflection).
    pub spring: Option<[f64; 2]>,
    /// A region the link's mass lies in, in the frame (m): the fit keeps
    /// `tr(Q·J) ≥ 0` ([`crate::inertia::Ellipsoid`]) unless asked not to.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub ellipsoid: Option<crate::inertia::Ellipsoid>,
}

/// Lower bounds applied to every element by the physically consistent fit.
///
/// The default is [`GlobalBounds::PHYSICAL`]: friction cannot be negative and a motor
/// has some inertia, and nothing more is known of them a priori. [`GlobalBounds::WANG_2019`] are
/// the bounds of the 2019 fit, kept to reproduce it: they exclude the small wrist
/// friction and motor inertias the real PSM and MTM data ask for.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(deny_unknown_fields, default)
)]
pub struct GlobalBounds {
    /// Coulomb friction, N·m or N
    pub fc_min: f64,
    /// viscous friction, N·m·s/rad or N·s/m
    pub fv_min: f64,
    /// motor inertia, kg·m²
    pub ia_min: f64,
    /// `J ⪰ eps·I` for every link pseudo-inertia (kg·m²)
    pub pseudo_inertia_eps: f64,
}

impl GlobalBounds {
    /// `Fc, Fv ≥ 0`, `Ia ≥ 1e-6`, `J ⪰ 1e-6·I`: the physical constraints. A motor
    /// inertia is kept positive, by the margin of the pseudo-inertias: a coordinate that
    /// moves no link with inertia (the PSM's jaw) has only its motor's, and with `Ia = 0`
    /// the mass matrix would be singular (no forward dynamics).
    pub const PHYSICAL: GlobalBounds = GlobalBounds {
        fc_min: 0.0,
        fv_min: 0.0,
        ia_min: 1e-6,
        pseudo_inertia_eps: 1e-6,
    };

    /// `Fc, Fv, Ia ≥ 0.001`, `J ⪰ 1e-6·I`: the bounds of Wang et al. (RA-L 2019).
    pub const WANG_2019: GlobalBounds = GlobalBounds {
        fc_min: 0.001,
        fv_min: 0.001,
        ia_min: 0.001,
        pseudo_inertia_eps: 1e-6,
    };
}

impl Default for GlobalBounds {
    fn default() -> Self {
        GlobalBounds::PHYSICAL
    }
}

/// Units of a parameter, for estimators that need a scale per unit (the SDP's fallback
/// scale of columns the data never see). Two parameters of one class have the same unit
/// and comparable magnitudes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnitClass {
    /// Link inertia about the frame origin, kg·m².
    LinkInertia,
    /// First moment of mass, kg·m.
    FirstMoment,
    /// Link mass, kg.
    Mass,
    /// A force along the joint value: Coulomb, offset, Stribeck, monotone friction (N·m or N).
    Force,
    /// Viscous friction, N·m·s/rad or N·s/m.
    Viscous,
    /// Quadratic viscous friction, N·m·s²/rad² or N·s²/m².
    QuadraticViscous,
    /// Motor (rotor) inertia, kg·m² (reflected).
    MotorInertia,
    /// Spring stiffness, N·m/rad or N/m (per unit of deflection).
    Stiffness,
    /// A dimensionless ratio: load-dependent friction per unit of load.
    Ratio,
}
