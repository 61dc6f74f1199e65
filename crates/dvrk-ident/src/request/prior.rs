//! Where the semidefinite fit's prior comes from (`--prior nominal|RESULT|none`, Python
//! `prior=`): the description's nominal values, whole or partial, an earlier result, or
//! none at all (to leave out a preset's or a base's prior).

use std::path::PathBuf;
use std::sync::Arc;

use dvrk_model::Model;

use crate::settings::{Prior, PriorMetric};
use crate::{FitResult, IdentError};

/// Where a prior's values come from.
#[derive(Clone, Debug)]
pub enum PriorSource {
    /// No prior: `none`, the flag's default, spelled out to leave out the prior of
    /// `--preset dvrk` or of the settings a fit starts from. (`--prior-weight 0` is not
    /// the same: the regularization still pulls toward the prior, which places what the
    /// data do not determine.)
    None,
    /// The robot description's nominal parameters (a URDF's inertias, a description's
    /// `nominal` entries).
    Nominal,
    /// An earlier result document.
    File(PathBuf),
    /// An earlier result in memory (e.g. Python's `prior=result`).
    Result(Arc<FitResult>),
}

/// As the flag reads it: `"nominal"`, `"none"` or the file's path (a result in memory as its
/// description).
impl serde::Serialize for PriorSource {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            PriorSource::None => s.serialize_str("none"),
            PriorSource::Nominal => s.serialize_str("nominal"),
            PriorSource::File(p) => s.serialize_str(&p.display().to_string()),
            PriorSource::Result(r) => s.collect_str(&format_args!(
                "a result in memory ({}, robot {})",
                r.tool, r.robot
            )),
        }
    }
}

/// `"nominal"`, `"none"` or a file's path.
impl<'de> serde::Deserialize<'de> for PriorSource {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        String::deserialize(d)?
            .parse()
            .map_err(<D::Error as serde::de::Error>::custom)
    }
}

/// Results in memory are equal when they are the same one.
impl PartialEq for PriorSource {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (PriorSource::None, PriorSource::None) => true,
            (PriorSource::Nominal, PriorSource::Nominal) => true,
            (PriorSource::File(a), PriorSource::File(b)) => a == b,
            (PriorSource::Result(a), PriorSource::Result(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

impl std::str::FromStr for PriorSource {
    type Err = crate::options::ValueError;

    /// `nominal`, `none`, or the path of a result file (`./none` for a file named so).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "" => Err(crate::options::ValueError::NoPrior),
            "none" => Ok(PriorSource::None),
            "nominal" => Ok(PriorSource::Nominal),
            path => Ok(PriorSource::File(PathBuf::from(path))),
        }
    }
}

/// `result`'s parameters for every parameter of `model` (a result without Stribeck
/// terms gets `Fs = 0`, the same friction law); errors name `source`.
fn result_values(result: &FitResult, model: &Model, source: &str) -> Result<Vec<f64>, IdentError> {
    result.check_robot(model, source)?;
    let mut named = result.parameters.clone();
    for p in &model.params {
        if p.kind == dvrk_model::ParamKind::Stribeck && !named.contains_key(&p.name) {
            named.insert(p.name.clone(), 0.0);
        }
    }
    Ok(model.params_from_named(named.iter().map(|(k, v)| (k.as_str(), *v)), source)?)
}

/// Whether every link of `model` has a nominal rotational inertia (a URDF's inertials):
/// only then are its nominal parameters a whole prior. The dVRK publishes masses and
/// centres of mass (the MTM's URDF, the Si arms' physical DH), not inertias; their
/// zeros are no value, and the entropic metric needs a positive definite prior.
fn every_nominal_inertia(model: &Model) -> bool {
    model
        .frames
        .iter()
        .filter(|f| f.inertia.is_some())
        .all(|f| f.nominal.inertia.is_some())
}

/// The partial prior of a robot whose description gives nominal values for some links
/// only, or no rotational inertias (the dVRK publishes link masses and centres of mass,
/// not the parallelograms, inertias, motor inertias or springs): per link with a
/// positive nominal mass, the mass, the first moment when it gives a centre of mass and
/// the rotational inertia when it gives that too; nothing else (an element's nominal
/// defaults, e.g. zero friction, are no published value). The prior term leaves the
/// other parameters free (`estimate::sdp`, "Priors"). Errors when no link has a
/// nominal mass.
fn partial_nominal(model: &Model) -> Result<Prior, IdentError> {
    let mut parameters = indexmap::IndexMap::new();
    let mut links = 0;
    for f in &model.frames {
        let (Some(p0), Some(m)) = (f.inertia, f.nominal.mass) else {
            continue;
        };
        if m <= 0.0 {
            // A link the maker's model leaves without mass (the Classic ECM's
            // counterbalanced yaw and pitch): no published mass to pull toward.
            continue;
        }
        links += 1;
        let c = f.nominal.com.unwrap_or([0.0; 3]);
        let ic = f.nominal.inertia.unwrap_or([0.0; 6]);
        let bary = dvrk_model::inertia::barycentric_from_standard(m, c, ic);
        // Barycentric order [Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m].
        let mut given = vec![9];
        if f.nominal.com.is_some() {
            given.extend(6..9);
            if f.nominal.inertia.is_some() {
                given.extend(0..6);
            }
        }
        given.sort_unstable();
        for k in given {
            parameters.insert(model.params[p0 + k].name.clone(), bary[k]);
        }
    }
    if links == 0 {
        return Err(IdentError::Setting {
            name: crate::options::Setting::Prior.into(),
            message: format!(
                "robot {} has no nominal values (no link has a positive nominal mass): give an \
                 earlier result file instead",
                model.name
            ),
        });
    }
    let total = model.frames.iter().filter(|f| f.inertia.is_some()).count();
    Ok(Prior {
        source: format!(
            "nominal (partial: {} parameters of {links} of {total} links)",
            parameters.len()
        ),
        metric: PriorMetric::default(),
        weight: Prior::DEFAULT_WEIGHT,
        parameters,
    })
}

impl PriorSource {
    /// The values for every parameter of `model` (the model fitted), or, for
    /// [`PriorSource::Nominal`] on a robot without every nominal value, the partial
    /// prior of [`partial_nominal`]; `None` for [`PriorSource::None`].
    pub(super) fn parameters(&self, model: &Model) -> Result<Option<Prior>, IdentError> {
        let (source, values) = match self {
            PriorSource::None => return Ok(None),
            PriorSource::Nominal => match model.nominal_parameters() {
                Some(values) if every_nominal_inertia(model) => ("nominal".to_string(), values),
                _ => return partial_nominal(model).map(Some),
            },
            PriorSource::File(path) => {
                let source = path.display().to_string();
                let values = result_values(&FitResult::read(path)?, model, &source)?;
                (source, values)
            }
            PriorSource::Result(result) => {
                let source = format!(
                    "a result in memory ({}, robot {})",
                    result.tool, result.robot
                );
                let values = result_values(result, model, &source)?;
                (source, values)
            }
        };
        Ok(Some(Prior {
            source,
            metric: PriorMetric::default(),
            weight: Prior::DEFAULT_WEIGHT,
            parameters: model
                .params
                .iter()
                .zip(values)
                .map(|(p, v)| (p.name.clone(), v))
                .collect(),
        }))
    }
}
