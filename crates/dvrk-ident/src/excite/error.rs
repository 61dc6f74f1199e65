//! The excitation errors, a leaf module: the limits compiler, the optimizer and the
//! evaluator all return them.

use thiserror::Error;

use super::FourierError;

/// Errors of the optimizer and evaluator.
#[derive(Debug, Error)]
pub enum ExciteError {
    /// The limits admit no trajectory (not even a static pose), or are malformed.
    #[error("impossible limits: {0}")]
    ImpossibleLimits(String),
    /// No start produced a trajectory that passes the dense feasibility check.
    #[error("no feasible trajectory found: {0}")]
    Infeasible(String),
    /// Bad options or a trajectory that does not fit the model.
    #[error("{0}")]
    Invalid(String),
    /// A Fourier trajectory that could not be read or is not usable (a starting point,
    /// or the trajectory to check).
    #[error(transparent)]
    Fourier(#[from] FourierError),
}
