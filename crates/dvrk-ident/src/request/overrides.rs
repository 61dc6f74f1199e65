//! The fit options, each declared once: its field of [`Overrides`], its name (the
//! command line's flag `--name`, Python's keyword `name=`, the serde key), its
//! documentation (the flag's help) and the type its value is read as. The `overrides!`
//! list below generates the struct, the [`Setting`] that names each option in errors,
//! and the one conversion from values ([`Overrides::from_values`]) both front ends use.
//!
//! **Adding a fit option**: one entry in the list (doc, field, type, variant, name), its
//! effect in [`Overrides::apply`] (or `settings_for`), and the command line's flag
//! details (heading, value name) in dvrk-cli's `cmd/settings.rs`, whose exhaustive
//! `match` does not compile without it; Python takes it as a keyword with no edit but
//! the type stub, which a test checks against [`Setting::ALL`].

use std::str::FromStr;

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer, Serialize};

use super::{Preset, PriorSource};
use crate::fit::delay::DelayOption;
use crate::fit::select::Candidates;
use crate::settings::{Joints, PriorMetric};
use crate::signal::Cutoff;
use crate::{BoundsSet, Method};

macro_rules! overrides {
    ($(
        $(#[doc = $doc:literal])*
        $field:ident: $ty:ty => $variant:ident($name:literal) $(with $with:literal)?;
    )*) => {
        /// Settings changed from a base (the defaults, or a result's `settings`): each
        /// field that is `Some` replaces the base's value, the same way for every front
        /// end. Serialized with the options' names as keys (`resample`, `stribeck`),
        /// unknown keys refused.
        ///
        /// ```rust
        /// use dvrk_ident::request::Overrides;
        /// use dvrk_ident::signal::Cutoff;
        /// use dvrk_ident::{FitSettings, Method};
        ///
        /// let base = FitSettings::default();
        /// let order = base.processing.filter.as_ref().unwrap().order;
        /// let s = Overrides {
        ///     method: Some(Method::Wls),
        ///     cutoff: Some(Some(Cutoff::All(16.965))),
        ///     trim: Some(50),
        ///     ..Overrides::default()
        /// }
        /// .apply(base);
        /// assert_eq!(s.method, Method::Wls);
        /// assert_eq!(s.processing.trim, 50);
        /// // A new cut-off keeps the filter's order and form.
        /// assert_eq!(s.processing.filter.as_ref().unwrap().order, order);
        /// // `Some(None)`: no filter.
        /// let none = Overrides { cutoff: Some(None), ..Overrides::default() }.apply(s);
        /// assert!(none.processing.filter.is_none());
        /// // The same from the options' names and values, as the front ends give them.
        /// let o: Overrides = serde_json::from_str(r#"{"method": "wls", "trim": 50}"#).unwrap();
        /// assert_eq!((o.method, o.trim), (Some(Method::Wls), Some(50)));
        /// assert!(serde_json::from_str::<Overrides>(r#"{"trimm": 50}"#).is_err());
        /// ```
        #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct Overrides {
            $(
                $(#[doc = $doc])*
                #[serde(rename = $name, default, skip_serializing_if = "Option::is_none"
                        $(, deserialize_with = $with)?)]
                pub $field: Option<$ty>,
            )*
        }

        /// A fit option by identity: errors carry it, and each front end spells it its
        /// own way (`--cutoff`, `cutoff=`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Setting {
            $(
                #[doc = concat!("`", $name, "` ([`Overrides::", stringify!($field), "`]).")]
                $variant,
            )*
        }

        impl Setting {
            /// Every option, in the order of [`Overrides`].
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

        impl Overrides {
            /// Each field of `self`, and `other`'s where `self` gives none.
            pub fn or(self, other: Overrides) -> Overrides {
                Overrides {
                    $($field: self.$field.or(other.$field),)*
                }
            }

            /// The options given (fields that are `Some`), in [`Setting::ALL`]'s order.
            pub fn given(&self) -> Vec<Setting> {
                let mut given = Vec::new();
                $(
                    if self.$field.is_some() {
                        given.push(Setting::$variant);
                    }
                )*
                given
            }

            /// `self` with only the options of `keep`.
            pub fn only(&self, keep: &[Setting]) -> Overrides {
                Overrides {
                    $($field: if keep.contains(&Setting::$variant) {
                        self.$field.clone()
                    } else {
                        None
                    },)*
                }
            }
        }
    };
}

overrides! {
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
    /// or m/s) to every friction element (parameters Fs<frame>)
    stribeck_velocity: f64 => Stribeck("stribeck") with "text_or_value";
    /// Add Dahl friction Fd·z (rate-independent hysteresis: z follows dz/ds =
    /// SIGMA·(1 − z·sign(ds)) along the joint value, integrated from the processed
    /// positions in time order) with this stiffness (1/rad or 1/m) to every friction
    /// element (parameters Fd<frame>, Fd ≥ 0 in the semidefinite fit)
    dahl_sigma: f64 => Dahl("dahl") with "text_or_value";
    /// Add a position-dependent torque Σ Pcₖ·cos(k·q) + Psₖ·sin(k·q), k = 1..ORDER (1 to
    /// 3), in the joint angle to every revolute friction element (parameters
    /// Pca<frame>, Psa<frame>, Pcb<frame>...; no constant term, that is the offset Fo;
    /// unbounded): the cables' and counterweights' torques of a cable-driven joint.
    /// Prismatic frames take it from a description (`position_torque = { order,
    /// period }`)
    position_torque_order: usize => PositionTorque("position_torque") with "text_or_value";
    /// Add load-dependent Coulomb friction Fl·|τ|·sign(q̇) to every friction element whose
    /// joint value is one coordinate's multiple, one per coordinate (parameters
    /// Fl<frame>, 0 ≤ Fl ≤ 1/2 in the semidefinite fit): friction in proportion to the
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
    /// values are recorded in the result's settings)
    prior: PriorSource => Prior("prior") with "text_or_value";
    /// Weight of the prior, relative to the data term scaled to at most 1 (0, or 1e-9 to 1e6)
    prior_weight: f64 => PriorWeight("prior_weight") with "text_or_value";
    /// How the prior's distance is measured: `entropic` (the log-det divergence of each
    /// link's pseudo-inertia from the prior's) or `euclidean`
    prior_metric: PriorMetric => PriorMetric("prior_metric") with "text_or_value";
    /// Settings recommended for an arm, for every setting not given here: `dvrk` (the
    /// dVRK arms: --method sdp --stribeck 0.3 --dahl 20, and --prior nominal
    /// --prior-weight 0.05 for an sdp fit of a robot with nominal masses). The result
    /// records the settings it expanded to
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

/// A value refused for an option: the option, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct SettingError {
    /// The option.
    pub setting: Setting,
    /// What is wrong with the value given.
    pub message: String,
}

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

    /// The default as the help shows it: the library's ([`crate::FitSettings::default`],
    /// [`crate::settings::Prior::DEFAULT_WEIGHT`]), or what applies when the option is
    /// not given; `None` for a switch (off unless given).
    pub fn default_text(self) -> Option<String> {
        let fit = crate::FitSettings::default();
        let p = &fit.processing;
        Some(match self {
            Setting::Method => fit.method.name().into(),
            Setting::Cutoff => match &p.filter {
                Some(f) => match &f.cutoff_hz {
                    Cutoff::All(hz) => hz.to_string(),
                    Cutoff::PerJoint(hz) => {
                        hz.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
                    }
                },
                None => "none".into(),
            },
            Setting::FilterOrder => match &p.filter {
                Some(f) => f.order.to_string(),
                None => "none".into(),
            },
            Setting::FilterTorque | Setting::Ellipsoids | Setting::LoadFriction => return None,
            Setting::Trim => p.trim.to_string(),
            Setting::Decimate => p.decimate.to_string(),
            Setting::MinSpeed => match p.min_speed {
                Some(v) => v.to_string(),
                None => "none, every sample kept".into(),
            },
            Setting::Resample => match p.resample_hz {
                Some(v) => v.to_string(),
                None => "none, the log's own rate".into(),
            },
            Setting::TestWindow => {
                "the excitation's first period with --excitation, else every sample".into()
            }
            Setting::IrlsIterations => fit.irls_iterations.to_string(),
            Setting::SdpRegularization => format!("{:e}", fit.sdp_regularization),
            Setting::Stribeck => "none".into(),
            Setting::Dahl => "none".into(),
            Setting::PositionTorque => "none".into(),
            Setting::MountingPitch => "the description's gravity (a result's: its own)".into(),
            Setting::Bounds => "the description's; the built-in robots': physical".into(),
            Setting::Delay => "0".into(),
            Setting::Prior => "none".into(),
            Setting::PriorWeight => format!("{:e}", crate::settings::Prior::DEFAULT_WEIGHT),
            Setting::PriorMetric => PriorMetric::default().name().into(),
            Setting::Preset => "none".into(),
            Setting::Joints => fit.joints.name().into(),
            Setting::LogOffsets => return None,
            Setting::Select => "none (with the flag alone: builtin)".into(),
        })
    }
}

impl Overrides {
    /// The overrides of these options and values: the one conversion of the front ends'
    /// flags and keyword arguments. A value is the option's own (a number, a list of
    /// numbers, a boolean) or its text as the command line gives it (`"16.965"`,
    /// `"5,5,3"`, `"auto"`); an error names the option.
    ///
    /// ```rust
    /// use dvrk_ident::request::{Overrides, Setting};
    /// use dvrk_ident::fit::delay::DelayOption;
    /// use serde_json::json;
    ///
    /// let o = Overrides::from_values([
    ///     (Setting::Trim, json!("50")),
    ///     (Setting::Delay, json!([0.01, 0.02])),
    /// ])
    /// .unwrap();
    /// assert_eq!((o.trim, o.delay), (Some(50), Some(DelayOption::Fixed(vec![0.01, 0.02]))));
    /// let e = Overrides::from_values([(Setting::Method, json!("fast"))]).unwrap_err();
    /// assert_eq!(e.setting, Setting::Method);
    /// assert_eq!(e.message, "unknown method \"fast\": expected ols, wls, irls or sdp");
    /// ```
    pub fn from_values(
        values: impl IntoIterator<Item = (Setting, serde_json::Value)>,
    ) -> Result<Overrides, SettingError> {
        let mut all = Overrides::default();
        for (setting, value) in values {
            let mut one = serde_json::Map::new();
            one.insert(setting.name().to_string(), value);
            let o: Overrides =
                serde_json::from_value(serde_json::Value::Object(one)).map_err(|e| {
                    SettingError {
                        setting,
                        message: e.to_string(),
                    }
                })?;
            all = o.or(all);
        }
        Ok(all)
    }
}

/// A value given as text is parsed as its flag's text ([`FromStr`], whose error names
/// the accepted values); any other as the value itself.
fn text_or_value<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: Deserializer<'de>,
    T: FromStr + DeserializeOwned,
    T::Err: std::fmt::Display,
{
    match serde_json::Value::deserialize(d)? {
        serde_json::Value::String(text) => text.parse().map(Some).map_err(D::Error::custom),
        value => T::deserialize(value).map(Some).map_err(D::Error::custom),
    }
}

/// `cutoff`: the flag's text ([`Cutoff::parse_flag`]), `false` (no filter), Hz, or a
/// list of Hz (one per coordinate).
fn cutoff<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Option<Cutoff>>, D::Error> {
    use serde_json::Value;
    let bad = || {
        D::Error::custom(
            "expected a number (Hz), one number per coordinate, or \"none\" (no filter)",
        )
    };
    Ok(Some(match Value::deserialize(d)? {
        Value::String(text) => Cutoff::parse_flag(&text).map_err(D::Error::custom)?,
        Value::Bool(false) | Value::Null => None,
        Value::Number(n) => Some(Cutoff::All(n.as_f64().ok_or_else(bad)?)),
        v @ Value::Array(_) => Some(Cutoff::PerJoint(
            Vec::<f64>::deserialize(v).map_err(|_| bad())?,
        )),
        _ => return Err(bad()),
    }))
}

/// `delay`: the flag's text (`auto`, `d1,d2,...`), seconds, or a list of seconds.
fn delay<'de, D: Deserializer<'de>>(d: D) -> Result<Option<DelayOption>, D::Error> {
    use serde_json::Value;
    let bad = || D::Error::custom("expected \"auto\", seconds, or a list of seconds");
    Ok(Some(match Value::deserialize(d)? {
        Value::String(text) => text.parse().map_err(D::Error::custom)?,
        Value::Number(n) => DelayOption::Fixed(vec![n.as_f64().ok_or_else(bad)?]),
        v @ Value::Array(_) => DelayOption::Fixed(Vec::<f64>::deserialize(v).map_err(|_| bad())?),
        _ => return Err(bad()),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every option has a distinct name and a documentation, and reads back from its
    /// serialized value (the serde keys are the names).
    #[test]
    fn names_docs_and_round_trip() {
        let mut names: Vec<&str> = Setting::ALL.iter().map(|s| s.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Setting::ALL.len());
        for s in Setting::ALL {
            assert!(!s.doc().is_empty() && !s.doc().contains("  "), "{s:?}");
            assert_eq!(Setting::from_name(s.name()), Some(*s));
            assert!(s.default_text().is_none_or(|t| !t.is_empty()));
        }
        let o = Overrides {
            cutoff: Some(Some(Cutoff::PerJoint(vec![5.0, 3.0]))),
            stribeck_velocity: Some(0.3),
            ellipsoids: Some(false),
            ..Overrides::default()
        };
        let json = serde_json::to_value(&o).unwrap();
        assert_eq!(
            json,
            serde_json::json!({"cutoff": [5.0, 3.0], "stribeck": 0.3, "ellipsoids": false})
        );
        assert_eq!(serde_json::from_value::<Overrides>(json).unwrap(), o);
        assert_eq!(
            o.given(),
            [Setting::Cutoff, Setting::Stribeck, Setting::Ellipsoids]
        );
    }

    /// The forms each front end gives: text (the command line) and values (Python),
    /// the same overrides; an error names the option.
    #[test]
    fn text_and_values_agree() {
        use serde_json::json;
        let text = Overrides::from_values([
            (Setting::Cutoff, json!("5,3")),
            (Setting::Trim, json!("7")),
            (Setting::Delay, json!("0.01")),
            (Setting::Prior, json!("nominal")),
            (Setting::Bounds, json!("2019")),
        ])
        .unwrap();
        let values = Overrides::from_values([
            (Setting::Cutoff, json!([5, 3])),
            (Setting::Trim, json!(7)),
            (Setting::Delay, json!(0.01)),
            (Setting::Prior, json!("nominal")),
            (Setting::Bounds, json!("2019")),
        ])
        .unwrap();
        assert_eq!(text, values);
        assert_eq!(text.bounds, Some(BoundsSet::Wang2019));
        // The candidates of a selection: the flag's text, a list of names, or true.
        let listed = Overrides::from_values([(Setting::Select, json!(["coulomb", "dahl:10"]))]);
        let text = Overrides::from_values([(Setting::Select, json!("coulomb,dahl:10"))]);
        assert_eq!(listed.unwrap(), text.unwrap());
        let all = Overrides::from_values([(Setting::Select, json!(true))]).unwrap();
        assert_eq!(
            all.select.unwrap().to_string(),
            "coulomb,stribeck,dahl,stribeck+dahl"
        );
        let e = Overrides::from_values([(Setting::Select, json!(["coulomb"]))]).unwrap_err();
        assert_eq!(e.setting, Setting::Select);
        assert!(
            e.message.contains("at least two candidates"),
            "{}",
            e.message
        );
        let none = Overrides::from_values([(Setting::Cutoff, json!(false))]).unwrap();
        assert_eq!(none.cutoff, Some(None));
        let e = Overrides::from_values([(Setting::Trim, json!(-1))]).unwrap_err();
        assert_eq!(e.setting, Setting::Trim);
        assert!(e.message.contains("-1"), "{}", e.message);
        let e = Overrides::from_values([(Setting::Cutoff, json!(true))]).unwrap_err();
        assert_eq!(e.setting, Setting::Cutoff);
    }
}
