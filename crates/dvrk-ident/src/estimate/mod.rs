//! Estimators, each a function of the observation's R factor: ordinary/weighted least
//! squares on the base parameters ([`ols`]) and the physically consistent semidefinite
//! fit over all parameters ([`sdp`]).

pub mod ols;
pub mod sdp;
mod status;

pub use status::SolverStatus;
