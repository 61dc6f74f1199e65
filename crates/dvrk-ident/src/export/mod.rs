//! The files other tools read, written from an identified model (a fit result's model and
//! parameters): a URDF, the 2019 package's `params.json`, the dVRK controller's MTM
//! gravity compensation. [`Export`] lists them; the command line (`export`, and
//! `fit --wpi-json`) and Python (`FitResult.wpi_params()`, `FitResult.dvrk_gc()`) map
//! their flags and methods onto its variants, so a written file and the value Python
//! returns are one document built by one function.
//!
//! Where each is computed:
//!
//! - URDF: in dvrk-model's description folder (`crates/dvrk-model/src/description/urdf/`),
//!   beside the URDF import whose frames an export must reproduce:
//!   [`Model::urdf_with_inertials`] puts the inertials into an existing URDF (the robot's
//!   own, or `export --template`) and keeps every other byte, [`Model::to_urdf`]
//!   generates a URDF of a whole description. Python's `Model.to_urdf` calls the latter
//!   directly, and Python has no way to the former;
//! - [`wpi_params`]: the 2019 package's `params.json` layout;
//! - [`dvrk_gc`]: sawIntuitiveResearchKit's MTM gravity-compensation file (version 2.0);
//! - [`dvrk_kinematic_gc`]: its kinematic gravity-compensation file (the physical DH the
//!   `kinematic_gc` key names) of the ECM, the PSM Si and the ECM Si.
//!
//! The next consumer's file is one new module here computing its document from a
//! [`Model`] and its parameters, one variant of [`Export`] with its arm in
//! [`Export::build`], then a flag of the CLI's `export` and a method of Python's
//! `FitResult`, each mapped onto that variant.

pub mod dvrk_gc;
pub mod dvrk_kinematic_gc;
pub mod wpi_params;

use dvrk_model::Model;
use serde::{Serialize, Serializer};

use crate::IdentError;

/// One file written from an identified model.
#[derive(Clone, Copy, Debug)]
pub enum Export<'a> {
    /// A URDF: the identified inertials put into `template` when there is one (a robot's
    /// URDF holds more than its dynamics: meshes, transmissions, controllers), else a URDF
    /// generated from the whole model.
    Urdf {
        /// The URDF to put the inertials into, if any.
        template: Option<UrdfTemplate<'a>>,
    },
    /// The 2019 package's `params.json` layout ([`wpi_params`]).
    WpiParams,
    /// The dVRK controller's MTM gravity-compensation file ([`dvrk_gc`]), fitted over
    /// `points` grid points per joint (6 to 10).
    DvrkGc {
        /// Grid points per joint ([`dvrk_gc::DEFAULT_POINTS`] by default).
        points: usize,
    },
    /// The dVRK controller's kinematic gravity-compensation file of the ECM, PSM Si and
    /// ECM Si ([`dvrk_kinematic_gc`]).
    DvrkKinematicGc {
        /// The ECM's endoscope type ([`dvrk_kinematic_gc::ENDOSCOPES`]); `None` for the
        /// PSM Si.
        endoscope: Option<&'a str>,
    },
}

/// A URDF that identified inertials are put into: its text, and its name for messages.
#[derive(Clone, Copy, Debug)]
pub struct UrdfTemplate<'a> {
    /// The document.
    pub text: &'a str,
    /// Its file name (or another name for messages).
    pub file: &'a str,
}

/// A built export: the document, and what the front end reports about it.
#[derive(Clone, Debug)]
pub struct Exported {
    /// The document.
    pub document: Document,
    /// What the file holds, in a few words (`wrote FILE: …`).
    pub what: String,
    /// More for the report, one line each, or empty (the gravity compensation's residuals).
    pub details: String,
}

/// An exported document: the JSON formats as a value (Python hands it over as a dict),
/// URDF as text.
#[derive(Clone, Debug)]
pub enum Document {
    /// A JSON document.
    Json(serde_json::Value),
    /// A text document (URDF).
    Text(String),
}

impl Document {
    /// The file's text: JSON pretty-printed, text as it is.
    pub fn to_text(&self) -> String {
        match self {
            Document::Json(v) => serde_json::to_string_pretty(v).expect("serializable"),
            Document::Text(t) => t.clone(),
        }
    }
}

impl Serialize for Document {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Document::Json(v) => v.serialize(s),
            Document::Text(t) => t.serialize(s),
        }
    }
}

impl Export<'_> {
    /// The document of `model` with parameters `params` (the full vector, SI units).
    pub fn build(&self, model: &Model, params: &[f64]) -> Result<Exported, IdentError> {
        Ok(match self {
            Export::Urdf {
                template: Some(t),
            } => Exported {
                document: Document::Text(model.urdf_with_inertials(params, t.text, t.file)?),
                what: format!(
                    "{} with the identified inertials of robot `{}`",
                    t.file, model.name
                ),
                details: String::new(),
            },
            Export::Urdf { template: None } => Exported {
                document: Document::Text(model.to_urdf(params)?),
                what: format!(
                    "URDF generated from robot `{}` (what URDF cannot hold is listed in its header)",
                    model.name
                ),
                details: String::new(),
            },
            Export::WpiParams => Exported {
                document: Document::Json(wpi_params::wpi_params_json(model, params)),
                what: "2019 params.json layout".into(),
                details: String::new(),
            },
            Export::DvrkGc { points } => {
                let gc = dvrk_gc::dvrk_gc(model, params, *points)?;
                Exported {
                    document: Document::Json(gc.to_json()),
                    what: "dVRK MTM gravity compensation".into(),
                    details: gc.summary(),
                }
            }
            Export::DvrkKinematicGc { endoscope } => {
                let gc = dvrk_kinematic_gc::dvrk_kinematic_gc(model, params, *endoscope)?;
                Exported {
                    document: Document::Json(gc.to_json()),
                    what: format!("dVRK kinematic gravity compensation of robot `{}`", model.name),
                    details: gc.summary(),
                }
            }
        })
    }
}
