//! A result on other logs: the samples a log gives once processed as the fit processes
//! them ([`prepare`], [`Prepared`]), the torques a result's parameters predict on them
//! ([`predict`]) and their errors per joint ([`joint_metrics`]), in the joints the fit
//! reports ([`JointMap`]). The command line's `validate` and Python's `FitResult.validate`,
//! `prepare` and `predict` are these functions.

pub use crate::fit::{joint_metrics, predict, prepare, JointMap, Prepared};
