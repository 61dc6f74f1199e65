//! The keyword arguments that change fit settings, shared by `fit`, `observe` and
//! `prepare`, mapped onto the library's [`request::Overrides`] in one place.

use std::path::PathBuf;
use std::sync::Arc;

use dvrk_ident::fit::delay::DelayOption;
use dvrk_ident::request::{self, PriorSource};
use dvrk_ident::settings::Joints;
use dvrk_ident::signal::Cutoff;
use dvrk_ident::{FitSettings, Method};
use pyo3::prelude::*;

use crate::classes::FitResultPy;
use crate::errors::input;
use crate::json::from_python;

pub(crate) fn parse_method(text: &str) -> PyResult<Method> {
    crate::convert::named("method", text)
}

/// `joints=`: ``"model"`` or ``"measured"``.
pub(crate) fn parse_joints(text: &str) -> PyResult<Joints> {
    crate::convert::named("joints", text)
}

/// `delay=`: ``"auto"``, seconds, or a list of seconds (one per coordinate).
fn delay_option(d: &Bound<'_, PyAny>) -> PyResult<DelayOption> {
    if let Ok(text) = d.extract::<String>() {
        text.parse::<DelayOption>()
    } else if let Ok(v) = d.extract::<f64>() {
        Ok(DelayOption::Fixed(vec![v]))
    } else if let Ok(v) = d.extract::<Vec<f64>>() {
        Ok(DelayOption::Fixed(v))
    } else {
        Err("expected \"auto\", seconds, or a list of seconds".to_string())
    }
    .map_err(|e| input(format!("delay: {e}")))
}

/// `prior=`: ``"nominal"``, the path of a result document, or a :class:`FitResult`.
fn prior_source(p: &Bound<'_, PyAny>) -> PyResult<PriorSource> {
    if let Ok(r) = p.cast::<FitResultPy>() {
        return Ok(PriorSource::Result(Arc::new(r.get().inner.clone())));
    }
    if let Ok(text) = p.extract::<String>() {
        return text
            .parse::<PriorSource>()
            .map_err(|e| input(format!("prior: {e}")));
    }
    let path: PathBuf = p.extract().map_err(|_| {
        input("prior: expected \"nominal\", the path of a result document, or a FitResult")
    })?;
    Ok(PriorSource::File(path))
}

/// The keyword arguments that change the settings, shared by `fit`, `observe` and
/// `prepare`: a base (`settings`) and the library's [`request::Overrides`].
#[derive(Default)]
pub(crate) struct Overrides<'a, 'py> {
    pub settings: Option<&'a Bound<'py, PyAny>>,
    pub method: Option<&'a str>,
    pub cutoff: Option<&'a Bound<'py, PyAny>>,
    pub filter_torque: Option<bool>,
    pub trim: Option<usize>,
    pub test_window: Option<usize>,
    pub decimate: Option<usize>,
    pub min_speed: Option<f64>,
    pub resample: Option<f64>,
    pub irls_iterations: Option<usize>,
    pub sdp_regularization: Option<f64>,
    pub stribeck: Option<f64>,
    pub dahl: Option<f64>,
    pub bounds: Option<&'a str>,
    pub ellipsoids: Option<bool>,
    pub mounting_pitch: Option<f64>,
    pub delay: Option<&'a Bound<'py, PyAny>>,
    pub prior: Option<&'a Bound<'py, PyAny>>,
    pub prior_weight: Option<f64>,
    pub prior_metric: Option<&'a str>,
    pub preset: Option<&'a str>,
    pub joints: Option<&'a str>,
}

impl Overrides<'_, '_> {
    /// The base settings: `settings` (the result document's `settings` layout; missing
    /// fields take the defaults) or the defaults.
    pub(crate) fn base(&self, py: Python<'_>) -> PyResult<FitSettings> {
        match self.settings.filter(|s| !s.is_none()) {
            Some(obj) => from_python::<FitSettings>(py, obj, "settings"),
            None => Ok(FitSettings::default()),
        }
    }

    /// The keywords that are not `None`, as the library's overrides.
    pub(crate) fn overrides(&self) -> PyResult<request::Overrides> {
        let cutoff = match self.cutoff.filter(|c| !c.is_none()) {
            None => None,
            Some(c) => {
                let bad = || {
                    input(
                        "cutoff: expected a number (Hz), one number per coordinate, \
                         or \"none\" (no filter)",
                    )
                };
                Some(if c.extract::<bool>().ok() == Some(false) {
                    None
                } else if let Ok(text) = c.extract::<String>() {
                    Cutoff::parse_flag(&text).map_err(|e| input(format!("cutoff: {e}")))?
                } else if c.is_instance_of::<pyo3::types::PyBool>() {
                    return Err(bad());
                } else if let Ok(v) = c.extract::<f64>() {
                    Some(Cutoff::All(v))
                } else {
                    Some(Cutoff::PerJoint(
                        c.extract::<Vec<f64>>().map_err(|_| bad())?,
                    ))
                })
            }
        };
        Ok(request::Overrides {
            method: self.method.map(parse_method).transpose()?,
            cutoff,
            filter_torque: self.filter_torque,
            trim: self.trim,
            decimate: self.decimate,
            min_speed: self.min_speed,
            resample_hz: self.resample,
            test_window: self.test_window,
            irls_iterations: self.irls_iterations,
            sdp_regularization: self.sdp_regularization,
            stribeck_velocity: self.stribeck,
            dahl_sigma: self.dahl,
            bounds: self
                .bounds
                .map(|b| crate::convert::named("bounds", b))
                .transpose()?,
            ellipsoids: self.ellipsoids,
            mounting_pitch_deg: self.mounting_pitch,
            delay: self
                .delay
                .filter(|d| !d.is_none())
                .map(delay_option)
                .transpose()?,
            prior: self
                .prior
                .filter(|p| !p.is_none())
                .map(prior_source)
                .transpose()?,
            prior_weight: self.prior_weight,
            prior_metric: self
                .prior_metric
                .map(|m| crate::convert::named("prior_metric", m))
                .transpose()?,
            preset: self
                .preset
                .map(|p| crate::convert::named("preset", p))
                .transpose()?,
            joints: self.joints.map(parse_joints).transpose()?,
        })
    }

    /// `settings` (or the defaults), then each keyword that is not `None`.
    pub fn apply(&self, py: Python<'_>) -> PyResult<FitSettings> {
        Ok(self.overrides()?.apply(self.base(py)?))
    }
}
