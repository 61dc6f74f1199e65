//! Loading a `dvrk-ident fit` result into a [`DvrkModel`] (`dvrk_model_from_result`)
//! and freeing it: not real-time, reads files and allocates.

use std::ffi::{c_char, CStr};
use std::panic::catch_unwind;
use std::path::Path;

use dvrk_model::Model;

use crate::{DvrkModel, BOUNDED_Q_MAX, BOUND_MAX};

/// What the loader reads of a result document: the rest (metrics, solver, inputs) is not
/// needed to evaluate the model.
/// Why a result cannot be loaded (`dvrk_model_from_result` writes its text to `err`).
/// Each names the file first, as the CLI's messages do.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// `result_path` is NULL.
    #[error("result_path is NULL")]
    NullPath,
    /// `result_path` is not UTF-8.
    #[error("result_path is not UTF-8")]
    PathNotUtf8,
    /// The file cannot be read (missing, too large, not UTF-8).
    #[error("{file}: {source}")]
    Read {
        /// The result file.
        file: String,
        /// The OS error or the reason.
        source: std::io::Error,
    },
    /// The file is not a result document.
    #[error("{file}: not a dvrk-ident result: {source}")]
    NotAResult {
        /// The result file.
        file: String,
        /// The JSON parser's message (with line and column).
        source: serde_json::Error,
    },
    /// The recorded robot cannot be loaded, or a fit option of the result is refused.
    #[error("{file}: {source}")]
    Model {
        /// The result file.
        file: String,
        /// The model's error.
        source: dvrk_model::ModelError,
    },
    /// The recorded robot's description now describes another robot.
    #[error("{file} was fitted for {fitted}, but its robot {robot_source} is {found}")]
    OtherRobot {
        /// The result file.
        file: String,
        /// The robot the result was fitted for.
        fitted: String,
        /// Where the result says that robot comes from (`builtin:psm`, a path).
        robot_source: String,
        /// The name of the robot found there.
        found: String,
    },
    /// A setting of the result (the mounting pitch) is out of range.
    #[error("{file}: {source}")]
    Setting {
        /// The result file.
        file: String,
        /// What is wrong with the setting.
        source: dvrk_model::input::InputError,
    },
    /// A parameter or the payload is refused (the error names the file).
    #[error(transparent)]
    Parameters(dvrk_model::ModelError),
    /// The robot's measured-joint coupling matrix cannot be inverted.
    #[error("{file}: the robot's measured-joint coupling matrix is singular")]
    SingularCoupling {
        /// The result file.
        file: String,
    },
    /// A joint, coordinate or parameter name holds a NUL byte (no C string).
    #[error("{file}: {source}")]
    Name {
        /// The result file.
        file: String,
        /// Where the NUL is.
        source: std::ffi::NulError,
    },
}

#[derive(serde::Deserialize)]
struct ResultDocument {
    robot: String,
    robot_source: String,
    #[serde(default)]
    settings: ResultSettings,
    parameters: std::collections::BTreeMap<String, f64>,
    /// A payload the arm carries (`dvrk-ident payload`), added to its frame's link.
    #[serde(default)]
    payload: Option<dvrk_model::Payload>,
}

#[derive(serde::Deserialize, Default)]
struct ResultSettings {
    #[serde(default)]
    stribeck_velocity: Option<f64>,
    /// Dahl friction of the fit (`--dahl`): its elements are part of the parameter
    /// vector. Their hysteresis state is not carried by this ABI: it stays at zero in
    /// a workspace, so Dahl friction adds nothing to the torques here (as in a fresh
    /// workspace of dvrk-model, and in `dvrk-ident model --torque`).
    #[serde(default)]
    dahl_sigma: Option<f64>,
    /// The position-dependent torques of the fit (`--position-torque`): their
    /// coefficients are part of the parameter vector.
    #[serde(default)]
    position_torque_order: Option<usize>,
    /// The load friction of the fit (`--load-friction`): predicted with its load, as the
    /// fit's metrics do ([`Model::loaded_inverse_dynamics`]).
    #[serde(default)]
    load_friction: bool,
    /// The arm's mounting pitch (degrees), which sets gravity in the base frame.
    #[serde(default)]
    mounting_pitch_deg: Option<f64>,
}

impl DvrkModel {
    /// Loads a result document as `dvrk-ident model --params RESULT` does: the recorded
    /// robot (`builtin:psm` or a description path, as written, relative to the working
    /// directory), refused if its name is not the result's robot, with a Stribeck term
    /// on every friction element when the fit had `stribeck_velocity`, every
    /// parameter by name (missing, unknown or non-finite ones refused), and its
    /// `payload` (`dvrk-ident payload`), if any, added to its frame's link.
    pub fn from_result(path: &Path) -> Result<DvrkModel, LoadError> {
        let file = path.display().to_string();
        let text = dvrk_model::input::read_text(path).map_err(|source| LoadError::Read {
            file: file.clone(),
            source,
        })?;
        let doc: ResultDocument =
            serde_json::from_str(&text).map_err(|source| LoadError::NotAResult {
                file: file.clone(),
                source,
            })?;
        let model_error = |source| LoadError::Model {
            file: file.clone(),
            source,
        };
        let robot = doc
            .robot_source
            .strip_prefix("builtin:")
            .unwrap_or(&doc.robot_source);
        let mut model = Model::load(robot).map_err(model_error)?;
        if model.name != doc.robot {
            return Err(LoadError::OtherRobot {
                file,
                fitted: doc.robot,
                robot_source: doc.robot_source,
                found: model.name,
            });
        }
        if let Some(v) = doc.settings.stribeck_velocity {
            model = model.with_stribeck(v).map_err(model_error)?;
        }
        if let Some(sigma) = doc.settings.dahl_sigma {
            model = model.with_dahl(sigma).map_err(model_error)?;
        }
        if let Some(order) = doc.settings.position_torque_order {
            model = model.with_position_torque(order).map_err(model_error)?;
        }
        if doc.settings.load_friction {
            model = model.with_load_friction();
        }
        if let Some(pitch) = doc.settings.mounting_pitch_deg {
            model.gravity =
                Model::mounting_pitch_gravity(pitch).map_err(|source| LoadError::Setting {
                    file: file.clone(),
                    source,
                })?;
        }
        // These name the file themselves.
        let mut params = model
            .params_from_named(doc.parameters.iter().map(|(k, v)| (k.as_str(), *v)), &file)
            .map_err(LoadError::Parameters)?;
        // As every consumer of a result: the arm with its payload, if it carries one.
        if let Some(p) = &doc.payload {
            p.add_to(&model, &mut params, &file)
                .map_err(LoadError::Parameters)?;
        }
        let mut link_params = vec![0.0; params.len()];
        for &j in model.link_frames() {
            if let Some(p0) = model.frame(j).inertia {
                link_params[p0..p0 + 10].copy_from_slice(&params[p0..p0 + 10]);
            }
        }
        let n = model.dof();
        let minv = model
            .measured_to_model_matrix()
            .ok_or_else(|| LoadError::SingularCoupling { file: file.clone() })?;
        let measured_to_model = (0..n * n).map(|k| minv[(k / n, k % n)]).collect();
        let names = |v: Vec<String>| -> Result<Vec<std::ffi::CString>, LoadError> {
            v.into_iter()
                .map(|s| {
                    std::ffi::CString::new(s).map_err(|source| LoadError::Name {
                        file: file.clone(),
                        source,
                    })
                })
                .collect()
        };
        let bounded = model.gravity_torque_bound(&params, BOUNDED_Q_MAX) <= BOUND_MAX
            && model.mass_matrix_bound(&params, BOUNDED_Q_MAX) <= BOUND_MAX;
        Ok(DvrkModel {
            bounded,
            joint_names: names(model.measured.joints.clone())?,
            param_names: names(model.param_names())?,
            coordinate_names: names(model.coordinates.clone())?,
            model,
            params,
            link_params,
            measured_to_model,
        })
    }

    /// The robot model (with the fit's Stribeck terms).
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The fitted parameters in the model's order.
    pub fn params(&self) -> &[f64] {
        &self.params
    }
}

/// Writes `message` into `err` (at most `err_len` bytes with the NUL), truncated at a
/// character boundary; nothing when `err` is NULL or `err_len` is 0.
fn write_error(message: &str, err: *mut c_char, err_len: usize) {
    if err.is_null() || err_len == 0 {
        return;
    }
    let mut end = message.len().min(err_len - 1);
    while !message.is_char_boundary(end) {
        end -= 1;
    }
    // SAFETY: the caller gives `err` valid for `err_len` bytes (checked non-NULL above);
    // `end + 1 <= err_len` bytes are written.
    let out = unsafe { std::slice::from_raw_parts_mut(err.cast::<u8>(), err_len) };
    out[..end].copy_from_slice(&message.as_bytes()[..end]);
    out[end] = 0;
}

/// Loads the result document of `dvrk-ident fit` at `result_path` (a NUL-terminated
/// path): its robot (a built-in name, or the description path it records, relative to
/// the working directory), the fit's Stribeck terms and its parameters. Returns NULL on
/// any error, with the message in `err` (NUL-terminated, truncated to `err_len` bytes;
/// `err` may be NULL). Not real-time: reads files and allocates. Free the model with
/// `dvrk_model_free` after its workspaces.
///
/// # Safety
///
/// `result_path` is NULL or a NUL-terminated string; `err` is NULL or valid for
/// `err_len` bytes of writing.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_from_result(
    result_path: *const c_char,
    err: *mut c_char,
    err_len: usize,
) -> *mut DvrkModel {
    let loaded = catch_unwind(|| {
        if result_path.is_null() {
            return Err(LoadError::NullPath);
        }
        // SAFETY: non-NULL, and the caller gives a NUL-terminated string.
        let path = unsafe { CStr::from_ptr(result_path) };
        let path = path.to_str().map_err(|_| LoadError::PathNotUtf8)?;
        DvrkModel::from_result(Path::new(path))
    });
    match loaded {
        Ok(Ok(model)) => Box::into_raw(Box::new(model)),
        Ok(Err(error)) => {
            write_error(&error.to_string(), err, err_len);
            std::ptr::null_mut()
        }
        Err(_) => {
            write_error("internal error (a bug of dvrk-model-c)", err, err_len);
            std::ptr::null_mut()
        }
    }
}

/// Frees a model from `dvrk_model_from_result`; NULL does nothing. Its workspaces must be
/// freed first (or at least no longer used).
///
/// # Safety
///
/// `model` is NULL or a pointer from `dvrk_model_from_result` not freed yet.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_free(model: *mut DvrkModel) {
    if !model.is_null() {
        // SAFETY: the pointer came from `Box::into_raw` in `dvrk_model_from_result` and is
        // freed once (the caller's obligation). Dropping a model cannot panic.
        drop(unsafe { Box::from_raw(model) });
    }
}
