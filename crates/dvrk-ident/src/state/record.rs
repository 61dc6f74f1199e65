//! What a state holds (see [`super`]): the robot and processing it was reduced for,
//! and the reduced logs. Its operations are the state's (merge and fit) and the
//! codec's (the file).

use crate::fit::Observed;
use crate::signal::Processing;

/// The training logs of a fit reduced, with what identifies the model and the
/// processing they were reduced for (see the module docs).
#[derive(Clone, Debug)]
pub struct ObservationState {
    /// The file the state was read from (named in errors); `None` for a state made in
    /// memory.
    pub file: Option<String>,
    /// The robot's name from its description, e.g. `psm`.
    pub robot: String,
    /// `builtin:psm` or the description's path, as [`Model::load`](dvrk_model::Model::load) takes it (without
    /// `builtin:`).
    pub robot_source: String,
    /// [`model_hash`](super::model_hash) of the model of the fit (Stribeck terms included).
    pub robot_hash: String,
    /// The processing the logs were reduced with; a fit of the state uses it unchanged.
    pub processing: Processing,
    /// The Stribeck velocity of the model the logs were reduced for, rad/s or m/s (it adds
    /// regressor columns); states to merge must agree on it.
    pub stribeck_velocity: Option<f64>,
    /// The mounting pitch (degrees) whose gravity the logs were reduced with; states to
    /// merge must agree on it.
    pub mounting_pitch_deg: Option<f64>,
    /// The reduced logs: each log's factors, their merge and the torque range.
    pub(crate) observed: Observed,
}
