//! Unit tests that drive the whole pipeline ([`crate::FitRequest`]) to check one stage:
//! the estimator's treatment of the model's elements and the observation states' merge,
//! files and refusals. They live here, at the root, rather than beside the stage: a
//! stage's own tests that reached the request would make the stage depend on every module
//! above it (`tools/module_cycles.py` counts test modules too).

mod elements;
#[cfg(feature = "recordings")]
mod state;
