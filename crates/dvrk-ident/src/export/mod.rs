//! The files other tools read, written from an identified model (a fit result's model and
//! parameters): a URDF, the 2019 package's `params.json`, the dVRK controller's MTM
//! gravity compensation.
//!
//! Where each is written:
//!
//! - URDF: dvrk-model's description folder (`crates/dvrk-model/src/description/urdf/`),
//!   beside the URDF import whose frames the export must reproduce:
//!   [`Model::urdf_with_inertials`](dvrk_model::Model::urdf_with_inertials) puts the inertials into an existing URDF (the robot's
//!   own, or `--template`) and keeps every other byte, [`Model::to_urdf`](dvrk_model::Model::to_urdf) generates a
//!   URDF of a whole description; Python's `Model.to_urdf` is the latter;
//! - [`wpi_params`]: the 2019 package's `params.json` layout;
//! - [`dvrk_gc`]: sawIntuitiveResearchKit's MTM gravity-compensation file (version 2.0).
//!
//! The next consumer's file (e.g. the dVRK's kinematic gravity-compensation file of the
//! ECM and Si arms, `--dvrk-kinematic-gc`) is one new module here computing its document
//! from a `Model` and its parameters.

pub mod dvrk_gc;
pub mod wpi_params;
