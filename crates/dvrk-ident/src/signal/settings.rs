//! The processing settings (low-pass filter, cut-off, acceleration source, trim,
//! decimation, resampling) and the processed signals they produce.

use super::advance;
use super::butter::{self, butter_lowpass_sos_wn, butter_lowpass_wn, Section, TransferFunction};
use super::error::SignalError;
use super::filter::{self, filtfilt, sosfiltfilt};
use super::ops::{self, Stencil};
use crate::options::ValueError;
use crate::Coordinates;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Form in which the Butterworth filter is designed and applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FilterForm {
    /// Transfer function `(b, a)` with [`filtfilt`]; what the 2019 code used. Loses
    /// precision at high orders and low normalized cut-offs.
    Ba,
    /// Second-order sections with [`sosfiltfilt`]; numerically robust.
    #[default]
    Sos,
}

/// How a cut-off in Hz becomes scipy's normalized `Wn`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum CutoffConvention {
    /// `Wn = fc / (fs / 2)`: the filter cuts off at `fc`.
    #[default]
    Standard,
    /// `Wn = 2 pi fc / fs`, the 2019 code's (mistaken) conversion: the filter actually
    /// cuts off at `pi * fc`. Only for reproducing the 2019 published results. Written
    /// `wpi`; result documents of 0.1.0 spell it `wpi2019`, still read.
    #[serde(alias = "wpi2019")]
    Wpi,
}

impl CutoffConvention {
    /// Normalized cut-off `Wn` for a cut-off `cutoff_hz` at sampling rate `rate_hz`.
    ///
    /// ```rust
    /// use dvrk_ident::signal::CutoffConvention;
    /// assert_eq!(CutoffConvention::Standard.wn(5.0, 200.0), 0.05);
    /// let wn = CutoffConvention::Wpi.wn(5.4, 200.0);
    /// assert!((wn - 2.0 * std::f64::consts::PI * 5.4 / 200.0).abs() < 1e-15);
    /// ```
    pub fn wn(self, cutoff_hz: f64, rate_hz: f64) -> f64 {
        match self {
            CutoffConvention::Standard => cutoff_hz / (rate_hz / 2.0),
            CutoffConvention::Wpi => 2.0 * PI * cutoff_hz / rate_hz,
        }
    }

    /// The cut-off the designed filter really has, Hz: `cutoff_hz` for
    /// [`Standard`](Self::Standard), `pi * cutoff_hz` for [`Wpi`](Self::Wpi).
    ///
    /// ```rust
    /// use dvrk_ident::signal::CutoffConvention;
    /// let fc = CutoffConvention::Wpi.effective_cutoff_hz(5.4);
    /// assert!((fc - 16.9646).abs() < 1e-4); // the PSM's 2019 filter
    /// ```
    pub fn effective_cutoff_hz(self, cutoff_hz: f64) -> f64 {
        match self {
            CutoffConvention::Standard => cutoff_hz,
            CutoffConvention::Wpi => PI * cutoff_hz,
        }
    }
}

/// `values` for `n` coordinates: one value for every coordinate, or one per coordinate;
/// `None` for any other count (the caller's message names the setting). The one rule of
/// the settings given that way (delays, simulated noise).
pub(crate) fn per_coordinate(values: &[f64], n: usize) -> Option<Vec<f64>> {
    match values {
        [v] => Some(vec![*v; n]),
        all if all.len() == n => Some(all.to_vec()),
        _ => None,
    }
}

/// A cut-off frequency, Hz: one for all joints or one per joint.
///
/// Serialized untagged: `cutoff_hz = 5.4` or `cutoff_hz = [5.4, 5.4, 3.0, ...]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Cutoff {
    /// The same cut-off for every joint, Hz.
    All(f64),
    /// One cut-off per joint (column), Hz.
    PerJoint(Vec<f64>),
}

impl Cutoff {
    /// The text of a cut-off flag: `none` (no filter), one cut-off in Hz, or one per
    /// coordinate separated by commas (`--cutoff 16.965`, `--cutoff 5,5,5,3,3,3,3`).
    ///
    /// ```
    /// use dvrk_ident::signal::Cutoff;
    /// assert_eq!(Cutoff::parse_flag("none"), Ok(None));
    /// assert_eq!(Cutoff::parse_flag("5.4"), Ok(Some(Cutoff::All(5.4))));
    /// assert_eq!(Cutoff::parse_flag("5, 3"), Ok(Some(Cutoff::PerJoint(vec![5.0, 3.0]))));
    /// assert!(Cutoff::parse_flag("fast").is_err());
    /// assert!(Cutoff::parse_flag("nan").is_err());
    /// assert!(Cutoff::parse_flag("5,-1").is_err());
    /// ```
    pub fn parse_flag(text: &str) -> Result<Option<Cutoff>, ValueError> {
        if text.trim().eq_ignore_ascii_case("none") {
            return Ok(None);
        }
        let values: Vec<f64> = text
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| ValueError::NotCutoff(text.to_string()))?;
        let cutoff = match values[..] {
            [one] => Cutoff::All(one),
            _ => Cutoff::PerJoint(values),
        };
        cutoff.check_values()?;
        Ok(Some(cutoff))
    }

    /// Every cut-off positive and finite: what any cut-off read (a flag, a result's or a
    /// state's settings) must be.
    fn check_values(&self) -> Result<(), ValueError> {
        let values = match self {
            Cutoff::All(v) => std::slice::from_ref(v),
            Cutoff::PerJoint(v) => v.as_slice(),
        };
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(ValueError::CutoffNotPositive(*v));
        }
        Ok(())
    }

    /// Cut-off of joint `j`, Hz (`None` when a per-joint list is too short).
    pub fn for_joint(&self, j: usize) -> Option<f64> {
        match self {
            Cutoff::All(f) => Some(*f),
            Cutoff::PerJoint(v) => v.get(j).copied(),
        }
    }

    fn check(&self, dof: usize) -> Result<(), SignalError> {
        match self {
            Cutoff::PerJoint(v) if v.len() != dof => Err(SignalError::CutoffCount {
                expected: dof,
                found: v.len(),
            }),
            _ => self
                .check_values()
                .map_err(|reason| SignalError::InvalidSetting {
                    name: "cutoff_hz",
                    reason: reason.to_string(),
                }),
        }
    }
}

impl From<f64> for Cutoff {
    fn from(v: f64) -> Self {
        Cutoff::All(v)
    }
}

impl From<Vec<f64>> for Cutoff {
    fn from(v: Vec<f64>) -> Self {
        Cutoff::PerJoint(v)
    }
}

/// A designed filter, ready to apply.
#[derive(Clone, Debug, PartialEq)]
enum Designed {
    Ba(TransferFunction),
    Sos(Vec<Section>),
}

/// Zero-phase Butterworth low-pass settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LowPass {
    /// Filter order (of the single pass; forward-backward doubles the attenuation slope).
    pub order: usize,
    /// Cut-off, Hz, one or per joint.
    pub cutoff_hz: Cutoff,
    /// `(b, a)` or second-order sections.
    pub form: FilterForm,
    /// How `cutoff_hz` becomes the normalized `Wn`.
    pub convention: CutoffConvention,
    /// Odd-extension length at each end, samples; `None`: scipy's default
    /// (`3 * max(len(a), len(b))`, or the SOS equivalent).
    pub padlen: Option<usize>,
}

impl Default for LowPass {
    /// 6th order, 5.4 Hz (the PSM cut-off stated by the 2019 notebooks: 5 x the 1.08 Hz
    /// highest harmonic of its excitation; choose it from your excitation's bandwidth),
    /// second-order sections, standard convention, scipy's default padding.
    fn default() -> Self {
        LowPass {
            order: 6,
            cutoff_hz: Cutoff::All(5.4),
            form: FilterForm::Sos,
            convention: CutoffConvention::Standard,
            padlen: None,
        }
    }
}

impl LowPass {
    /// The 2019 filter for a *stated* cut-off `stated_cutoff_hz` (5.4 Hz PSM, 1.8 Hz
    /// MTM): 6th order, `(b, a)` form, `Wn = 2 pi fc / fs` (effective cut-off `pi * fc`),
    /// odd padding of 20 samples.
    pub fn wpi(stated_cutoff_hz: f64) -> Self {
        LowPass {
            order: 6,
            cutoff_hz: Cutoff::All(stated_cutoff_hz),
            form: FilterForm::Ba,
            convention: CutoffConvention::Wpi,
            padlen: Some(20),
        }
    }

    /// Designs the filter for one cut-off, Hz, at `rate_hz`.
    fn design(&self, cutoff_hz: f64, rate_hz: f64) -> Result<Designed, SignalError> {
        butter::check_rate(rate_hz)?;
        let wn = self.convention.wn(cutoff_hz, rate_hz);
        butter::check_wn_for(wn, cutoff_hz, rate_hz)?;
        Ok(match self.form {
            FilterForm::Ba => Designed::Ba(butter_lowpass_wn(self.order, wn)?),
            FilterForm::Sos => Designed::Sos(butter_lowpass_sos_wn(self.order, wn)?),
        })
    }

    /// Filters one signal with the cut-off `cutoff_hz` at `rate_hz`.
    ///
    /// ```rust
    /// use dvrk_ident::signal::LowPass;
    /// let lp = LowPass::default();
    /// let y = lp.apply_slice(&[2.0; 100], 5.0, 200.0).unwrap();
    /// assert!((y[0] - 2.0).abs() < 1e-12);
    /// ```
    pub fn apply_slice(
        &self,
        x: &[f64],
        cutoff_hz: f64,
        rate_hz: f64,
    ) -> Result<Vec<f64>, SignalError> {
        run(&self.design(cutoff_hz, rate_hz)?, x, self.padlen)
    }

    /// Filters every column of `m` (samples in rows) with its joint's cut-off.
    ///
    /// ```rust
    /// use dvrk_ident::signal::{Cutoff, LowPass};
    /// use nalgebra::DMatrix;
    /// let lp = LowPass { cutoff_hz: Cutoff::PerJoint(vec![5.0, 20.0]), ..LowPass::default() };
    /// let m = DMatrix::from_fn(200, 2, |i, _| (i as f64 * 0.05).sin());
    /// let y = lp.apply(&m, 200.0).unwrap();
    /// assert_eq!(y.shape(), (200, 2));
    /// ```
    pub fn apply(&self, m: &DMatrix<f64>, rate_hz: f64) -> Result<DMatrix<f64>, SignalError> {
        self.cutoff_hz.check(m.ncols())?;
        // Design once per distinct cut-off.
        let mut cache: Vec<(f64, Designed)> = Vec::new();
        let mut j = 0;
        ops::map_columns(m, |col| {
            let fc = self.cutoff_hz.for_joint(j).unwrap_or(f64::NAN);
            j += 1;
            let pos = match cache.iter().position(|(c, _)| c.to_bits() == fc.to_bits()) {
                Some(p) => p,
                None => {
                    cache.push((fc, self.design(fc, rate_hz)?));
                    cache.len() - 1
                }
            };
            run(&cache[pos].1, col, self.padlen)
        })
    }
}

impl LowPass {
    /// The filter for one cut-off, Hz, at `rate_hz`, ready to run sample by sample, and
    /// second-order sections with its poles (they bound its transients).
    pub(crate) fn stepper(
        &self,
        cutoff_hz: f64,
        rate_hz: f64,
    ) -> Result<(filter::Stepper, Vec<Section>), SignalError> {
        Ok(match self.design(cutoff_hz, rate_hz)? {
            Designed::Ba(tf) => {
                let wn = self.convention.wn(cutoff_hz, rate_hz);
                (
                    filter::Stepper::ba(&tf.b, &tf.a)?,
                    butter_lowpass_sos_wn(self.order, wn)?,
                )
            }
            Designed::Sos(sections) => (filter::Stepper::sos(&sections)?, sections),
        })
    }
}

fn run(d: &Designed, x: &[f64], padlen: Option<usize>) -> Result<Vec<f64>, SignalError> {
    match d {
        Designed::Ba(tf) => filtfilt(&tf.b, &tf.a, x, padlen),
        Designed::Sos(s) => sosfiltfilt(s, x, padlen),
    }
}

/// Which velocity the acceleration is differentiated from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AccelerationSource {
    /// The raw measured velocity (the 2019 protocol); falls back to the processed
    /// velocity when the log has none.
    #[default]
    RawVelocity,
    /// The processed (filtered) velocity.
    FilteredVelocity,
}

/// Processing settings for [`process`](fn@super::process). Every field has a default, so a settings file
/// only states what differs (`#[serde(default)]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Processing {
    /// Zero-phase low-pass applied to the motion: q, dq and ddq (and to tau with
    /// `filter_torque`); `None`: no filtering.
    pub filter: Option<LowPass>,
    /// Also low-pass the torques, as the 2019 protocol does. Off by default: the
    /// regressor is evaluated on the filtered motion, not filtered itself, so a filter
    /// on the torques alone smooths the Coulomb friction steps `Fc·sign(q̇)` at every
    /// velocity reversal on the measured side only. On a clean simulated log that
    /// leaves residuals 10–30 times the noise at the reversals and biases the friction
    /// and inertial estimates by tens of standard deviations; on the real 2019 dVRK logs
    /// the estimates barely change either way (least squares already averages white
    /// torque noise). Filtering is what differentiation needs, so it is applied to the
    /// motion.
    pub filter_torque: bool,
    /// Stencil to differentiate filtered positions when the log has no velocities.
    pub velocity_stencil: Stencil,
    /// Stencil to differentiate velocities into accelerations.
    pub acceleration_stencil: Stencil,
    /// Velocity that accelerations are differentiated from.
    pub acceleration_from: AccelerationSource,
    /// Samples dropped at each end after filtering (filter and difference edge effects),
    /// at most [`MAX_TRIM`].
    pub trim: usize,
    /// Keep every `decimate`-th sample after filtering and trimming (1: keep all).
    pub decimate: usize,
    /// Drop samples where some joint has |dq| below this, rad/s or m/s (Coulomb
    /// friction sign noise). `None`: keep all.
    pub min_speed: Option<f64>,
    /// Resample to this uniform rate, Hz, by linear interpolation before anything else.
    /// `None`: the log must already be uniform within `uniform_tolerance`.
    pub resample_hz: Option<f64>,
    /// Largest accepted relative deviation of a time step from the median step when not
    /// resampling (gaps and jitter beyond it are rejected).
    pub uniform_tolerance: f64,
    /// Measurement delay of each coordinate's torque, s (none: empty): the torque of
    /// coordinate `j` at `t + delay_s[j]` is the one the motion at `t` explains
    /// (`advance`), applied on the processing clock before the filters.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub delay_s: Vec<f64>,
}

/// Most samples [`Processing::trim`] may drop at each end: 10⁹, 58 days at 200 Hz and
/// far beyond any log, so that twice the trim never overflows and a state file (whose
/// processing is read, not given) cannot claim a trim no log could have had.
pub const MAX_TRIM: usize = 1_000_000_000;

impl Default for Processing {
    fn default() -> Self {
        Processing {
            filter: Some(LowPass::default()),
            filter_torque: false,
            velocity_stencil: Stencil::FivePoint,
            acceleration_stencil: Stencil::FivePoint,
            acceleration_from: AccelerationSource::RawVelocity,
            trim: 200,
            decimate: 1,
            min_speed: None,
            resample_hz: None,
            uniform_tolerance: 0.1,
            delay_s: Vec::new(),
        }
    }
}

/// Logs read for this processing resample to its rate ([`ReadOptions::for_processing`]).
///
/// [`ReadOptions::for_processing`]: crate::log::ReadOptions::for_processing
impl crate::log::Resampling for Processing {
    fn resample_hz(&self) -> Option<f64> {
        self.resample_hz
    }
}

impl Processing {
    /// Sets the motion's low-pass cut-off as `--cutoff` and Python's `cutoff=` do:
    /// `None` removes the filter; a cut-off keeps the filter's order, form and
    /// convention (the defaults where there was no filter), so that a new cut-off on a
    /// result's 2019 settings still converts it the 2019 way.
    ///
    /// ```
    /// use dvrk_ident::signal::{Cutoff, CutoffConvention, LowPass, Processing};
    /// let mut p = Processing::default();
    /// p.filter = Some(LowPass::wpi(5.4));
    /// p.set_cutoff(Some(Cutoff::All(3.0)));
    /// let f = p.filter.clone().unwrap();
    /// assert_eq!((f.cutoff_hz, f.convention), (Cutoff::All(3.0), CutoffConvention::Wpi));
    /// p.set_cutoff(None);
    /// assert!(p.filter.is_none());
    /// ```
    pub fn set_cutoff(&mut self, cutoff: Option<Cutoff>) {
        self.filter = cutoff.map(|cutoff_hz| LowPass {
            cutoff_hz,
            ..self.filter.take().unwrap_or_default()
        });
    }

    /// Checks the settings that do not depend on the data (cut-offs for `dof`
    /// coordinates, decimation, minimum speed), for the whole-log and the block
    /// processing alike.
    pub(crate) fn check(&self, dof: usize) -> Result<(), SignalError> {
        if let Some(f) = &self.filter {
            f.cutoff_hz.check(dof)?;
        }
        advance::check_delays(&self.delay_s, dof)?;
        if self.trim > MAX_TRIM {
            return Err(SignalError::InvalidSetting {
                name: "trim",
                reason: format!(
                    "{} samples at each end, more than the {MAX_TRIM} accepted",
                    self.trim
                ),
            });
        }
        if self.decimate == 0 {
            return Err(SignalError::InvalidSetting {
                name: "decimate",
                reason: "the decimation factor must be at least 1".into(),
            });
        }
        if let Some(s) = self.min_speed {
            if !(s.is_finite() && s >= 0.0) {
                return Err(SignalError::InvalidSetting {
                    name: "min_speed",
                    reason: format!("must be finite and non-negative, got {s}"),
                });
            }
        }
        if let Some(r) = self.resample_hz {
            if !(r.is_finite() && r > 0.0) {
                return Err(SignalError::InvalidSetting {
                    name: "resample_hz",
                    reason: format!("must be positive and finite, got {r}"),
                });
            }
        }
        if !(self.uniform_tolerance.is_finite() && self.uniform_tolerance >= 0.0) {
            return Err(SignalError::InvalidSetting {
                name: "uniform_tolerance",
                reason: format!(
                    "must be finite and non-negative, got {}",
                    self.uniform_tolerance
                ),
            });
        }
        Ok(())
    }

    /// The 2019 protocol for a stated cut-off (5.4 Hz PSM, 1.8 Hz MTM): 6th-order
    /// `(b, a)` Butterworth with the 2019 `Wn = 2 pi fc / fs` conversion (effective
    /// cut-off `pi * fc`) and 20-sample padding on q, measured dq, tau (`filter_torque`)
    /// and the 5-point derivative of the raw measured dq; 200 samples trimmed at each
    /// end.
    ///
    /// ```rust
    /// use dvrk_ident::signal::Processing;
    /// let p = Processing::wpi(5.4);
    /// assert_eq!(p.trim, 200);
    /// ```
    pub fn wpi(stated_cutoff_hz: f64) -> Self {
        Processing {
            filter: Some(LowPass::wpi(stated_cutoff_hz)),
            filter_torque: true,
            ..Processing::default()
        }
    }
}

/// Result of [`process`](fn@super::process): uniformly filtered signals, trimmed (and possibly decimated
/// or thinned), one row per kept sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Processed {
    /// Times of the kept samples, s (gaps show where samples were dropped).
    pub time: Vec<f64>,
    /// Filtered positions, rad or m.
    pub q: DMatrix<f64>,
    /// Velocities, rad/s or m/s: filtered measurement, or derivative of filtered q.
    pub dq: DMatrix<f64>,
    /// Accelerations, rad/s² or m/s²: filtered derivative of the velocity.
    pub ddq: DMatrix<f64>,
    /// Efforts, N·m or N: low-passed with `filter_torque`, else as measured.
    pub tau: DMatrix<f64>,
    /// One name per column.
    pub joint_names: Vec<String>,
    /// Joint space of the columns.
    pub coordinates: Coordinates,
    /// Rate at which the signals were filtered and differentiated, Hz (before
    /// decimation).
    pub rate_hz: f64,
    /// Whether `dq` comes from a velocity measurement (else from differentiating q).
    pub dq_measured: bool,
    /// The trajectory's source.
    pub source: String,
}

impl Processed {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.q.nrows()
    }

    /// `true` when no sample is left.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
