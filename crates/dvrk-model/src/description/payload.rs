//! The payload file: a rigid body fixed to a frame, as `simulate --payload` reads it.
//!
//! ```toml
//! frame = "main_insertion"      # a frame of the robot
//! mass = 0.2                    # kg
//! com = [0.0, 0.02, 0.165]      # m, in that frame
//! inertia = [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0]   # kg·m² about the com: xx yy zz xy xz yz (optional)
//! ```

use std::path::Path;

use serde::Deserialize;

use crate::error::ModelError;
use crate::input::read_text;
use crate::model::Model;
use crate::payload::Payload;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PayloadFile {
    frame: String,
    mass: f64,
    com: [f64; 3],
    #[serde(default)]
    inertia: [f64; 6],
}

impl Payload {
    /// Reads a payload file's text (`file` names it in errors) and checks it against
    /// `model`.
    ///
    /// ```
    /// # use dvrk_model::{Model, Payload};
    /// let psm = Model::builtin("psm").unwrap();
    /// let text = "frame = \"main_insertion\"\nmass = 0.2\ncom = [0.0, 0.02, 0.165]\n";
    /// let payload = Payload::from_toml_str(&psm, text, "payload.toml").unwrap();
    /// assert_eq!(payload.barycentric()[9], 0.2);
    /// ```
    pub fn from_toml_str(model: &Model, text: &str, file: &str) -> Result<Payload, ModelError> {
        let f: PayloadFile = toml::from_str(text).map_err(|e| ModelError::Syntax {
            file: file.into(),
            message: e.to_string(),
        })?;
        let payload = Payload {
            frame: f.frame,
            mass: f.mass,
            com: f.com,
            inertia: f.inertia,
        };
        payload.check(model, file)?;
        Ok(payload)
    }

    /// Reads and checks a payload file.
    pub fn load(model: &Model, path: impl AsRef<Path>) -> Result<Payload, ModelError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = read_text(path).map_err(|source| ModelError::Io {
            file: file.clone(),
            source,
        })?;
        Payload::from_toml_str(model, &text, &file)
    }
}
