//! The fit options' struct, [`Overrides`], generated from the one list of options
//! (`fit_options!` in `crate::options`, which also makes [`Setting`]), with the one
//! conversion from values ([`Overrides::from_values`]) both front ends use.

use std::str::FromStr;

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer, Serialize};

pub use crate::options::Setting;

use super::PriorSource;
use crate::fit::delay::DelayOption;
use crate::settings::Candidates;
use crate::settings::{FrameNames, Joints, PriorMetric};
use crate::signal::Cutoff;
use crate::{BoundsSet, FitSettings, IdentError, Method};
use dvrk_logs::hint::Hint;
use dvrk_model::Model;

/// Settings recommended for a kind of robot, by name (`--preset dvrk`, Python
/// `preset="dvrk"`): each fills the settings the request does not give itself.
///
/// ```rust
/// use dvrk_ident::{Overrides, Preset};
/// use dvrk_ident::Method;
///
/// let o = Overrides { preset: Some(Preset::Dvrk), method: Some(Method::Wls), ..Overrides::default() };
/// let e = o.expanded(false);
/// assert_eq!(e.method, Some(Method::Wls)); // given: kept
/// assert_eq!(e.stribeck_velocity, Some(0.3)); // from the preset
/// assert_eq!(e.dahl_sigma, Some(20.0));
/// assert_eq!(e.delay, None); // no delay search: Dahl friction holds at other speeds
/// assert_eq!(e.preset, None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// The dVRK arms: the physically consistent fit (`sdp`), a Stribeck term of 0.3 rad/s
    /// (m/s) and Dahl friction of stiffness 20/rad (1/m) on every friction element. On
    /// the real 2019 logs (fit "one", test "two", the 2019 processing) it beats the
    /// published 2019 SDP on every joint: mean test error PSM 0.1257 against 0.1875
    /// (−33.0 %), MTM 0.1726 against 0.2103 (−17.9 %); on the PSM speed pair (fit one
    /// speed, test the other) 0.187 (1.0 → 0.5) and 0.168 (0.5 → 1.0), where the earlier
    /// preset's delay search gave 0.270 and 0.290: the wrist's lag is hysteresis over a
    /// displacement, not a delay (the book's "Generalization across speeds"). The
    /// descriptions' bounding ellipsoids (the dVRK's meshes: 7 MTM links, the PSM's
    /// pitch_front, 3 ECM links) apply too (MTM +0.3 % test error, PSM none); a
    /// partial prior toward the nominal masses (`--prior nominal --prior-weight 0.05`,
    /// `PRESET_PRIOR_WEIGHT`; `--prior none` leaves it out) is part of the preset
    /// wherever the description has nominal masses (every built-in arm but
    /// `psm_simplified`; the Classic PSM's are the CAD masses of WPI's model, its maker
    /// publishing none) and the method is `sdp`: on the real MTM it moves every mass the
    /// dVRK publishes into 0.38-1.8 times it (the upper arm from its 15 kg bound, 16.7
    /// times the dVRK's 0.9 kg, to 1.6 kg) for +1.6 % in mean test error; on the real PSM
    /// it takes three parallelogram masses off their 2019 bounds for −0.6 %. In a fit of
    /// logs the description's `[preset]` elements join the model
    /// ([`dvrk_model::PresetElements`]; `--position-torque 0` leaves the position torque
    /// out): the MTM's shoulder and elbow cable torques, which take its mean test error
    /// from 0.1799 to 0.1726, put every MTM mass with a dVRK value within 0.77-1.00 times
    /// it and none on a bound (the book's identification chapter, §6.5).
    Dvrk,
}

impl crate::names::Named for Preset {
    const WHAT: &'static str = "preset";
    const NAMES: &'static [(&'static str, Self)] = &[("dvrk", Preset::Dvrk)];
    const CANONICAL: usize = 1;
}

impl std::str::FromStr for Preset {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

impl Preset {
    /// The settings the preset stands for.
    pub fn overrides(self) -> Overrides {
        match self {
            // Dahl friction replaced the delay search (issue 28): the wrist's lag is
            // hysteresis over a displacement, which holds at another speed where a delay
            // fitted at one does not (docs/book/src/generalization.md).
            // The prior toward the description's nominal masses applies only where there
            // are some, to the semidefinite fit (`FitRequest::run`).
            Preset::Dvrk => Overrides {
                method: Some(Method::Sdp),
                stribeck_velocity: Some(0.3),
                dahl_sigma: Some(20.0),
                prior: Some(PriorSource::Nominal),
                prior_weight: Some(PRESET_PRIOR_WEIGHT),
                ..Overrides::default()
            },
        }
    }
}

/// The weight of `--preset dvrk`'s prior toward the description's nominal values
/// (entropic metric). Measured on the real MTM (2019 protocol, the book's identification
/// chapter, 6.5): it moves the masses the data do not determine into 0.38-1.8 times the
/// dVRK's (the upper arm from its 15 kg bound, 16.7 times the dVRK's 0.9 kg, to 1.6 kg)
/// for +1.6 % in mean test error against the preset without prior and ellipsoids; 1e-2
/// (+0.9 %) leaves the wrist roll on its 0.02 kg lower bound (0.2 times), 1e-1 costs
/// +2.3 %.
pub const PRESET_PRIOR_WEIGHT: f64 = 5e-2;

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
        /// use dvrk_ident::Overrides;
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

crate::options::fit_options!(overrides);

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
            Setting::TestWindow => format!(
                "the excitation's first period with {}, else every sample",
                Hint::Excitation
            ),
            Setting::IrlsIterations => fit.irls_iterations.to_string(),
            Setting::SdpRegularization => format!("{:e}", fit.sdp_regularization),
            Setting::Stribeck => "none".into(),
            Setting::Dahl => "none".into(),
            Setting::PositionTorque => "none".into(),
            Setting::PositionTorqueFrames => "every revolute frame with friction".into(),
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
    /// use dvrk_ident::{Overrides, Setting};
    /// use dvrk_ident::DelayOption;
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
    T::Err: std::error::Error + Send + Sync + 'static,
{
    crate::options::parse_text_or_value(serde_json::Value::deserialize(d)?)
        .map(Some)
        .map_err(D::Error::custom)
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

impl Overrides {
    /// These overrides with the fields they do not give taken from their preset (and no
    /// preset left). `from_states`: the fit reads observation states, which carry their
    /// own processing, so the preset's processing fields (delays, Stribeck terms) are
    /// left to `observe`.
    pub fn expanded(&self, from_states: bool) -> Overrides {
        let mut o = self.clone();
        let Some(preset) = o.preset.take() else {
            return o;
        };
        o = o.or(preset.overrides());
        if self.select.is_some() {
            // The candidates give the friction terms; the preset gives the rest.
            o.stribeck_velocity = self.stribeck_velocity;
            o.dahl_sigma = self.dahl_sigma;
        }
        if from_states {
            let given = self.observation_fields();
            if !given.contains(&Setting::Stribeck) {
                o.stribeck_velocity = self.stribeck_velocity;
            }
            if !given.contains(&Setting::Dahl) {
                o.dahl_sigma = self.dahl_sigma;
            }
            if !given.contains(&Setting::PositionTorque) {
                o.position_torque_order = self.position_torque_order;
            }
            if !given.contains(&Setting::LoadFriction) {
                o.load_friction = self.load_friction;
            }
            if !given.contains(&Setting::Delay) {
                o.delay = self.delay.clone();
            }
        }
        o
    }

    /// `base` with every given field replaced.
    pub fn apply(&self, base: FitSettings) -> FitSettings {
        let mut s = base;
        if let Some(m) = self.method {
            s.method = m;
        }
        if let Some(c) = &self.cutoff {
            s.processing.set_cutoff(c.clone());
        }
        if let Some(n) = self.filter_order {
            if let Some(f) = &mut s.processing.filter {
                f.order = n;
            }
        }
        if let Some(f) = self.filter_torque {
            s.processing.filter_torque = f;
        }
        if let Some(t) = self.trim {
            s.processing.trim = t;
        }
        if let Some(d) = self.decimate {
            s.processing.decimate = d;
        }
        if let Some(v) = self.min_speed {
            s.processing.min_speed = Some(v);
        }
        if let Some(r) = self.resample_hz {
            s.processing.resample_hz = Some(r);
        }
        if let Some(w) = self.test_window {
            s.test_window = Some(w);
        }
        if let Some(i) = self.irls_iterations {
            s.irls_iterations = i;
        }
        if let Some(r) = self.sdp_regularization {
            s.sdp_regularization = r;
        }
        if let Some(v) = self.stribeck_velocity {
            s.stribeck_velocity = Some(v);
        }
        if let Some(v) = self.dahl_sigma {
            s.dahl_sigma = Some(v);
        }
        if let Some(k) = self.position_torque_order {
            // 0: none (leaves out a preset's).
            s.position_torque_order = (k > 0).then_some(k);
        }
        if let Some(FrameNames(f)) = &self.position_torque_frames {
            s.position_torque_frames = f.clone();
        }
        if let Some(l) = self.load_friction {
            s.load_friction = l;
        }
        if let Some(p) = self.mounting_pitch_deg {
            s.mounting_pitch_deg = Some(p);
        }
        if let Some(b) = self.bounds {
            s.bounds = Some(b);
        }
        if let Some(e) = self.ellipsoids {
            s.ellipsoids = e;
        }
        if let Some(j) = self.joints {
            s.joints = j;
        }
        if let Some(b) = self.log_offsets {
            s.log_offsets = b;
        }
        if let Some(c) = &self.select {
            s.select = Some(c.clone());
        }
        s
    }

    /// [`Overrides::apply`], the delays for `model`'s coordinates and the prior for its
    /// parameters.
    pub fn settings_for(
        &self,
        base: FitSettings,
        model: &Model,
    ) -> Result<FitSettings, IdentError> {
        let mut s = self.apply(base);
        if let Some(d) = &self.delay {
            d.apply(&mut s, model.dof())?;
        }
        check_position_torque_frames(&s, model)?;
        let fitted = s.model(model)?.into_owned();
        self.set_prior(&mut s, &fitted)?;
        Ok(s)
    }

    /// The prior of `s` for `fitted` (the model with the settings' Stribeck terms):
    /// read from [`Overrides::prior`], or the base's with the weight and metric
    /// overridden, then checked.
    pub(super) fn set_prior(&self, s: &mut FitSettings, fitted: &Model) -> Result<(), IdentError> {
        if let Some(source) = &self.prior {
            s.prior = source.parameters(fitted)?;
        }
        match &mut s.prior {
            Some(p) => {
                if let Some(w) = self.prior_weight {
                    p.weight = w;
                }
                if let Some(m) = self.prior_metric {
                    p.metric = m;
                }
                p.check(s.method)
            }
            None => {
                let given = [
                    (Setting::PriorWeight, self.prior_weight.is_some()),
                    (Setting::PriorMetric, self.prior_metric.is_some()),
                ];
                match given.iter().find(|(_, set)| *set) {
                    Some((name, _)) => Err(IdentError::Setting {
                        name: (*name).into(),
                        message: "needs a prior (nominal, or an earlier result file)".into(),
                    }),
                    None => Ok(()),
                }
            }
        }
    }

    /// The overrides that change how logs are processed or which model is fitted
    /// (the delays shift the torques before the reduction): observation states carry
    /// their own, so these are refused with them.
    pub(super) fn observation_fields(&self) -> Vec<Setting> {
        self.given()
            .into_iter()
            .filter(|s| {
                Setting::OBSERVE.contains(s)
                    || matches!(
                        s,
                        Setting::Delay
                            | Setting::Dahl
                            | Setting::PositionTorque
                            | Setting::PositionTorqueFrames
                            | Setting::LoadFriction
                    )
            })
            .collect()
    }
}

/// The position torque's frames of `s` name frames of `model` that can carry one, and
/// come with its order: refused naming the setting, not as a model error.
fn check_position_torque_frames(s: &FitSettings, model: &Model) -> Result<(), IdentError> {
    if s.position_torque_frames.is_empty() {
        return Ok(());
    }
    let refuse = |message: String| IdentError::Setting {
        name: Setting::PositionTorqueFrames.into(),
        message,
    };
    if s.position_torque_order.is_none() {
        return Err(refuse(format!(
            "needs the position torque's order ({})",
            Setting::PositionTorque.name()
        )));
    }
    model
        .check_position_torque_frames(&s.position_torque_frames)
        .map_err(IdentError::of_setting(Setting::PositionTorqueFrames))
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
