//! The dVRK descriptions shipped with the crate, and loading by name or path.

use std::path::Path;

use crate::error::ModelError;
use crate::model::Model;

/// Built-in robot descriptions: (name, TOML text).
pub const BUILTIN: [(&str, &str); 7] = [
    ("psm", include_str!("../../robots/psm.toml")),
    (
        "psm_simplified",
        include_str!("../../robots/psm_simplified.toml"),
    ),
    ("mtm", include_str!("../../robots/mtm.toml")),
    ("ecm", include_str!("../../robots/ecm.toml")),
    ("psm_si", include_str!("../../robots/psm_si.toml")),
    ("psm_si_tool", include_str!("../../robots/psm_si_tool.toml")),
    ("ecm_si", include_str!("../../robots/ecm_si.toml")),
];

impl Model {
    /// A built-in robot: `psm`, `psm_simplified`, `mtm`, `ecm`, `psm_si`, `psm_si_tool` or
    /// `ecm_si`.
    pub fn builtin(name: &str) -> Result<Model, ModelError> {
        let (_, text) = BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| ModelError::UnknownRobot(name.to_string()))?;
        Model::from_toml_str(text, &format!("builtin:{name}"))
    }

    /// Names of the built-in robots.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN.iter().map(|(n, _)| *n).collect()
    }

    /// A built-in name, or a path to a description (`.toml`) or a `.urdf` file.
    pub fn load(name_or_path: &str) -> Result<Model, ModelError> {
        if BUILTIN.iter().any(|(n, _)| *n == name_or_path) {
            return Model::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        // A bare word that is no file is a misspelt built-in name; anything that looks
        // like a path is a file that cannot be read.
        let looks_like_path =
            name_or_path.contains(std::path::MAIN_SEPARATOR) || path.extension().is_some();
        if !looks_like_path && !path.exists() {
            return Err(ModelError::UnknownRobot(name_or_path.to_string()));
        }
        let text = crate::input::read_text(path).map_err(|source| ModelError::Io {
            file: name_or_path.to_string(),
            source,
        })?;
        if is_urdf_document(path, &text) {
            Model::from_urdf_str(&text, name_or_path)
        } else {
            Model::from_toml_str(&text, name_or_path)
        }
    }
}

/// Whether a robot file is a URDF (by its `.urdf` extension or an XML start) rather than a
/// TOML description: how [`Model::load`] decides, for callers that need the original
/// document again (e.g. to export identified inertials into it).
///
/// ```
/// use std::path::Path;
/// assert!(dvrk_model::is_urdf_document(Path::new("arm.xml"), "<robot name=\"arm\"/>"));
/// assert!(!dvrk_model::is_urdf_document(Path::new("arm.toml"), "name = \"arm\""));
/// ```
pub fn is_urdf_document(path: &Path, text: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
        || text.trim_start().starts_with("<?xml")
        || text.trim_start().starts_with("<robot")
}
