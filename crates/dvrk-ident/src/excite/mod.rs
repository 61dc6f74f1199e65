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
