//! Excitation trajectories: the motions a robot runs so that its log determines the
//! dynamic parameters. [`fourier`]: finite Fourier series (the 2019 package's
//! parametrization), with their analytic derivatives and the loader of the 2019
//! coefficient files.

pub mod fourier;
mod grid;
pub mod limits;
pub mod optimize;

pub use fourier::{FourierError, FourierTrajectory};
