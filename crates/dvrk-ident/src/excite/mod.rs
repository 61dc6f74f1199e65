//! Excitation trajectories: the motions a robot runs so that its log determines the
//! dynamic parameters. [`FourierTrajectory`]: finite Fourier series (the 2019 package's
//! parametrization), with their analytic derivatives and the loader of the 2019
//! coefficient files.

mod criterion;
mod error;
mod fourier;
mod grid;
mod lbfgs;
mod limits;
pub mod optimize;
mod options;
mod rng;
pub mod setpoints;

pub use error::ExciteError;
pub use fourier::{FourierError, FourierTrajectory};

use dvrk_model::Model;

/// `traj` is a valid trajectory with one coordinate per coordinate of `model`: the
/// check every entry point of the optimizer and the setpoints start with.
pub(crate) fn check_dof(model: &Model, traj: &FourierTrajectory) -> Result<(), ExciteError> {
    traj.validate("trajectory")?;
    if traj.dof() != model.dof() {
        return Err(ExciteError::Invalid(format!(
            "the trajectory has {} coordinates, model {} has {}",
            traj.dof(),
            model.name,
            model.dof()
        )));
    }
    Ok(())
}
