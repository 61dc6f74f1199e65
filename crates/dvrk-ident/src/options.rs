//! The fit options, each declared once: its field of [`Overrides`](crate::request::Overrides),
//! its name (the command line's flag `--name`, Python's keyword `name=`, the serde
//! key), its documentation (the flag's help) and the type its value is read as. The
//! `fit_options!` list below makes [`Setting`], which names each option in errors,
//! here, in a module that depends on nothing (so that [`crate::IdentError`] can carry a
//! `Setting`); `request/overrides.rs` makes the struct and the conversion from values
//! from the same list.
//!
//! **Adding a fit option**: one entry in the list (doc, field, type, variant, name), its
//! effect in `Overrides::apply` (or `settings_for`) and its default's text in
//! `Setting::default_text` (`request/overrides.rs`), and the command line's flag
//! details (heading, value name) in dvrk-cli's `cmd/settings.rs`, whose exhaustive
//! `match` does not compile without it; Python takes it as a keyword with no edit but
//! the type stub, which a test checks against [`Setting::ALL`].

/// The list of fit options, handed to the macro `$then` (the types are named as
/// `request/overrides.rs` imports them: this module expands the list without them).
macro_rules! fit_options {
    ($then:ident) => {
        $then! {
            /// Estimator: ordinary, weighted or iteratively re-weighted least squares on the
            /// base parameters, or the physically consistent semidefinite fit
            method: Method => Method("method") with "text_or_value";
            /// Low-pass cut-off (Hz) of the positions, velocities and accelerations, zero-phase
            /// Butterworth (of the order filter_order); one value or one per coordinate,
            /// comma-separated, or `none` (no filter). The 2019 PSM/MTM fits effectively used
            /// 16.965/5.655
            cutoff: Option<Cutoff> => Cutoff("cutoff") with "cutoff";
            /// Order of the low-pass filter (of one pass: the zero-phase filtering doubles its
            /// slope), N ≥ 1; a higher order cuts more sharply above the cut-off
            filter_order: usize => FilterOrder("filter_order") with "text_or_value";
            /// Also low-pass the torques, as the 2019 protocol did (it smooths the Coulomb
            /// friction steps on the measured side only, which biases the friction estimates)
            filter_torque: bool => FilterTorque("filter_torque");
            /// Samples trimmed at each end after filtering
            trim: usize => Trim("trim") with "text_or_value";
            /// Keep every N-th processed sample (after filtering; N ≥ 1)
            decimate: usize => Decimate("decimate") with "text_or_value";
            /// Drop processed samples where some joint moves slower than this (rad/s or m/s):
            /// the sign of its Coulomb friction is noise there
            min_speed: f64 => MinSpeed("min_speed") with "text_or_value";
            /// Resample to this uniform rate (Hz) by linear interpolation before anything else
            /// (bridges gaps and jitter; without it such logs are refused)
            resample_hz: f64 => Resample("resample") with "text_or_value";
            /// Metrics on the first N processed samples of each test log only (N ≥ 1)
            test_window: usize => TestWindow("test_window") with "text_or_value";
            /// Re-weighting passes of --method irls
            irls_iterations: usize => IrlsIterations("irls_iterations") with "text_or_value";
            /// Tikhonov weight of the semidefinite fit toward zero (toward the prior with
            /// --prior), relative
            sdp_regularization: f64 => SdpRegularization("sdp_regularization") with "text_or_value";
            /// Add a Stribeck friction term Fs·sign(v)·exp(-(v/VS)²) with this velocity (rad/s
            /// or m/s) to every friction element (parameters FsN, N the frame's number)
            stribeck_velocity: f64 => Stribeck("stribeck") with "text_or_value";
            /// Add Dahl friction Fd·z (rate-independent hysteresis: z follows dz/ds =
            /// SIGMA·(1 − z·sign(ds)) along the joint value, integrated from the processed
            /// positions in time order) with this stiffness (1/rad or 1/m) to every friction
            /// element (parameters FdN, Fd ≥ 0 in the semidefinite fit)
            dahl_sigma: f64 => Dahl("dahl") with "text_or_value";
            /// Add a position-dependent torque Σ Pcₖ·cos(k·q) + Psₖ·sin(k·q), k = 1..ORDER (1 to
            /// 3; 0: none, which leaves out a preset's), in the joint angle to every revolute
            /// friction element (parameters PcaN, PsaN, PcbN...; no constant term, that is
            /// the offset Fo; unbounded): the cables' and counterweights' torques of a
            /// cable-driven joint. Prismatic frames take it from a description
            /// (`position_torque = { order, period }`)
            position_torque_order: usize => PositionTorque("position_torque") with "text_or_value";
            /// The frames of --position-torque, by name, comma-separated (each revolute with
            /// friction); without it every revolute frame with friction. `--preset dvrk`
            /// takes both from the description's `[preset]` (the MTM's upper arm and forearm)
            position_torque_frames: FrameNames => PositionTorqueFrames("position_torque_frames") with "text_or_value";
            /// Add load-dependent Coulomb friction Fl·|τ|·sign(q̇) to every friction element whose
            /// joint value is one coordinate's multiple, one per coordinate (parameters
            /// FlN, 0 ≤ Fl ≤ 1/2 in the semidefinite fit): friction in proportion to the
            /// torque the joint transmits, the load its measured torque in the fit and its
            /// predicted torque in the metrics
            load_friction: bool => LoadFriction("load_friction");
            /// The arm's mounting pitch, degrees, as the dVRK's `mounting_pitch` (which is in
            /// radians): gravity in the base frame becomes (0, −9.81·sin p, −9.81·cos p) m/s²
            /// (the dVRK mounts PSM1 and PSM2 at −45°, PSM3 at −15°, the ECM at −70° (Si) or
            /// −45° (Classic)). A fit records it and every use of its result applies it
            mounting_pitch_deg: f64 => MountingPitch("mounting_pitch") with "text_or_value";
            /// Lower bounds of the semidefinite fit on friction and motor inertias, in place of
            /// the robot description's: `physical` (friction ≥ 0, motor inertia ≥ 1e-6) or `2019`
            /// (≥ 0.001, to reproduce the 2019 fit)
            bounds: BoundsSet => Bounds("bounds") with "text_or_value";
            /// The links' bounding ellipsoids of the robot description: by default the
            /// semidefinite fit keeps each link's mass inside its ellipsoid, when the description
            /// gives one (the built-in MTM, a URDF's collision geometry); `--no-ellipsoids`
            /// (Python `ellipsoids=False`) ignores them
            ellipsoids: bool => Ellipsoids("ellipsoids");
            /// Measurement delay of the torques: `auto` (estimated per coordinate within
            /// 0–0.150 s with the parameters, recorded in the result), `0` (none) or seconds, one
            /// for all coordinates or one per coordinate `d1,d2,...`
            delay: DelayOption => Delay("delay") with "delay";
            /// Regularize the semidefinite fit toward a prior: `nominal` (the description's
            /// nominal parameters, e.g. a URDF's inertias) or an earlier result document (its
            /// values are recorded in the result's settings); `none` leaves out a preset's
            /// prior
            prior: PriorSource => Prior("prior") with "text_or_value";
            /// Weight of the prior, relative to the data term scaled to at most 1 (0, or 1e-9 to 1e6)
            prior_weight: f64 => PriorWeight("prior_weight") with "text_or_value";
            /// How the prior's distance is measured: `entropic` (the log-det divergence of each
            /// link's pseudo-inertia from the prior's) or `euclidean`
            prior_metric: PriorMetric => PriorMetric("prior_metric") with "text_or_value";
            /// Settings recommended for an arm, for every setting not given here: `dvrk` (the
            /// dVRK arms: --method sdp --stribeck 0.3 --dahl 20, --prior nominal
            /// --prior-weight 0.05 for an sdp fit of a robot with nominal masses, and the
            /// description's `[preset]`: the MTM's --position-torque 1
            /// --position-torque-frames upper_arm,forearm). The result records the settings
            /// it expanded to
            preset: Preset => Preset("preset") with "text_or_value";
            /// Give every training log after the first its own torque offset per coordinate
            /// (the arm is re-homed between recordings): fitted with the parameters, recorded
            /// in the result's inputs (`offset`, N·m or N over the model's); the model's Fo are
            /// the first log's, which validate and residual apply to any other log
            log_offsets: bool => LogOffsets("log_offsets");
            /// Choose the friction model by held-out error: fit each candidate on part of the
            /// training logs and score it on the rest (leave one log out with several logs,
            /// else 4 blocks in time with a guard band), then fit the lowest mean held-out
            /// error on all of them. `builtin` (coulomb,stribeck,dahl,stribeck+dahl) or names
            /// joined by commas: `coulomb`, or terms `stribeck[:VS]` and `dahl[:SIGMA]` joined
            /// by `+` (defaults 0.3 and 20). The result records the table and the choice
            select: Candidates => Select("select");
            /// Show the errors and figures in the `model` coordinates (q1..qn, the estimator's)
            /// or in the arm's `measured` joints by name (the PSM's outer_wrist_pitch,
            /// outer_wrist_yaw and jaw rather than its motor-side q5..q7); the fit is the same
            joints: Joints => Joints("joints") with "text_or_value";
        }
    };
}
pub(crate) use fit_options;

macro_rules! setting {
    ($(
        $(#[doc = $doc:literal])*
        $field:ident: $ty:ty => $variant:ident($name:literal) $(with $with:literal)?;
    )*) => {
        /// A fit option by identity: errors carry it, and each front end spells it its
        /// own way (`--cutoff`, `cutoff=`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Setting {
            $(
                #[doc = concat!("`", $name, "` ([`Overrides::", stringify!($field), "`](crate::request::Overrides::", stringify!($field), ")).")]
                $variant,
            )*
        }

        impl Setting {
            /// Every option, in the order of [`Overrides`](crate::request::Overrides).
            pub const ALL: &'static [Setting] = &[$(Setting::$variant),*];

            /// The option's name: the serde key, Python's keyword, the flag's stem.
            pub fn name(self) -> &'static str {
                match self {
                    $(Setting::$variant => $name,)*
                }
            }

            /// The option's documentation, one paragraph (the command line's help).
            pub fn doc(self) -> String {
                let lines: &[&str] = match self {
                    $(Setting::$variant => &[$($doc),*],)*
                };
                lines.iter().map(|l| l.trim()).collect::<Vec<_>>().join(" ")
            }
        }
    };
}

fit_options!(setting);

impl Setting {
    /// The processing options (how a log is read and filtered before the reduction):
    /// the options of commands that process logs (`validate`, Python's `prepare`).
    pub const PROCESSING: &'static [Setting] = &[
        Setting::Cutoff,
        Setting::FilterOrder,
        Setting::FilterTorque,
        Setting::Trim,
        Setting::Decimate,
        Setting::MinSpeed,
        Setting::Resample,
    ];

    /// The options an observation state carries (`observe`'s): the processing, the
    /// Stribeck terms and the mounting. A fit of states refuses them (and `delay`).
    pub const OBSERVE: &'static [Setting] = &[
        Setting::Cutoff,
        Setting::FilterOrder,
        Setting::FilterTorque,
        Setting::Trim,
        Setting::Decimate,
        Setting::MinSpeed,
        Setting::Resample,
        Setting::Stribeck,
        Setting::MountingPitch,
    ];

    /// The option of this name ([`Setting::name`]).
    pub fn from_name(name: &str) -> Option<Setting> {
        Setting::ALL.iter().copied().find(|s| s.name() == name)
    }
}

/// Why an option's text is not one of its values: the errors of the options' `FromStr`
/// (the command line's flags, Python's strings, a result document's text).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ValueError {
    /// A name none of an option enum's.
    #[error(transparent)]
    UnknownName(#[from] crate::names::UnknownName),
    /// `cutoff`: not a number, a list of them or `none`.
    #[error("`{0}` is not a cut-off (Hz), a list of them or `none`")]
    NotCutoff(String),
    /// `cutoff`: a value that is not positive and finite (Hz).
    #[error("cut-off {0} Hz: must be positive and finite (or `none`: no filter)")]
    CutoffNotPositive(f64),
    /// `delay`: not `auto` nor seconds.
    #[error("`{0}` is not a delay: expected auto or seconds d1,d2,...")]
    NotDelay(String),
    /// `select`: a term's value that is not a positive number.
    #[error("candidate `{candidate}`: `{value}` is not a positive number ({term}'s value)")]
    CandidateValue {
        /// The candidate as given.
        candidate: String,
        /// The term (`stribeck`, `dahl`).
        term: String,
        /// The value's text.
        value: String,
    },
    /// `select`: a term that is neither `stribeck` nor `dahl`.
    #[error(
        "unknown candidate term `{term}` in `{candidate}`: expected coulomb, or terms \
         stribeck[:VS] and dahl[:SIGMA] joined by +"
    )]
    UnknownCandidateTerm {
        /// The candidate as given.
        candidate: String,
        /// The term as given.
        term: String,
    },
    /// `select`: a candidate with a term twice.
    #[error("candidate `{candidate}` gives {term} twice")]
    TermTwice {
        /// The candidate as given.
        candidate: String,
        /// The term given twice.
        term: String,
    },
    /// `select`: fewer than two candidates.
    #[error("`{0}`: give at least two candidates to choose from (or `builtin`)")]
    TooFewCandidates(String),
    /// `select`: a candidate given twice.
    #[error("`{list}`: candidate {candidate} is given twice")]
    CandidateTwice {
        /// The list as given.
        list: String,
        /// The candidate's name.
        candidate: String,
    },
    /// `position_torque_frames`: an empty name.
    #[error("`{0}`: expected frame names separated by commas")]
    NotFrameNames(String),
    /// `prior`: an empty text.
    #[error("give `nominal` or a result file")]
    NoPrior,
}

/// An option's value as a front end gives it: text is parsed as its flag's text
/// ([`FromStr`](std::str::FromStr), whose error names the accepted values), any other
/// value is read as the value itself. The one reading of the fit options'
/// (`request/overrides.rs`) and the excitation options' (`excite/options.rs`) values.
pub(crate) fn parse_text_or_value<T>(value: serde_json::Value) -> Result<T, TextOrValueError>
where
    T: std::str::FromStr + serde::de::DeserializeOwned,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    match value {
        serde_json::Value::String(text) => text
            .parse()
            .map_err(|e: T::Err| TextOrValueError::Text(Box::new(e))),
        value => T::deserialize(value).map_err(TextOrValueError::Value),
    }
}

/// Why [`parse_text_or_value`] refused a value: its text (the type's `FromStr` error:
/// a [`ValueError`], an [`UnknownName`](crate::names::UnknownName), a number's), or the
/// value itself.
#[derive(Debug, thiserror::Error)]
pub(crate) enum TextOrValueError {
    #[error(transparent)]
    Text(Box<dyn std::error::Error + Send + Sync>),
    #[error(transparent)]
    Value(serde_json::Error),
}
