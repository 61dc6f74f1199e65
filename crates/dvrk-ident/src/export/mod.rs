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
//! What each checks: the URDF and the controller's gravity compensation hold rigid
//! bodies and refuse parameters that are not ([`Model::check_rigid_bodies`]: a negative
//! mass, a first moment without mass, moments outside the triangle inequality), with no
//! flag to force them: a controller compensating a negative mass pushes the arm the
//! wrong way. `params.json` is the 2019 package's layout for its own least-squares fits,
//! which are representatives of the base parameters, not rigid bodies: it takes any
//! finite fit, as that package did.
//!
//! The next consumer's file is one new module here computing its document from a
//! [`Model`] and its parameters, one variant of [`Export`] with its arm in
//! [`Export::build`], then a flag of the CLI's `export` and a method of Python's
//! `FitResult`, each mapped onto that variant.

pub mod dvrk_gc;
pub mod dvrk_kinematic_gc;
pub mod wpi_params;

use dvrk_model::{Model, ParamKind};
use serde::{Serialize, Serializer};

use crate::result::ParameterStatus;
use crate::{FitResult, IdentError};

/// Which element parameters an export writes (see [`Export::undetermined`]).
#[derive(Clone, Copy)]
enum Elements {
    None,
    All,
    /// Those of the static torque: Coulomb, offset, Stribeck, spring.
    Static,
}

/// `at its lower bound` / `at its upper bound`, or `None` off the bounds.
fn bound_word(status: &ParameterStatus) -> Option<&'static str> {
    match status {
        ParameterStatus::AtLowerBound => Some("at its lower bound"),
        ParameterStatus::AtUpperBound => Some("at its upper bound"),
        _ => None,
    }
}

/// `text` (an XML document) with a comment of `lines` after its declaration (or first,
/// without one). `--`, which a comment may not hold, becomes `- -`.
fn with_xml_comment(text: &str, lines: &[String]) -> String {
    let body = lines.join("\n  ").replace("--", "- -");
    let comment = format!(
        "<!-- dvrk-ident: values not determined by the data (set by the bounds, the \
         regularization or a prior of the fit; see parameter_status in the result):\n  \
         {body}\n-->\n"
    );
    let start = text
        .strip_prefix('\u{feff}')
        .map_or(0, |_| '\u{feff}'.len_utf8());
    let at = match text[start..].starts_with("<?xml") {
        true => text[start..].find("?>").map_or(start, |i| start + i + 2),
        false => start,
    };
    let (head, tail) = text.split_at(at);
    match at > start {
        true => format!("{head}\n{comment}{}", tail.trim_start_matches(['\r', '\n'])),
        false => format!("{head}{comment}{tail}"),
    }
}

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
    /// The values written that the data did not determine, one line each
    /// ([`Export::build_for`]; empty from [`Export::build`]): what the command line
    /// prints as warnings and Python raises as `UserWarning`s.
    pub undetermined: Vec<String>,
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
    /// The document of a fit's `result` (its parameters `params` on `model`, SI units),
    /// with the values it writes that the data did not determine
    /// ([`Export::undetermined`]) in [`Exported::undetermined`] and in the file itself:
    /// an XML comment after a URDF's declaration, a `not_determined_by_the_data` list
    /// in the gravity compensation's `dvrk_ident` object (which the controller does not
    /// read). The 2019 `params.json` gets no such note: its top-level keys are the frame
    /// numbers `"1"` … `"N"`, and readers that iterate over them would take another key
    /// for a frame.
    pub fn build_for(
        &self,
        model: &Model,
        params: &[f64],
        result: &FitResult,
    ) -> Result<Exported, IdentError> {
        let mut exported = self.build(model, params)?;
        let lines = self.undetermined(model, result);
        if !lines.is_empty() {
            match &mut exported.document {
                Document::Text(text) => *text = with_xml_comment(text, &lines),
                Document::Json(value) => {
                    if let Some(ours) = value.get_mut("dvrk_ident").and_then(|v| v.as_object_mut())
                    {
                        ours.insert("not_determined_by_the_data".into(), lines.clone().into());
                    }
                }
            }
        }
        exported.undetermined = lines;
        Ok(exported)
    }

    /// The values this export writes of `result` that the data did not determine
    /// (`result.parameter_status`, see `crate::fit::status`), one line each; empty for
    /// a result written before parameter statuses. What each format writes: a URDF the
    /// links' mass, centre of mass and inertia (a generated one also lists every
    /// element's parameter in its header), `params.json` the links and the elements; the
    /// gravity compensation depends on the links only through the base parameters, which
    /// the data determine, so it names the parameters at a bound (which moved them) and
    /// the static elements' (Coulomb, offset, Stribeck, spring) parameters the data did
    /// not determine.
    pub fn undetermined(&self, model: &Model, result: &FitResult) -> Vec<String> {
        let status = &result.parameter_status;
        if status.is_empty() {
            return Vec::new();
        }
        let (links, elements) = match self {
            Export::Urdf { template: Some(_) } => (true, Elements::None),
            Export::Urdf { template: None } | Export::WpiParams => (true, Elements::All),
            Export::DvrkGc { .. } | Export::DvrkKinematicGc { .. } => (false, Elements::Static),
        };
        let mut out = Vec::new();
        let kinds: std::collections::HashMap<&str, ParamKind> = model
            .params
            .iter()
            .map(|p| (p.name.as_str(), p.kind))
            .collect();
        for l in result.links.iter().filter(|_| links) {
            let Some(d) = l.determined else { continue };
            let missing: Vec<&str> = [
                (d.mass, "mass"),
                (d.com(), "centre of mass"),
                (d.inertia_com(), "inertia"),
            ]
            .into_iter()
            .filter(|(ok, _)| !ok)
            .map(|(_, what)| what)
            .collect();
            if missing.is_empty() {
                continue;
            }
            let at_bounds: Vec<String> = result
                .link_status(l)
                .into_iter()
                .flatten()
                .filter_map(|(name, s)| bound_word(&s).map(|w| format!("{name} {w}")))
                .collect();
            let bounds = match at_bounds.is_empty() {
                true => String::new(),
                false => format!("; {}", at_bounds.join(", ")),
            };
            out.push(format!(
                "link {}: {} not determined by the data{bounds}",
                l.link,
                missing.join(", ")
            ));
        }
        for (name, st) in status {
            let Some(&kind) = kinds.get(name.as_str()) else {
                continue;
            };
            let link = matches!(kind, ParamKind::Inertia { .. });
            let wanted = match elements {
                Elements::None => false,
                Elements::All => !link && !st.identified(),
                Elements::Static => {
                    bound_word(st).is_some()
                        || (!st.identified()
                            && matches!(
                                kind,
                                ParamKind::Coulomb
                                    | ParamKind::Offset
                                    | ParamKind::Stribeck
                                    | ParamKind::Spring
                            ))
                }
            };
            if wanted {
                let why = bound_word(st).unwrap_or("not determined by the data");
                out.push(format!("{name} = {}: {why}", result.parameters[name]));
            }
        }
        out
    }
    /// The document of `model` with parameters `params` (the full vector, SI units),
    /// without the notes on undetermined values that [`Export::build_for`] adds.
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
                undetermined: Vec::new(),
            },
            Export::Urdf { template: None } => Exported {
                document: Document::Text(model.to_urdf(params)?),
                what: format!(
                    "URDF generated from robot `{}` (what URDF cannot hold is listed in its header)",
                    model.name
                ),
                details: String::new(),
                undetermined: Vec::new(),
            },
            Export::WpiParams => Exported {
                document: Document::Json(wpi_params::wpi_params_json(model, params)),
                what: "2019 params.json layout".into(),
                details: String::new(),
                undetermined: Vec::new(),
            },
            Export::DvrkGc { points } => {
                let gc = dvrk_gc::dvrk_gc(model, params, *points)?;
                Exported {
                    document: Document::Json(gc.to_json()),
                    what: "dVRK MTM gravity compensation".into(),
                    details: gc.summary(),
                    undetermined: Vec::new(),
                }
            }
            Export::DvrkKinematicGc { endoscope } => {
                let gc = dvrk_kinematic_gc::dvrk_kinematic_gc(model, params, *endoscope)?;
                Exported {
                    document: Document::Json(gc.to_json()),
                    what: format!("dVRK kinematic gravity compensation of robot `{}`", model.name),
                    details: gc.summary(),
                    undetermined: Vec::new(),
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
