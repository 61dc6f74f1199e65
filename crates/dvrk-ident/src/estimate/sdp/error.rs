//! Why the semidefinite fit could not set up its problem.

use thiserror::Error;

/// Why `solve_sdp` could not set up the problem (infeasibility is not an error: it is
/// reported in `SdpSolution::status`).
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SdpError {
    /// The R factor's size does not match the model's parameters plus the torque column.
    #[error(
        "the R factor is {rows}x{cols}, but model {model} needs {expected}x{expected} \
         ({params} parameters and the torque column)"
    )]
    Dimension {
        /// The model's name.
        model: String,
        /// The R factor's rows.
        rows: usize,
        /// The R factor's columns.
        cols: usize,
        /// The size it should have, `params + 1`.
        expected: usize,
        /// The model's parameter count.
        params: usize,
    },
    /// The prior's values are not one per model parameter.
    #[error("prior has {found} values, model {model} has {expected} parameters")]
    PriorLength {
        /// The model's name.
        model: String,
        /// The prior's value count.
        found: usize,
        /// The model's parameter count.
        expected: usize,
    },
    /// The entropic prior needs a positive definite pseudo-inertia for every link.
    #[error(
        "the prior's link {link} (frame {frame}) is not physically consistent (smallest \
         pseudo-inertia eigenvalue {min_eigenvalue:e}): the entropic metric needs a positive \
         definite prior; use the euclidean metric or a physically consistent prior"
    )]
    PriorInconsistent {
        /// The link's name.
        link: String,
        /// The link's frame index.
        frame: usize,
        /// The smallest eigenvalue of the prior's pseudo-inertia, kg·m² (≤ 0).
        min_eigenvalue: f64,
    },
    /// A NaN or infinity in the R factor or in a bound of the description.
    #[error("non-finite value in {what}")]
    NonFinite {
        /// Where: `the R factor`, or the bound (frame and field).
        what: String,
    },
    /// An `SdpOptions` value out of range (regularization, prior weight, tolerance,
    /// iteration limit).
    #[error("invalid SDP option {name}: {message}")]
    Option {
        /// The option's field name in `SdpOptions`.
        name: &'static str,
        /// The value and the range it should be in.
        message: String,
    },
    /// Clarabel refused its settings or the problem data (its own message).
    #[error("clarabel rejected the problem: {0}")]
    Solver(String),
}
