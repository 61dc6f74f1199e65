//! How an estimator ended: Clarabel's statuses as a type of our own, so a result
//! document names them the same way whatever the solver's version, and code matches on
//! them instead of on strings.

use serde::{Deserialize, Serialize};

/// The end state of an estimator. Least squares always ends [`SolverStatus::Solved`];
/// the semidefinite fit takes Clarabel's status. Serialized as the variant's name
/// (`"Solved"`, `"AlmostSolved"`, ...).
///
/// ```rust
/// use dvrk_ident::SolverStatus;
///
/// assert!(SolverStatus::Solved.converged());
/// // Reduced accuracy is not a result.
/// assert!(!SolverStatus::AlmostSolved.converged());
/// assert_eq!(SolverStatus::AlmostSolved.to_string(), "AlmostSolved");
/// assert_eq!(serde_json::to_string(&SolverStatus::MaxIterations).unwrap(), "\"MaxIterations\"");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SolverStatus {
    /// The solver did not start or was not run to an end.
    Unsolved,
    /// Solved to full accuracy: the only status that is a result.
    Solved,
    /// No parameters satisfy the constraints (bounds, pseudo-inertia LMIs).
    PrimalInfeasible,
    /// The dual problem is infeasible: the objective is unbounded below on the constraints.
    DualInfeasible,
    /// Met only Clarabel's reduced tolerances: not a result.
    AlmostSolved,
    /// Infeasible to reduced tolerances.
    AlmostPrimalInfeasible,
    /// Dual infeasible (unbounded) to reduced tolerances.
    AlmostDualInfeasible,
    /// Stopped at the iteration limit.
    MaxIterations,
    /// Stopped at the time limit.
    MaxTime,
    /// Stopped by a numerical failure (e.g. a singular factorization).
    NumericalError,
    /// Stopped because the iterates no longer improved.
    InsufficientProgress,
    /// Stopped by a user callback (not used by this crate).
    CallbackTerminated,
}

impl SolverStatus {
    /// Only `Solved` is a result: the "almost" statuses met reduced tolerances.
    pub fn converged(self) -> bool {
        self == SolverStatus::Solved
    }

    /// The problem (bounds, constraints) has no solution, to the solver's tolerance.
    pub fn infeasible(self) -> bool {
        matches!(
            self,
            SolverStatus::PrimalInfeasible
                | SolverStatus::DualInfeasible
                | SolverStatus::AlmostPrimalInfeasible
                | SolverStatus::AlmostDualInfeasible
        )
    }
}

impl std::fmt::Display for SolverStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Debug::fmt(self, f)
    }
}

impl From<clarabel::solver::SolverStatus> for SolverStatus {
    fn from(s: clarabel::solver::SolverStatus) -> Self {
        use clarabel::solver::SolverStatus as C;
        match s {
            C::Unsolved => SolverStatus::Unsolved,
            C::Solved => SolverStatus::Solved,
            C::PrimalInfeasible => SolverStatus::PrimalInfeasible,
            C::DualInfeasible => SolverStatus::DualInfeasible,
            C::AlmostSolved => SolverStatus::AlmostSolved,
            C::AlmostPrimalInfeasible => SolverStatus::AlmostPrimalInfeasible,
            C::AlmostDualInfeasible => SolverStatus::AlmostDualInfeasible,
            C::MaxIterations => SolverStatus::MaxIterations,
            C::MaxTime => SolverStatus::MaxTime,
            C::NumericalError => SolverStatus::NumericalError,
            C::InsufficientProgress => SolverStatus::InsufficientProgress,
            C::CallbackTerminated => SolverStatus::CallbackTerminated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every Clarabel status maps to ours with the same name, which is what result
    /// documents written before this type hold.
    #[test]
    fn names_match_clarabel() {
        use clarabel::solver::SolverStatus as C;
        for c in [
            C::Unsolved,
            C::Solved,
            C::PrimalInfeasible,
            C::DualInfeasible,
            C::AlmostSolved,
            C::AlmostPrimalInfeasible,
            C::AlmostDualInfeasible,
            C::MaxIterations,
            C::MaxTime,
            C::NumericalError,
            C::InsufficientProgress,
            C::CallbackTerminated,
        ] {
            let ours = SolverStatus::from(c);
            assert_eq!(ours.to_string(), format!("{c:?}"));
            let json = serde_json::to_string(&ours).unwrap();
            assert_eq!(serde_json::from_str::<SolverStatus>(&json).unwrap(), ours);
            assert_eq!(ours.converged(), c == C::Solved);
        }
    }
}

/// Solver statistics; `converged` false means the numbers are NOT a result.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SolverInfo {
    /// `qr` for the least-squares methods, `clarabel` for the semidefinite one.
    pub name: String,
    /// The solver's end state (Clarabel's status name; always `Solved` for least
    /// squares); anything but `Solved`, `AlmostSolved` included, is not a result.
    pub status: SolverStatus,
    /// `status` is `Solved`: the flag scripts should check before using the numbers.
    pub converged: bool,
    /// Wall time, s: Clarabel's solve time, or for least squares the estimation from the
    /// observation's R factors (IRLS re-weightings included).
    pub seconds: f64,
    /// Solver iterations: Clarabel's, or 1 + the re-weightings for IRLS, 1 for OLS/WLS.
    pub iterations: u32,
    /// The semidefinite solver's feasibility and gap tolerance (relative, in its scaled
    /// problem): the link pseudo-inertias satisfy `J ⪰ eps·I` to it, while friction and
    /// motor inertia bounds hold exactly (projected after the solve).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
}
