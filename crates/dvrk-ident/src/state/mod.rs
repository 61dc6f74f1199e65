//! Observation states: training logs reduced to their per-coordinate R factors, in a
//! file, so that engines outside this process (a shell loop, `xargs -P`, a Slurm array,
//! Dask, Ray, Spark) can run the map (`dvrk-ident observe`, one state per log) and the
//! reduce (merging states) of a fit, and a fit of the merged state gives the document
//! of the fit of the logs themselves (`dvrk-ident fit --states`).
//!
//! A state holds what the merge and the later fit need: the robot (name, source and a
//! hash of the model as built, [`model_hash`]), the processing settings and the
//! Stribeck velocity of the fit's model, the running range of the processed torques
//! (the WLS weights), every log's provenance (path, SHA-256, bytes, source, samples)
//! and per-coordinate factors (its own training metrics), and the factors of all the
//! logs merged. Merging refuses states of other robots or settings; it merges the
//! factors (a QR of the two stacked, exact up to rounding, so associative and
//! commutative to rounding), joins the ranges and lists the logs in order.
//!
//!
//! The file format is `codec`'s (`state/codec.rs`).

use dvrk_model::Model;
use sha2::{Digest, Sha256};

use crate::error::IdentError;
use crate::fit::{fit_observed, prepare_logs, test_inputs, LogData, Observed};
use crate::log::LogReader;
use crate::progress::Progress;
use crate::result::{FitResult, InputInfo};
use crate::settings::FitSettings;
use crate::signal::Processing;

mod codec;
mod record;
pub use record::ObservationState;

#[cfg(all(test, feature = "recordings"))]
pub(crate) use codec::MAGIC;

/// SHA-256 (hex) of what makes a model's regressor: coordinates, measured joints and
/// coupling, gravity, every frame's name, parent, joint, joint value, fixed transforms
/// and elements (friction with its Stribeck velocity, motor inertia, spring deflection,
/// known force), and the parameter names. Bounds, limits and nominal values are left
/// out: they do not change an observation, and so are the frames with no parameter in
/// their subtree (a tool tip: kinematics only), so that adding one keeps the states
/// observed before. Two loads of the same description hash the same on any machine
/// that parses numbers and evaluates `sin`/`cos` alike.
pub fn model_hash(model: &Model) -> String {
    // Frames (1-based) with a parameter in their subtree: those with a link or an
    // element, and their ancestors.
    let mut carries = vec![false; model.frames.len() + 1];
    for (i, f) in model.frames.iter().enumerate() {
        if f.inertia.is_some() || !f.elements.is_empty() {
            let mut k = i + 1;
            while k != 0 && !carries[k] {
                carries[k] = true;
                k = model.frames[k - 1].parent;
            }
        }
    }
    let mut h = Sha256::new();
    let mut text = |t: &str| {
        h.update((t.len() as u64).to_le_bytes());
        h.update(t.as_bytes());
    };
    text(&model.name);
    for c in &model.coordinates {
        text(c);
    }
    for j in &model.measured.joints {
        text(j);
    }
    let mut numbers: Vec<f64> = model.measured.coupling.iter().copied().collect();
    numbers.extend(model.gravity.iter());
    let mut words: Vec<String> = Vec::new();
    for (f, _) in model.frames.iter().zip(&carries[1..]).filter(|(_, &c)| c) {
        words.push(f.name.clone());
        words.push(format!("{}:{:?}", f.parent, f.kind));
        f.value.push_numbers(&mut numbers);
        for t in [&f.pre, &f.post] {
            numbers.extend(t.rotation.iter());
            numbers.extend(t.translation.iter());
        }
        let index = |i: Option<usize>| i.map_or(-1.0, |i| i as f64);
        numbers.push(index(f.inertia));
        // A frame without friction marks its place (the layout of the first hashes,
        // kept so that earlier observation states still merge); friction, when there,
        // is the frame's first element.
        if f.friction().is_none() {
            numbers.push(-1.0);
        }
        for e in &f.elements {
            e.fingerprint(&mut numbers, &mut words);
        }
    }
    for p in &model.params {
        words.push(p.name.clone());
    }
    for w in &words {
        text(w);
    }
    for x in numbers {
        h.update(x.to_le_bytes());
    }
    format!("{:x}", h.finalize())
}

impl ObservationState {
    /// The state of reduced logs: `model` is the robot as loaded, `settings` those of
    /// the reduction (the processing and the Stribeck velocity are kept).
    pub(crate) fn new(
        model: &Model,
        settings: &FitSettings,
        observed: Observed,
    ) -> Result<ObservationState, IdentError> {
        let fitted = settings.model(model)?;
        Ok(ObservationState {
            file: None,
            robot: model.name.clone(),
            robot_source: model.source.clone(),
            robot_hash: model_hash(&fitted),
            processing: settings.processing.clone(),
            stribeck_velocity: settings.stribeck_velocity,
            mounting_pitch_deg: settings.mounting_pitch_deg,
            observed,
        })
    }

    /// The map: training logs in memory, each processed on its own and reduced, as
    /// the fit of logs in memory does before the estimator.
    pub(crate) fn observe(
        model: &Model,
        logs: &[LogData<'_>],
        settings: &FitSettings,
        progress: &dyn Progress,
    ) -> Result<ObservationState, IdentError> {
        let fitted = settings.model(model)?;
        progress.stage("processing", None);
        let data = prepare_logs(&fitted, logs, &settings.processing)?;
        progress.finish();
        let observed = crate::fit::observe_prepared(&fitted, logs, &data, progress)?;
        ObservationState::new(model, settings, observed)
    }

    /// The map of logs read from their files block by block
    /// ([`crate::fit::stream::observe_stream_logs`]): the same state as [`Self::observe`].
    pub(crate) fn observe_stream(
        model: &Model,
        logs: &[&LogReader],
        settings: &FitSettings,
        block_samples: usize,
        progress: &dyn Progress,
    ) -> Result<ObservationState, IdentError> {
        let fitted = settings.model(model)?;
        let observed = crate::fit::stream::observe_stream_logs(
            &fitted,
            logs,
            settings,
            block_samples,
            progress,
        )?;
        ObservationState::new(model, settings, observed)
    }

    /// The state's logs, for messages: `observation of a.mcap + b.csv`.
    pub fn name(&self) -> String {
        let names: Vec<&str> = self
            .observed
            .logs
            .iter()
            .map(|l| {
                if l.info.path.is_empty() {
                    l.info.source.as_str()
                } else {
                    l.info.path.as_str()
                }
            })
            .collect();
        format!("observation of {}", names.join(" + "))
    }

    /// What names this state in errors: its file, else its logs ([`Self::name`]).
    fn label(&self) -> String {
        self.file.clone().unwrap_or_else(|| self.name())
    }

    /// The coordinates and the factor width (parameters + 1) of the state.
    fn shape(&self) -> (usize, usize) {
        let parts = &self.observed.parts;
        (parts.len(), parts.first().map_or(0, |p| p.r().ncols()))
    }

    /// Each log's provenance (role `train`, path, hash, bytes, source) and its processed
    /// samples, in the order the logs were observed and merged.
    pub fn logs(&self) -> impl ExactSizeIterator<Item = (&InputInfo, usize)> {
        self.observed
            .logs
            .iter()
            .map(|l| (&l.info, l.parts.first().map_or(0, |p| p.rows())))
    }

    /// Processed samples of all the logs.
    pub fn samples(&self) -> usize {
        self.observed.samples()
    }

    /// Why `other` cannot be merged with this state, if it cannot.
    fn mismatch(&self, other: &ObservationState) -> Option<String> {
        if self.robot_hash != other.robot_hash {
            return Some(format!(
                "robot {} (model hash {}) differs from robot {} (model hash {}) of the \
                 states before it: states of different robots do not merge",
                other.robot,
                &other.robot_hash[..12.min(other.robot_hash.len())],
                self.robot,
                &self.robot_hash[..12.min(self.robot_hash.len())]
            ));
        }
        if self.shape() != other.shape() {
            return Some(format!(
                "{} coordinates and factors of width {} differ from {} and {} of the \
                 states before it",
                other.shape().0,
                other.shape().1,
                self.shape().0,
                self.shape().1
            ));
        }
        if self.processing != other.processing {
            let show = |p: &Processing| serde_json::to_string(p).unwrap_or_default();
            return Some(format!(
                "processing settings {} differ from {} of the states before it: states \
                 processed differently do not merge (observe every log with the same options)",
                show(&other.processing),
                show(&self.processing)
            ));
        }
        if self.stribeck_velocity != other.stribeck_velocity {
            return Some(format!(
                "Stribeck velocity {:?} differs from {:?} of the states before it",
                other.stribeck_velocity, self.stribeck_velocity
            ));
        }
        if self.mounting_pitch_deg != other.mounting_pitch_deg {
            return Some(format!(
                "mounting pitch {:?}° differs from {:?}° of the states before it",
                other.mounting_pitch_deg, self.mounting_pitch_deg
            ));
        }
        None
    }

    /// The reduce: the logs of `other` after these. Refuses (naming `other`'s logs) a
    /// state of another robot, processing or Stribeck velocity.
    pub fn merge(&mut self, other: &ObservationState) -> Result<(), IdentError> {
        if let Some(message) = self.mismatch(other) {
            return Err(IdentError::Mismatch {
                source_name: other.label(),
                message,
            });
        }
        self.observed.merge(&other.observed);
        Ok(())
    }

    /// The settings of a fit of this state: the estimator's (`method`, `test_window`,
    /// `irls_iterations`, `sdp_regularization`) from `estimator`, the processing and
    /// the Stribeck velocity from the state.
    pub fn settings(&self, estimator: &FitSettings) -> FitSettings {
        FitSettings {
            processing: self.processing.clone(),
            stribeck_velocity: self.stribeck_velocity,
            mounting_pitch_deg: self.mounting_pitch_deg,
            ..estimator.clone()
        }
    }

    /// `model` (the robot as loaded) with the state's model options, refused unless it
    /// is the model the state was reduced for.
    pub fn model(&self, model: &Model) -> Result<Model, IdentError> {
        let fitted = self.settings(&FitSettings::default()).model(model)?;
        let hash = model_hash(&fitted);
        if hash != self.robot_hash {
            return Err(IdentError::Mismatch {
                source_name: self.label(),
                message: format!(
                    "reduced for robot {} (model hash {}), but the robot given is {} from {} \
                     (model hash {}): give the robot the logs were observed with",
                    self.robot,
                    &self.robot_hash[..12.min(self.robot_hash.len())],
                    model.name,
                    model.source,
                    &hash[..12]
                ),
            });
        }
        // The hash is the file's word only: its factors must have the model's shape.
        let expected = (fitted.dof(), fitted.n_params() + 1);
        if self.shape() != expected {
            return Err(IdentError::State {
                file: self.label(),
                message: format!(
                    "{} coordinates and factors of width {}, but its robot {} has {} \
                     coordinates and {} parameters (width {}): the file was altered",
                    self.shape().0,
                    self.shape().1,
                    fitted.name,
                    expected.0,
                    expected.1 - 1,
                    expected.1
                ),
            });
        }
        Ok(fitted.into_owned())
    }

    /// The robot the state was observed with, loaded from its recorded source (a
    /// built-in name or a description path).
    pub fn robot_model(&self) -> Result<Model, IdentError> {
        let robot = crate::result::loadable_robot(&self.robot_source);
        Model::load(robot).map_err(|e| IdentError::State {
            file: self.label(),
            message: format!("its robot {robot}: {e}"),
        })
    }

    /// The fit of the state's logs with the estimator settings of `estimator` (see
    /// [`Self::settings`]), validated on `test` logs (processed with the state's
    /// settings): the document of the fit of the same logs. A program runs it through
    /// [`crate::FitRequest`] ([`crate::Training::Observations`]).
    pub(crate) fn fit(
        &self,
        model: &Model,
        estimator: &FitSettings,
        test: &[LogData<'_>],
        progress: &dyn Progress,
    ) -> Result<FitResult, IdentError> {
        let settings = self.settings(estimator);
        crate::fit::no_delay_search(&settings, "a fit of observation states")?;
        let model = self.model(model)?;
        // The estimator's bounds (not part of the state: no column depends on them).
        let model = settings.model(&model)?;
        let model: &Model = &model;
        progress.stage("processing", None);
        let test_data = prepare_logs(model, test, &settings.processing)?;
        progress.finish();
        fit_observed(
            model,
            &self.observed,
            &settings,
            crate::fit::MetricPasses {
                train: None,
                test: &|params: &[f64]| {
                    test_inputs(model, test, &test_data, params, settings.test_window)
                },
            },
            progress,
        )
    }
}
