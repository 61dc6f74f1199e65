//! Python exceptions for the library's errors: every message is the Rust error's text.
//!
//! The classes derive from both `DvrkError` (catch everything from this module) and the
//! built-in exception a Python user expects:
//!
//! | class | bases | raised for |
//! |---|---|---|
//! | `DvrkError` | `Exception` | base class |
//! | `InputError` | `DvrkError`, `ValueError` | bad arguments, shapes, NaN, unknown robot, description or log content, data that do not fit the robot or determine the parameters |
//! | `DvrkIOError` | `DvrkError`, `OSError` | a file that cannot be read or written |
//! | `DvrkFileNotFoundError` | `DvrkIOError`, `FileNotFoundError` | a file that does not exist |
//! | `SolverError` | `DvrkError`, `RuntimeError` | numerical failures (solver, base parameters), internal errors |
//! | `NotConvergedError` | `SolverError` | a fit whose solver did not converge; `.result` holds the unconverged `FitResult` |

use dvrk_ident::excite::{ExciteError, FourierError};
use dvrk_ident::log::LogError;
use dvrk_ident::IdentError;
use dvrk_ident::Setting;
use dvrk_ident::SettingName;
use dvrk_logs::hint::Hint;
use dvrk_model::ModelError;
use pyo3::exceptions::{PyException, PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The exception classes, created once at module initialization.
pub struct Exceptions {
    pub base: Py<PyType>,
    pub input: Py<PyType>,
    pub io: Py<PyType>,
    pub not_found: Py<PyType>,
    pub solver: Py<PyType>,
    pub not_converged: Py<PyType>,
}

static EXCEPTIONS: PyOnceLock<Exceptions> = PyOnceLock::new();

/// Which class an error maps to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Input,
    Io,
    NotFound,
    Solver,
    NotConverged,
}

fn new_type<'py>(
    py: Python<'py>,
    name: &str,
    bases: &[Bound<'py, PyType>],
    doc: &str,
) -> PyResult<Py<PyType>> {
    let ns = PyDict::new(py);
    ns.set_item("__module__", "dvrk_ident")?;
    ns.set_item("__doc__", doc)?;
    let bases = PyTuple::new(py, bases)?;
    let ty = py
        .get_type::<PyType>()
        .call1((name, bases, ns))?
        .cast_into::<PyType>()?;
    Ok(ty.unbind())
}

fn exceptions(py: Python<'_>) -> PyResult<&Exceptions> {
    EXCEPTIONS.get_or_try_init(py, || {
        let base = new_type(
            py,
            "DvrkError",
            &[py.get_type::<PyException>()],
            "Base class of every error raised by dvrk_ident.",
        )?;
        let input = new_type(
            py,
            "InputError",
            &[base.bind(py).clone(), py.get_type::<PyValueError>()],
            "Invalid input: arguments, array shapes or values (NaN), robot descriptions, \
             log contents, data that do not fit the robot or do not determine the parameters.",
        )?;
        let io = new_type(
            py,
            "DvrkIOError",
            &[base.bind(py).clone(), py.get_type::<PyOSError>()],
            "A file that cannot be read or written.",
        )?;
        let not_found = new_type(
            py,
            "DvrkFileNotFoundError",
            &[io.bind(py).clone(), py.get_type::<PyFileNotFoundError>()],
            "A file that does not exist.",
        )?;
        let solver = new_type(
            py,
            "SolverError",
            &[base.bind(py).clone(), py.get_type::<PyRuntimeError>()],
            "A numerical failure (solver, base parameters) or an internal error.",
        )?;
        let not_converged = new_type(
            py,
            "NotConvergedError",
            &[solver.bind(py).clone()],
            "The fit's solver did not converge: the parameters are not a result. The \
             unconverged Result is in the `result` attribute.",
        )?;
        Ok(Exceptions {
            base,
            input,
            io,
            not_found,
            solver,
            not_converged,
        })
    })
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let e = exceptions(py)?;
    for ty in [
        &e.base,
        &e.input,
        &e.io,
        &e.not_found,
        &e.solver,
        &e.not_converged,
    ] {
        let ty = ty.bind(py);
        m.add(ty.name()?, ty)?;
    }
    Ok(())
}

/// How Python spells an option: its keyword (`cutoff`), in messages and in the
/// conversion of keyword arguments alike.
pub(crate) fn setting_keyword(s: Setting) -> &'static str {
    s.name()
}

/// How Python spells a setting a library message suggests ([`Hint`]): as its keyword
/// (`rate=HZ`, `topic="..."`) where the command line gives its flag (`--rate HZ`).
fn keyword(hint: Hint) -> String {
    let option = |s: Setting| format!("{}=", setting_keyword(s));
    match hint {
        Hint::Rate => "rate=".into(),
        Hint::RateHz => "rate=HZ".into(),
        Hint::Resample => "resample=".into(),
        Hint::ResampleHz => "resample=HZ".into(),
        Hint::ResampleAt(hz) => format!("resample={hz}"),
        Hint::Topics => {
            "topic=\"...\" (a list of topics merges their joints, e.g. an arm and its jaw)".into()
        }
        Hint::LogTimes => "time_source=\"log\"".into(),
        Hint::Cutoff => option(Setting::Cutoff),
        Hint::Trim => option(Setting::Trim),
        Hint::TestWindow => option(Setting::TestWindow),
        Hint::MaxUnpackedMib => "max_unpacked_mib=".into(),
        Hint::Excitation => "excitation=".into(),
        Hint::MethodSdp => format!("{}\"sdp\"", option(Setting::Method)),
        Hint::DvrkGc => "FitResult.dvrk_gc()".into(),
        Hint::OtherExports => "Model.to_urdf() or FitResult.wpi_params()".into(),
    }
}

/// A library error's text as Python shows it: the settings it suggests as keywords
/// ([`keyword`]), in it and in every error nested in it.
pub fn text(e: &dyn std::fmt::Display) -> String {
    dvrk_logs::hint::spelled(e, keyword)
}

/// An exception of `kind` with `message` (a library error's as [`text`] gives it).
pub fn error(kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| match exceptions(py) {
        Ok(e) => {
            let ty = match kind {
                Kind::Input => &e.input,
                Kind::Io => &e.io,
                Kind::NotFound => &e.not_found,
                Kind::Solver => &e.solver,
                Kind::NotConverged => &e.not_converged,
            };
            PyErr::from_type(ty.bind(py).clone(), message)
        }
        Err(err) => err,
    })
}

/// `InputError(message)`.
pub fn input(message: impl Into<String>) -> PyErr {
    error(Kind::Input, message)
}

fn io_kind(e: &std::io::Error) -> Kind {
    if e.kind() == std::io::ErrorKind::NotFound {
        Kind::NotFound
    } else {
        Kind::Io
    }
}

/// A file that cannot be read: `DvrkFileNotFoundError` or `DvrkIOError`, naming it.
pub fn from_io(path: &std::path::Path, e: &std::io::Error) -> PyErr {
    error(io_kind(e), format!("{}: {e}", path.display()))
}

pub fn model_kind(e: &ModelError) -> Kind {
    match e {
        ModelError::Io { source, .. } => io_kind(source),
        ModelError::Numeric { .. } => Kind::Solver,
        _ => Kind::Input,
    }
}

pub fn log_kind(e: &LogError) -> Kind {
    match e {
        LogError::Io { source, .. } => io_kind(source),
        _ => Kind::Input,
    }
}

pub fn excite_kind(e: &ExciteError) -> Kind {
    match e {
        ExciteError::Infeasible(_) => Kind::Solver,
        ExciteError::Fourier(f) => fourier_kind(f),
        ExciteError::ImpossibleLimits(_) | ExciteError::Invalid(_) => Kind::Input,
    }
}

pub fn fourier_kind(e: &FourierError) -> Kind {
    match e {
        FourierError::Io { source, .. } => io_kind(source),
        _ => Kind::Input,
    }
}

pub fn ident_kind(e: &IdentError) -> Kind {
    match e {
        IdentError::Model(m) => model_kind(m),
        IdentError::Log(l) => log_kind(l),
        IdentError::Sdp(_) => Kind::Solver,
        IdentError::Io { source, .. } => io_kind(source),
        IdentError::Output(o) => io_kind(&o.source),
        IdentError::Excite(x) => excite_kind(x),
        _ => Kind::Input,
    }
}

pub fn from_model(e: ModelError) -> PyErr {
    error(model_kind(&e), text(&e))
}

pub fn from_log(e: LogError) -> PyErr {
    error(log_kind(&e), text(&e))
}

/// How Python spells a setting the library refuses: each fit option and any other
/// argument as its keyword (`cutoff`, `wrench`).
pub fn spelled(name: &SettingName) -> String {
    match name {
        SettingName::Options(settings) => settings
            .iter()
            .map(|s| setting_keyword(*s))
            .collect::<Vec<_>>()
            .join(", "),
        SettingName::Argument(n) => (*n).into(),
    }
}

/// A library error's class and its text as Python shows it: a refused setting named as
/// its keyword ([`spelled`]), any other as the library's message.
pub fn ident_failure(e: &IdentError) -> (Kind, String) {
    let text = match e {
        IdentError::Setting { name, message } => format!("{}: {message}", spelled(name)),
        e => text(e),
    };
    (ident_kind(e), text)
}

pub fn from_ident(e: IdentError) -> PyErr {
    let (kind, text) = ident_failure(&e);
    error(kind, text)
}
