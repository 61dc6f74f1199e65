//! # dvrk-model
//!
//! Numeric rigid-body models of robot arms described as trees of frames whose joint
//! values are affine in the generalized coordinates: closed chains (parallelograms),
//! tendon couplings and motor-side coordinates all become one constant constraint
//! Jacobian `A`. The crate gives kinematics, the parameter-linear regressor
//! `τ = H(q, q̇, q̈)·π`, inverse and forward dynamics, gravity, the mass matrix and the
//! base (identifiable) parameters — in microseconds per sample, where the 2019 dVRK
//! package needed an hour of symbolic algebra per arm.
//!
//! Design, as in Pinocchio: an immutable [`Model`] built once, and a mutable
//! [`Workspace`] reused per sample, so the real-time calls (inverse dynamics, gravity,
//! regressor into a buffer, the momentum observer) allocate nothing. The crate has no
//! dependency on the identification stack and can be embedded in a controller: without
//! its default feature `description` (`default-features = false`) it parses no file (no
//! TOML, URDF, XML or serde) and [`ModelBuilder`] builds the model from numbers.
//!
//! ```
//! use dvrk_model::{Model, Workspace};
//! let model = Model::builtin("psm").unwrap();
//! assert_eq!(model.n_params(), 115);
//! let base = model.base_parameters().unwrap();
//! assert_eq!(base.rank(), 49);
//! let mut ws = Workspace::new(&model);
//! let mut tau = [0.0; 7];
//! let params = vec![0.0; model.n_params()];
//! model.inverse_dynamics(&mut ws, &params, &[0.0; 7], &[0.0; 7], &[0.0; 7], &mut tau);
//! assert_eq!(tau, [0.0; 7]);
//! ```

#![warn(missing_docs)]
// No unsafe code: the workspace's unsafe code is in crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls) and crates/dvrk-model-c (the C ABI).
#![forbid(unsafe_code)]

mod base;
mod builder;
#[cfg(feature = "description")]
mod description;
mod dynamics;
mod element;
mod error;
pub mod expr;
mod hysteresis;
pub mod inertia;
pub mod input;
mod kinematics;
mod limits;
mod load_friction;
mod model;
mod observer;
mod param;
mod payload;
mod regressor;
mod spatial;
mod summary;
mod workspace;

pub use base::BaseParameters;
pub use builder::{Convention, FrameSpec, Joint, ModelBuilder};
pub use dynamics::NotPositiveDefinite;
pub use element::{
    sign0, BoundOrigin, BoundRow, BoundsContext, Dahl, Deflection, Element, ElementSpec, Friction,
    KnownForce, LoadFriction, MonotoneFriction, MotorInertia, Note, PositionTorque,
    QuadraticViscous, Sample, Side, Spring, Stribeck, MAX_LOAD_RATIO,
};
pub use error::ModelError;
pub use expr::{Affine, NumOrExpr};
pub use limits::Limits;
pub use model::*;
pub use observer::{InvalidGain, MomentumObserver};
pub use payload::Payload;
pub use summary::{BaseSummary, FrameSummary, ModelSummary};
pub use workspace::Workspace;

#[cfg(feature = "description")]
pub use description::{is_urdf_document, CartesianLimitSpec, JointLimitSpec, LimitsSpec};
