//! A fit as the front ends ask for it: the logs (files or samples already in memory, or
//! observation states), how to read them ([`ReadOptions`]), the settings changed from
//! their defaults ([`Overrides`]), the excitation the logs follow. The command line and
//! the Python module only map their flags and keyword arguments onto a [`FitRequest`]:
//! everything that decides the result (reading, overriding, streaming, the 2019
//! test-window rule, provenance) happens here, once.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use dvrk_model::Model;

use crate::excite::FourierTrajectory;
use crate::fit::stream::{fit_stream_logs, BLOCK_SAMPLES};
use crate::fit::{fit_logs, LogData};
use crate::log::{self, LogReader, ReadOptions};
use crate::progress::Progress;
use crate::state::ObservationState;
use crate::{FitResult, FitSettings, IdentError, JointLog, Method};

mod overrides;
mod prior;
pub use overrides::{Overrides, Preset, Setting, SettingError};
pub use prior::PriorSource;

/// A log to fit or to test on.
#[derive(Clone, Debug)]
pub enum LogSource {
    /// A file (or rosbag2 folder), read with the request's [`ReadOptions`].
    File(PathBuf),
    /// Samples already read, and the file they came from (for the provenance).
    Samples {
        /// The samples (in the log's joints, as read).
        samples: Arc<JointLog>,
        /// The file or rosbag2 folder they were read from, hashed into the result's `inputs`;
        /// `None` hashes the samples.
        file: Option<PathBuf>,
    },
}

impl LogSource {
    fn path(&self) -> Option<&Path> {
        match self {
            LogSource::File(p) => Some(p),
            LogSource::Samples { file, .. } => file.as_deref(),
        }
    }
}

/// What the training data are.
#[derive(Clone, Debug)]
pub enum Training {
    /// Logs, each processed on its own, their observations merged.
    Logs(Vec<LogSource>),
    /// Observation states of `observe` (the reduce), merged in order and fitted with
    /// their own processing settings and robot; each with the file it was read from
    /// (named when it does not merge).
    Observations(Vec<(Arc<ObservationState>, Option<PathBuf>)>),
}

/// Whether to read the logs block by block from disk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Streaming {
    /// Streamed when a log's files exceed [`STREAM_ABOVE_BYTES`].
    #[default]
    Auto,
    /// Always streamed (files only).
    Always,
    /// Always read into memory.
    Never,
}

impl Streaming {
    /// Whether `logs` are read block by block: never when some are samples already in
    /// memory, always under [`Streaming::Always`], and under [`Streaming::Auto`] when one
    /// of them [`is_large`].
    fn applies<'a>(self, logs: impl Iterator<Item = &'a LogSource> + Clone) -> bool {
        let mut logs = logs;
        if self == Streaming::Never || !logs.clone().all(|l| matches!(l, LogSource::File(_))) {
            return false;
        }
        self == Streaming::Always || logs.any(|l| l.path().is_some_and(is_large))
    }
}

/// Logs larger than this are fitted streamed under [`Streaming::Auto`]: about a tenth
/// of a 24 GiB machine's memory in samples and their processed copies.
pub const STREAM_ABOVE_BYTES: u64 = 256 << 20;

/// Whether a log (its files, for a rosbag2 folder) is large enough to be streamed (a
/// log that cannot be examined is read the usual way, which reports the problem).
pub fn is_large(path: &Path) -> bool {
    log::files_of(path).is_ok_and(|files| {
        files
            .iter()
            .filter_map(|f| std::fs::metadata(f).ok())
            .map(|m| m.len())
            .sum::<u64>()
            > STREAM_ABOVE_BYTES
    })
}

/// A whole fit: see the module docs.
#[derive(Clone, Debug)]
pub struct FitRequest {
    /// What the fit reduces: logs or observation states.
    pub train: Training,
    /// Logs the fitted model is tested on (the result's `metrics.test`); none by default.
    pub test: Vec<LogSource>,
    /// How the files are read (the robot's joints are added, see
    /// [`ReadOptions::for_model`]).
    pub read: ReadOptions,
    /// The base settings (defaults, or a result's), before [`FitRequest::overrides`].
    pub settings: FitSettings,
    /// The CLI's flags and Python's keyword arguments, applied to `settings` the same way
    /// for both.
    pub overrides: Overrides,
    /// The excitation the logs follow: with test logs but no test window, the metrics
    /// cover its first period (the 2019 protocol).
    pub excitation: Option<FourierTrajectory>,
    /// Whether the logs are read block by block (default: by size).
    pub streaming: Streaming,
    /// Samples per block when the logs are streamed (default `BLOCK_SAMPLES`): a
    /// memory knob only, the result is the same to the last bit for any block size.
    pub block_samples: usize,
}

/// The training and the test logs of a fit, in order.
pub type HeldLogs = (Vec<Arc<JointLog>>, Vec<Arc<JointLog>>);

/// What a [`FitRequest`] gives back.
#[derive(Debug)]
pub struct FitOutcome {
    /// The model fitted (with the Stribeck terms of the settings).
    pub model: Model,
    /// The settings used (overrides applied, test window derived).
    pub settings: FitSettings,
    /// The result document.
    pub result: FitResult,
    /// The logs when they were held in memory (not streamed, not observation
    /// states), for figures.
    pub logs: Option<HeldLogs>,
}

impl FitRequest {
    /// A request for these training logs with every option at its default.
    pub fn new(train: Training) -> FitRequest {
        FitRequest {
            train,
            test: Vec::new(),
            read: ReadOptions::default(),
            settings: FitSettings::default(),
            overrides: Overrides::default(),
            excitation: None,
            streaming: Streaming::Auto,
            block_samples: BLOCK_SAMPLES,
        }
    }

    /// A request to fit logs already in memory with `settings` as the base (the
    /// result's `inputs` hash their samples): the shortest way for a program that holds
    /// its logs. Set the other fields as usual (`..FitRequest::of_samples(..)`).
    ///
    /// ```rust
    /// use dvrk_ident::{log, FitRequest, FitSettings, Method};
    ///
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/psm_excitation.mcap");
    /// let samples = log::read(file, None, None).unwrap();
    /// let settings = FitSettings { method: Method::Wls, ..FitSettings::default() };
    /// let request = FitRequest::of_samples([&samples], None, settings);
    /// let result = request.run(Some(&psm), &dvrk_ident::Silent).unwrap().result;
    /// assert_eq!((result.robot.as_str(), result.method.as_str()), ("psm", "wls"));
    /// ```
    pub fn of_samples<'a>(
        train: impl IntoIterator<Item = &'a JointLog>,
        test: impl IntoIterator<Item = &'a JointLog>,
        settings: FitSettings,
    ) -> FitRequest {
        let samples = |logs: &mut dyn Iterator<Item = &'a JointLog>| -> Vec<LogSource> {
            logs.map(|l| LogSource::Samples {
                samples: Arc::new(l.clone()),
                file: None,
            })
            .collect()
        };
        FitRequest {
            test: samples(&mut test.into_iter()),
            settings,
            ..FitRequest::new(Training::Logs(samples(&mut train.into_iter())))
        }
    }

    /// Whether the logs will be read block by block.
    pub fn streams(&self) -> bool {
        match &self.train {
            Training::Observations(_) => false,
            Training::Logs(train) => self.streaming.applies(train.iter().chain(&self.test)),
        }
    }

    /// The fit of `robot` (a built-in, description or URDF model; for observation
    /// states `None` loads the robot they were observed with).
    pub fn run(
        &self,
        robot: Option<&Model>,
        progress: &dyn Progress,
    ) -> Result<FitOutcome, IdentError> {
        if self.overrides.preset.is_some() {
            let from_states = matches!(self.train, Training::Observations(_));
            let mut overrides = self.overrides.expanded(from_states);
            // The preset's prior toward the nominal values: only for the semidefinite fit
            // of a robot that has some (`--prior nominal` would apply); otherwise left
            // out, not refused (`psm_simplified` has none).
            // `--prior none` leaves it out as a robot without nominal masses does.
            let none_given = matches!(self.overrides.prior, Some(PriorSource::None));
            if (self.overrides.prior.is_none() || none_given) && overrides.prior.is_some() {
                let states_robot = match (robot, &self.train) {
                    (None, Training::Observations(states)) => {
                        states.first().and_then(|(s, _)| s.robot_model().ok())
                    }
                    _ => None,
                };
                let applies = !none_given
                    && overrides.method.unwrap_or(self.settings.method) == Method::Sdp
                    && robot
                        .or(states_robot.as_ref())
                        .is_some_and(|m| PriorSource::Nominal.parameters(m).is_ok());
                if !applies {
                    overrides.prior = None;
                    // A weight given beside it asks for the preset's prior: refused
                    // without one (`set_prior`), unless it is 0 (no prior).
                    overrides.prior_weight = self.overrides.prior_weight.filter(|w| *w != 0.0);
                }
            }
            // The description's `[preset]` elements, for a fit of logs (states carry
            // their own model): its position torque, unless the request gives an order
            // (`0`: none).
            let preset_torque = robot.and_then(|m| m.preset.position_torque.as_ref());
            if let Some((order, frames)) = preset_torque.filter(|_| !from_states) {
                if self.overrides.position_torque_order.is_none() {
                    overrides.position_torque_order = Some(*order);
                    if self.overrides.position_torque_frames.is_none() {
                        overrides.position_torque_frames = Some(crate::FrameNames(frames.clone()));
                    }
                }
            }
            let request = FitRequest {
                overrides,
                ..self.clone()
            };
            return request.run(robot, progress);
        }
        self.check_applicable()?;
        let mut outcome = match &self.train {
            Training::Logs(train) => {
                let robot = robot.ok_or_else(|| IdentError::Setting {
                    name: crate::error::SettingName::Argument("robot"),
                    message: "a fit of logs needs the robot".into(),
                })?;
                self.run_logs(robot, train, progress)?
            }
            Training::Observations(states) => self.run_observations(robot, states, progress)?,
        };
        // The prior's file is an input of the result like the logs.
        if let Some(PriorSource::File(path)) = &self.overrides.prior {
            let info = crate::result::InputInfo::from_file("prior", path)?;
            outcome.result.inputs.push(info);
        }
        Ok(outcome)
    }

    /// Refuses a setting given for this fit that would change nothing in it, as a
    /// sampling rate for a log with its own time stamps is refused: the user asked for
    /// something the fit would silently not do. (Settings from `settings`, the base,
    /// are a whole document and are not checked.)
    fn check_applicable(&self) -> Result<(), IdentError> {
        let o = &self.overrides;
        let method = o.method.unwrap_or(self.settings.method);
        let refuse = |name: Setting, message: String| {
            Err(IdentError::Setting {
                name: name.into(),
                message,
            })
        };
        if o.irls_iterations.is_some() && method != Method::Irls {
            return refuse(
                Setting::IrlsIterations,
                format!(
                    "only the irls method re-weights, and this fit's method is {}",
                    method.name()
                ),
            );
        }
        if o.sdp_regularization.is_some() && method != Method::Sdp {
            return refuse(
                Setting::SdpRegularization,
                format!(
                    "only the semidefinite fit (method sdp) is regularized, and this fit's \
                     method is {}",
                    method.name()
                ),
            );
        }
        if o.bounds.is_some() && method != Method::Sdp {
            return refuse(
                Setting::Bounds,
                format!(
                    "the bounds are the semidefinite fit's (method sdp); method {} has none",
                    method.name()
                ),
            );
        }
        if o.ellipsoids.is_some() && method != Method::Sdp {
            return refuse(
                Setting::Ellipsoids,
                format!(
                    "the bounding ellipsoids are the semidefinite fit's (method sdp); method {} \
                     has none",
                    method.name()
                ),
            );
        }
        if o.select.is_some() || self.settings.select.is_some() {
            if let Some(given) = [
                (Setting::Stribeck, o.stribeck_velocity.is_some()),
                (Setting::Dahl, o.dahl_sigma.is_some()),
            ]
            .iter()
            .find(|(_, given)| *given)
            {
                return refuse(
                    Setting::Select,
                    format!(
                        "the candidates give the friction terms, and {} is given too: name it \
                         in a candidate (e.g. select coulomb,stribeck:0.2)",
                        given.0.name()
                    ),
                );
            }
            let why = match &self.train {
                Training::Observations(_) => Some("observation states"),
                Training::Logs(_) if self.streams() => Some("streamed logs"),
                Training::Logs(_) => None,
            };
            if let Some(why) = why {
                return refuse(
                    Setting::Select,
                    format!(
                        "the folds cut the processed samples in memory, which {why} do not \
                         hold"
                    ),
                );
            }
        }
        if o.test_window.is_some() && self.test.is_empty() {
            return refuse(
                Setting::TestWindow,
                "the test window is counted in the test logs, and none is given (test)".into(),
            );
        }
        let filtered = match &o.cutoff {
            Some(cutoff) => cutoff.is_some(),
            None => self.settings.processing.filter.is_some(),
        };
        if o.filter_order.is_some() && !filtered {
            return refuse(
                Setting::FilterOrder,
                "the order is the motion's low-pass filter's, and there is none (cutoff none)"
                    .into(),
            );
        }
        if o.filter_torque == Some(true) && !filtered {
            return refuse(
                Setting::FilterTorque,
                "the torques get the motion's low-pass filter, and there is none (cutoff none)"
                    .into(),
            );
        }
        Ok(())
    }

    fn run_logs(
        &self,
        robot: &Model,
        train: &[LogSource],
        progress: &dyn Progress,
    ) -> Result<FitOutcome, IdentError> {
        if train.is_empty() {
            return Err(crate::fit::no_training_log());
        }
        let settings = self.overrides.settings_for(self.settings.clone(), robot)?;
        let model = settings.model(robot)?.into_owned();
        let read = self
            .read
            .for_model(&model)
            .for_processing(&settings.processing)
            .for_logs(train.iter().chain(&self.test).filter_map(LogSource::path));
        if self.streams() {
            if self.excitation.is_some() && !self.test.is_empty() && settings.test_window.is_none()
            {
                return Err(IdentError::Setting {
                    name: crate::options::Setting::TestWindow.into(),
                    message: "a streamed fit with an excitation needs a test window \
                              (samples of one period)"
                        .into(),
                });
            }
            let (train, test) = (open_all(&read, train)?, open_all(&read, &self.test)?);
            let result = fit_stream_logs(
                &model,
                &train.iter().collect::<Vec<_>>(),
                &test.iter().collect::<Vec<_>>(),
                &settings,
                self.block_samples,
                progress,
            )?;
            return Ok(FitOutcome {
                model,
                settings,
                result,
                logs: None,
            });
        }
        let train_data = read_all(&read, train, progress)?;
        let train_logs = log_data(&train_data, train);
        let (model, settings, selection) = match &settings.select {
            None => (model, settings, None),
            Some(candidates) => {
                let (selection, chosen) = crate::fit::select::select(
                    robot,
                    &train_logs,
                    &settings,
                    candidates,
                    progress,
                )?;
                // The winner on all the data; the settings keep the candidates asked for.
                let settings = FitSettings {
                    select: settings.select.clone(),
                    ..chosen.settings(&settings)
                };
                let model = settings.model(robot)?.into_owned();
                (model, settings, Some(selection))
            }
        };
        let mut outcome = self.fit_with_test(
            model,
            settings,
            &read,
            Some(&train_data),
            progress,
            |m, s, test| fit_logs(m, &train_logs, test, s, progress),
        )?;
        outcome.result.selection = selection;
        Ok(outcome)
    }

    fn run_observations(
        &self,
        robot: Option<&Model>,
        states: &[(Arc<ObservationState>, Option<PathBuf>)],
        progress: &dyn Progress,
    ) -> Result<FitOutcome, IdentError> {
        let fields = self.overrides.observation_fields();
        if !fields.is_empty() {
            return Err(IdentError::Setting {
                name: crate::error::SettingName::Options(fields.to_vec()),
                message: "the processing (and the Stribeck terms) of observation states are \
                          their own, set when they were observed: give these options to observe"
                    .into(),
            });
        }
        let ((first, _), rest) = states
            .split_first()
            .ok_or_else(crate::fit::no_training_log)?;
        // Every state checked against the robot on its own, so that an error names its
        // file, before any is merged.
        let named = |file: &Option<PathBuf>, e: IdentError| match file {
            Some(f) if !e.to_string().contains(&f.display().to_string()) => IdentError::State {
                file: f.display().to_string(),
                message: e.to_string(),
            },
            _ => e,
        };
        let base = match robot {
            Some(r) => r.clone(),
            None => first.robot_model().map_err(|e| named(&states[0].1, e))?,
        };
        for (s, file) in states {
            s.model(&base).map_err(|e| named(file, e))?;
        }
        let mut state = ObservationState::clone(first);
        for (s, file) in rest {
            state.merge(s).map_err(|e| named(file, e))?;
        }
        let model = state.model(&base)?;
        let mut settings = state.settings(&self.overrides.apply(self.settings.clone()));
        self.overrides.set_prior(&mut settings, &model)?;
        let read = self
            .read
            .for_model(&model)
            .for_processing(&settings.processing)
            .for_logs(self.test.iter().filter_map(LogSource::path));
        self.fit_with_test(model, settings, &read, None, progress, |_, s, test| {
            state.fit(&base, s, test, progress)
        })
    }

    /// The outcome of `fit` (of the model, the settings and the test logs), the test logs
    /// read in memory and `settings.test_window` derived from them; with the training
    /// logs `train` held in memory, the outcome keeps them and the test logs.
    fn fit_with_test(
        &self,
        model: Model,
        mut settings: FitSettings,
        read: &ReadOptions,
        train: Option<&[Arc<JointLog>]>,
        progress: &dyn Progress,
        fit: impl FnOnce(&Model, &FitSettings, &[LogData<'_>]) -> Result<FitResult, IdentError>,
    ) -> Result<FitOutcome, IdentError> {
        let test_data = self.read_test(read, &mut settings, progress)?;
        let result = fit(&model, &settings, &log_data(&test_data, &self.test))?;
        Ok(FitOutcome {
            model,
            settings,
            result,
            logs: train.map(|t| (t.to_vec(), test_data)),
        })
    }

    /// The test logs in memory, and `settings.test_window` derived from them (see
    /// [`FitRequest::test_window`]).
    fn read_test(
        &self,
        read: &ReadOptions,
        settings: &mut FitSettings,
        progress: &dyn Progress,
    ) -> Result<Vec<Arc<JointLog>>, IdentError> {
        let test = read_all(read, &self.test, progress)?;
        settings.test_window = self.test_window(settings, &test)?;
        Ok(test)
    }

    /// The test window: given, or with an excitation and test logs one period of it at
    /// the first test log's rate (`int(rate / f0)` samples as in 2019: 1111 for the PSM at
    /// 200 Hz and 0.18 Hz), in processed (decimated) samples.
    fn test_window(
        &self,
        settings: &FitSettings,
        test: &[Arc<JointLog>],
    ) -> Result<Option<usize>, IdentError> {
        if let (None, Some(traj), Some(t)) = (settings.test_window, &self.excitation, test.first())
        {
            let rate = t.rate_hz().ok_or_else(|| IdentError::Setting {
                name: crate::error::SettingName::Argument("excitation"),
                message: format!(
                    "{}: the test log has no usable time stamps for one period of the excitation",
                    self.test
                        .first()
                        .and_then(|l| l.path())
                        .map_or_else(|| t.source.clone(), |p| p.display().to_string())
                ),
            })?;
            let samples = (traj.period_s() * rate + 1e-9).floor() as usize;
            return Ok(Some(samples / settings.processing.decimate.max(1)));
        }
        Ok(settings.test_window)
    }
}

/// The map of a distributed fit as the front ends ask for it (`dvrk-ident observe`,
/// Python's `observe`): the logs processed and reduced exactly as a [`FitRequest`]
/// processes them before its estimator, into one [`ObservationState`]. Reading,
/// overriding and the streaming decision happen here, so both front ends give the same
/// state byte for byte.
///
/// ```rust
/// use dvrk_ident::Silent;
/// use dvrk_ident::{LogSource, ObserveRequest, Overrides, Streaming};
/// use dvrk_model::Model;
///
/// let log = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/psm_excitation.mcap");
/// let psm = Model::load("psm").unwrap();
/// let request = ObserveRequest {
///     overrides: Overrides { trim: Some(20), ..Overrides::default() },
///     ..ObserveRequest::new(vec![LogSource::File(log.into())])
/// };
/// let state = request.run(&psm, &Silent).unwrap();
/// assert_eq!((state.robot.as_str(), state.processing.trim), ("psm", 20));
/// // Read block by block, the state is the same to the last bit.
/// let streamed = ObserveRequest { streaming: Streaming::Always, ..request }.run(&psm, &Silent);
/// assert_eq!(streamed.unwrap().to_bytes(), state.to_bytes());
/// ```
#[derive(Clone, Debug)]
pub struct ObserveRequest {
    /// The logs, each processed on its own; the state holds them all.
    pub logs: Vec<LogSource>,
    /// How the files are read (the robot's joints are added, see
    /// [`ReadOptions::for_model`]).
    pub read: ReadOptions,
    /// The base settings (defaults, or a result's), before [`ObserveRequest::overrides`].
    pub settings: FitSettings,
    /// The processing (and Stribeck terms) changed from the base; a delay search is
    /// refused (it needs every log of the fit at once).
    pub overrides: Overrides,
    /// Whether the files are read block by block.
    pub streaming: Streaming,
}

impl ObserveRequest {
    /// A request for these logs with every option at its default.
    pub fn new(logs: Vec<LogSource>) -> ObserveRequest {
        ObserveRequest {
            logs,
            read: ReadOptions::default(),
            settings: FitSettings::default(),
            overrides: Overrides::default(),
            streaming: Streaming::Auto,
        }
    }

    /// Whether the logs will be read block by block (the rule of
    /// [`FitRequest::streams`]).
    pub fn streams(&self) -> bool {
        self.streaming.applies(self.logs.iter())
    }

    /// The observation state of `robot` (a built-in, description or URDF model).
    pub fn run(
        &self,
        robot: &Model,
        progress: &dyn Progress,
    ) -> Result<ObservationState, IdentError> {
        if self.logs.is_empty() {
            return Err(crate::fit::no_training_log());
        }
        let settings = self.overrides.settings_for(self.settings.clone(), robot)?;
        crate::fit::no_delay_search(&settings, "an observation state")?;
        let read = self
            .read
            .for_model(settings.model(robot)?.as_ref())
            .for_processing(&settings.processing)
            .for_logs(self.logs.iter().filter_map(LogSource::path));
        if self.streams() {
            let readers = open_all(&read, &self.logs)?;
            return ObservationState::observe_stream(
                robot,
                &readers.iter().collect::<Vec<_>>(),
                &settings,
                BLOCK_SAMPLES,
                progress,
            );
        }
        let data = read_all(&read, &self.logs, progress)?;
        ObservationState::observe(robot, &log_data(&data, &self.logs), &settings, progress)
    }
}

/// A block reader of every log's file, in order (files only: a streamed request holds
/// no samples in memory, see [`Streaming`]).
fn open_all(read: &ReadOptions, logs: &[LogSource]) -> Result<Vec<LogReader>, IdentError> {
    logs.iter()
        .filter_map(|l| l.path())
        .map(|p| Ok(read.open(p)?))
        .collect()
}

/// Every log in memory, in order (files read with `read`).
fn read_all(
    read: &ReadOptions,
    logs: &[LogSource],
    progress: &dyn Progress,
) -> Result<Vec<Arc<JointLog>>, IdentError> {
    logs.iter()
        .map(|l| match l {
            LogSource::File(p) => {
                progress.stage(&format!("reading {}", p.display()), None);
                let t = read.read(p);
                progress.finish();
                Ok(Arc::new(t?))
            }
            LogSource::Samples { samples, .. } => Ok(samples.clone()),
        })
        .collect()
}

fn log_data<'a>(data: &'a [Arc<JointLog>], logs: &'a [LogSource]) -> Vec<LogData<'a>> {
    data.iter()
        .zip(logs)
        .map(|(samples, l)| LogData {
            samples,
            file: l.path(),
        })
        .collect()
}
