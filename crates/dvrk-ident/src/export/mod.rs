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
//! - [`dvrk_gc`]: sawIntuitiveResearchKit's MTM gravity-compensation file (version 2.0).
//!
//! What each checks: the URDF and the controller's gravity compensation hold rigid
//! bodies and refuse parameters that are not ([`Model::check_rigid_bodies`]: a negative
//! mass, a first moment without mass, moments outside the triangle inequality), with no
//! flag to force them: a controller compensating a negative mass pushes the arm the
//! wrong way. `params.json` is the 2019 package's layout for its own least-squares fits,
//! which are representatives of the base parameters, not rigid bodies: it takes any
//! finite fit, as that package did.
//!
//! The next consumer's file (e.g. the dVRK's kinematic gravity-compensation file of the
//! ECM and Si arms, `--dvrk-kinematic-gc`) is one new module here computing its document
//! from a [`Model`] and its parameters, one variant of [`Export`] with its arm in
//! [`Export::build`], then a flag of the CLI's `export` and a method of Python's
//! `FitResult`, each mapped onto that variant.

pub mod dvrk_gc;
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
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every export that holds rigid bodies refuses a link of negative mass (−5 kg on
    /// the MTM's shoulder): the controller's file as the URDF, naming the link; the
    /// 2019 layout, which holds least-squares representatives, takes it.
    #[test]
    fn exports_of_rigid_bodies_refuse_a_negative_mass() {
        let model = Model::builtin("mtm").unwrap();
        let mut params = dvrk_gc::tests::mtm_params(&model);
        let good = Export::DvrkGc { points: 6 }.build(&model, &params);
        assert!(good.is_ok(), "{:?}", good.err());
        let frame = model.frames.iter().find(|f| f.inertia.is_some()).unwrap();
        params[frame.inertia.unwrap() + 9] = -5.0;
        for export in [
            Export::DvrkGc { points: 6 },
            Export::Urdf { template: None },
        ] {
            let e = export.build(&model, &params).unwrap_err().to_string();
            assert!(
                e.contains(&format!("link {} (mass -5)", frame.name))
                    && e.contains("is not a rigid body"),
                "{export:?}: {e}"
            );
        }
        assert!(Export::WpiParams.build(&model, &params).is_ok());
    }
}
