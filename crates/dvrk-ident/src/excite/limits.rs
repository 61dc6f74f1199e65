//! The limits an excitation trajectory must respect, compiled for the optimizer and the
//! dense feasibility check.
//!
//! Two kinds, both checked at every sample of a time grid:
//!
//! * joint limits (the description's `[[limits]]`): ranges of position, velocity and
//!   acceleration of affine combinations of the coordinates. They are linear in the
//!   Fourier coefficients, so the largest feasible step along a segment is exact;
//! * Cartesian boxes (`[[cartesian_limits]]`): the origin of a frame stays within
//!   `[min, max]` per base-frame axis. They are nonlinear; their gradient goes through
//!   the frame-origin Jacobian, and steps along a segment are found by bisection against
//!   the grid.
//!
//! Every bounded scalar is an `Item`; on a grid of `T` samples the constraint values
//! are indexed `2·(k·m + i) + side` (`m` items, side 0 = lower, 1 = upper), normalized by
//! the item's range so that one penalty weight suits radians, metres and rates alike.

mod constraints;
mod repair;

pub(crate) use constraints::{Constraints, Enforced, Multipliers};
pub use constraints::{Feasibility, Limits, Violation};
