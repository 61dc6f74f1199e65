//! Python bindings of dvrk-ident: the `dvrk_ident` module (build with maturin, see
//! `pyproject.toml` and `README.md` next to this crate).
//!
//! A thin layer: conversions between numpy arrays and the library's buffers, and calls
//! into `dvrk-model` and `dvrk-ident`; no algorithm lives here. Heavy work runs
//! without the GIL (per-sample loops in chunks with a signal check between them, fits
//! and log reading on a worker thread polled for Ctrl-C).

// No unsafe code: the workspace's unsafe code is in crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls) and crates/dvrk-model-c (the C ABI).
#![forbid(unsafe_code)]

mod classes;
mod compare;
mod convert;
mod data;
mod deprecated;
mod errors;
mod excite;
mod fit;
mod frame;
mod json;
mod limits;
mod observe;
mod overrides;
mod payload;
mod residual;
mod robot;
mod warnings;

use pyo3::prelude::*;

/// Dynamic parameter identification for robot arms (dVRK PSM/MTM, DH and URDF
/// robots): models, regressors and dynamics over numpy arrays, log reading, and the
/// fit of ``dvrk-ident fit``, and the excitation trajectories of ``dvrk-ident excite``.
///
/// Example::
///
///     >>> import dvrk_ident as di
///     >>> psm = di.Model.load("psm")
///     >>> train = di.read_log("one_results.csv", psm, format="wpi-csv", rate=200)
///     >>> result = di.fit(psm, train, method="ols", cutoff=16.965)
///     >>> result.metrics["train"]["relative_error"]
#[pymodule(name = "dvrk_ident")]
mod dvrk_ident_module {
    use super::*;

    #[pymodule_export]
    use crate::classes::{FitResultPy, ModelPy};

    #[pymodule_export]
    use crate::robot::BaseParametersPy;

    #[pymodule_export]
    use crate::data::{list_topics, read_log, JointLogPy, PreparedPy};

    #[pymodule_export]
    use crate::fit::{fit, prepare};

    #[pymodule_export]
    use crate::compare::compare;

    #[pymodule_export]
    use crate::payload::identify_payload;

    #[pymodule_export]
    use crate::residual::{external_torque, MomentumObserverPy};

    #[pymodule_export]
    use crate::observe::{observe, ObservationPy};

    #[pymodule_export]
    use crate::excite::{evaluate_trajectory, excite, ExcitationPy, FourierTrajectoryPy};

    #[pymodule_export]
    use crate::convert::{held_computations, hold_computations};

    #[pymodule_export]
    use crate::deprecated::module_getattr;

    /// Runs the ``dvrk-ident`` command line with ``argv`` (the program name first)
    /// in this process and returns its exit status; what the command prints goes to
    /// the process's stdout and stderr. The ``dvrk-ident`` console command and
    /// ``python -m dvrk_ident`` call it.
    #[pyfunction]
    fn _cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
        py.detach(move || dvrk_cli::run(argv))
    }

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        crate::errors::register(m)?;
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        m.add("_options", crate::overrides::options_table(m.py())?)?;
        m.add("_excite_options", crate::excite::options_table(m.py())?)?;
        Ok(())
    }
}
