//! The classes that refer to each other, defined apart from their methods so that the
//! modules of the methods form no cycle: a [`ModelPy`] accepts a fit result as its
//! parameters (`robot.rs`), and a [`FitResultPy`] keeps the model it was fitted with
//! (`fit.rs`).

use std::sync::{Arc, OnceLock};

use dvrk_ident::{FitResult, FitSettings, IdentError};
use dvrk_model::{BaseParameters, Model};
use pyo3::prelude::*;

/// A robot model: a built-in dVRK arm (``"psm"``, ``"psm_simplified"``, ``"mtm"``, ``"ecm"``, ``"psm_si"``, ``"psm_si_tool"``, ``"ecm_si"``), a
/// ``.toml`` description or a ``.urdf`` file.
///
/// Arrays are float64. Functions of the state take one sample as 1-D arrays of
/// ``dof`` values, or ``N`` samples as 2-D arrays of shape ``(N, dof)``; the output
/// then has a leading sample axis (see each method). ``dq`` and ``ddq`` default to
/// zeros. Parameters (``params``) are a vector of ``len(parameter_names)`` values in
/// ``parameter_names`` order, a dict ``{name: value}`` with every parameter, or a fit
/// ``FitResult``.
///
/// Example::
///
///     >>> import numpy as np, dvrk_ident as di
///     >>> psm = di.Model.load("psm")
///     >>> psm.dof, len(psm.parameter_names), len(psm.base().names)
///     (7, 115, 49)
///     >>> psm.regressor(np.zeros((10, 7))).shape
///     (70, 115)
#[pyclass(name = "Model", module = "dvrk_ident", frozen)]
pub struct ModelPy {
    pub model: Arc<Model>,
    pub(crate) base: OnceLock<Arc<BaseParameters>>,
    /// What the model was built from, and the settings of the fit whose model options
    /// (Stribeck and Dahl terms, mounting pitch, bounds: `FitSettings::model`) were
    /// applied to it, for pickling.
    pub(crate) origin: Origin,
    pub(crate) fit: Option<Box<FitSettings>>,
}

/// What a robot was built from: enough to build it again in another process (a file
/// is kept as its text, so the copy does not depend on the file).
#[derive(Clone, Debug)]
pub enum Origin {
    Builtin(String),
    Toml { text: String, source: String },
    Urdf { text: String, source: String },
}

impl Origin {
    /// The model it describes, with the model options of the fit `fit` if given
    /// (`FitSettings::model`: Stribeck and Dahl terms, mounting pitch, bounds).
    pub(crate) fn build(&self, fit: Option<&FitSettings>) -> Result<Model, IdentError> {
        let model = match self {
            Origin::Builtin(name) => Model::builtin(name)?,
            Origin::Toml { text, source } => Model::from_toml_str(text, source)?,
            Origin::Urdf { text, source } => Model::from_urdf_str(text, source)?,
        };
        match fit {
            Some(s) => Ok(s.model(&model)?.into_owned()),
            None => Ok(model),
        }
    }

    /// A built-in name or a description file, as `Model::load` takes it.
    pub fn load(name_or_path: &str) -> Result<(Model, Origin), dvrk_model::ModelError> {
        if Model::builtin_names().contains(&name_or_path) {
            return Ok((
                Model::builtin(name_or_path)?,
                Origin::Builtin(name_or_path.to_string()),
            ));
        }
        let model = Model::load(name_or_path)?;
        let text =
            std::fs::read_to_string(name_or_path).map_err(|source| dvrk_model::ModelError::Io {
                file: name_or_path.to_string(),
                source,
            })?;
        let source = name_or_path.to_string();
        let origin = if dvrk_model::is_urdf_document(std::path::Path::new(name_or_path), &text) {
            Origin::Urdf { text, source }
        } else {
            Origin::Toml { text, source }
        };
        Ok((model, origin))
    }
}

/// The result of :func:`fit`: the document of ``dvrk-ident fit --out`` (see
/// :meth:`to_json`), with its fields as attributes and the identified model's
/// predictions.
///
/// Attributes (the JSON keys): ``parameters`` (dict name → value, model order),
/// ``base_parameters`` (list of ``{name, expression, value, std}``), ``links``,
/// ``consistency`` (list of ``{frame, link, min_eigenvalue, consistent}``),
/// ``physically_consistent``, ``solver`` (``{name, status, converged, seconds,
/// iterations}``), ``metrics`` (``{train, test}``, each ``{joints, samples,
/// relative_error, rms}`` or ``None``), ``method``, ``robot`` (name),
/// ``robot_source``, ``settings``, ``inputs``, ``weights``, ``rows``,
/// ``condition_number``, ``sigma2``, ``tool``. Non-finite numbers are ``None``, as in
/// the JSON.
#[pyclass(name = "FitResult", module = "dvrk_ident", frozen)]
pub struct FitResultPy {
    pub inner: FitResult,
    /// The robot it was fitted with (`None` when read from JSON without one).
    pub robot: Option<Py<ModelPy>>,
    // `inner`'s numbers Python reads as attributes, copied once (the class is frozen).
    #[pyo3(get)]
    rows: usize,
    #[pyo3(get)]
    condition_number: f64,
    #[pyo3(get)]
    sigma2: f64,
}

impl FitResultPy {
    pub fn new(inner: FitResult, robot: Option<Py<ModelPy>>) -> Self {
        FitResultPy {
            rows: inner.rows,
            condition_number: inner.condition_number,
            sigma2: inner.sigma2,
            inner,
            robot,
        }
    }
}
