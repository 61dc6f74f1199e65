//! Two fit results side by side (`dvrk-ident compare`, Python `compare`): the settings
//! that differ, the base parameters with their uncertainty, the full parameters and link
//! masses, and the per-joint errors of each result on test logs — what a lab asks after
//! a re-identification.
//!
//! Each result is evaluated on a test log exactly as `dvrk-ident validate` evaluates it:
//! with its own model (the fit's model options applied) and its own processing
//! settings ([`prepare`], then [`joint_metrics`]); both in the joints of the first
//! result's settings ([`crate::settings::Joints`]), so that their columns line up.
//!
//! ```no_run
//! use dvrk_ident::compare::{compare, Side};
//! use dvrk_ident::FitResult;
//!
//! let (a, b) = (
//!     FitResult::read("a.json".as_ref()).unwrap(),
//!     FitResult::read("b.json".as_ref()).unwrap(),
//! );
//! let (ma, mb) = (a.model(None).unwrap(), b.model(None).unwrap());
//! let doc = compare(
//!     &Side { name: "a.json", result: &a, model: &ma },
//!     &Side { name: "b.json", result: &b, model: &mb },
//!     &[],
//!     None,
//! )
//! .unwrap();
//! for d in &doc.differences {
//!     println!("{}: {} -> {}", d.path, d.a, d.b);
//! }
//! ```

use dvrk_model::Model;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::IdentError;
use crate::fit::{joint_metrics, prepare, JointMap};
use crate::log::ReadOptions;
use crate::result::JointMetrics;
use crate::settings::Joints;
use crate::{FitResult, JointLog};

/// One of the two results: how it is named in the document and in errors (its file),
/// the result and the model that evaluates its parameters (the robot it records, with
/// the fit's model options: [`FitResult::model`]).
#[derive(Clone, Copy)]
pub struct Side<'a> {
    /// The result's file, or what stands for it.
    pub name: &'a str,
    /// The result.
    pub result: &'a FitResult,
    /// The model of its parameters.
    pub model: &'a Model,
}

impl Side<'_> {
    /// How this result reads a test log, from the caller's reading options (format,
    /// rate, topics): for its model's joints and at its processing's resampling rate,
    /// as `dvrk-ident validate` reads it. When both sides give the same options, a log
    /// is read once for both.
    pub fn read_options(&self, base: &ReadOptions) -> ReadOptions {
        base.for_model(self.model)
            .for_processing(&self.result.settings.processing)
    }
}

/// A test log as each result reads it ([`Side::read_options`]); both samples are the
/// same log (read once when the options agree).
#[derive(Clone, Copy)]
pub struct TestLog<'a> {
    /// The log's name in the document (its path, or the samples' source).
    pub name: &'a str,
    /// The log as read for result A and for result B.
    pub samples: [&'a JointLog; 2],
}

/// What the document says of each result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The result's file, or what stands for it.
    pub name: String,
    /// The robot's name (the same for both).
    pub robot: String,
    /// Where the robot came from (`builtin:psm` or a description's path).
    pub robot_source: String,
    /// The program and version that wrote the result.
    pub tool: String,
    /// The estimator.
    pub method: String,
    /// The solver converged (otherwise the numbers are not a result).
    pub converged: bool,
    /// Every link physically realizable and the friction bounds met.
    pub physically_consistent: bool,
    /// Observation rows of the fit (samples × coordinates).
    pub rows: usize,
    /// Condition number of the weighted base regressor.
    pub condition_number: f64,
    /// Residual variance of the weighted least-squares fit.
    pub sigma2: f64,
}

impl Summary {
    fn of(side: &Side<'_>) -> Summary {
        let r = side.result;
        Summary {
            name: side.name.to_string(),
            robot: r.robot.clone(),
            robot_source: r.robot_source.clone(),
            tool: r.tool.clone(),
            method: r.method.clone(),
            converged: r.solver.converged,
            physically_consistent: r.physically_consistent,
            rows: r.rows,
            condition_number: r.condition_number,
            sigma2: r.sigma2,
        }
    }
}

/// A setting (or `tool`, `robot_source`) whose values differ, with its value in result
/// A (`a`) and in result B (`b`).
use crate::settings::Difference;

/// A base parameter's value and standard deviation in one result.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// The fitted value (units of the leading parameter).
    pub value: f64,
    /// Its standard deviation.
    pub std: f64,
}

/// One base parameter of either result. A base parameter is matched by its name and its
/// expression (the same combination of standard parameters); one that only one result
/// has has `None` on the other side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaseRow {
    /// The leading parameter's name, e.g. `L2xx`.
    pub name: String,
    /// The combination of standard parameters.
    pub expression: String,
    /// Its estimate in result A.
    pub a: Option<Estimate>,
    /// Its estimate in result B.
    pub b: Option<Estimate>,
    /// `b − a`, when both have it.
    pub difference: Option<f64>,
    /// `|a − b| / sqrt(std_a² + std_b²)`, the difference in units of the combined
    /// standard deviation; `None` when one result lacks the parameter, or when both
    /// standard deviations are zero and the values differ.
    pub sigmas: Option<f64>,
}

/// The base parameters side by side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaseComparison {
    /// Both results have the same base parameters (names and expressions), so they
    /// compare one by one.
    pub comparable: bool,
    /// Why they are not, when they are not.
    pub reason: Option<String>,
    /// A's base parameters in its order, then those only B has.
    pub parameters: Vec<BaseRow>,
}

/// A named number of both results (`None` where one result has no such entry).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pair {
    /// The parameter's or link's name.
    pub name: String,
    /// Its value in result A.
    pub a: Option<f64>,
    /// Its value in result B.
    pub b: Option<f64>,
}

/// The per-joint errors of both results on one test log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TestComparison {
    /// The log.
    pub log: String,
    /// Result A's errors, with its model and processing.
    pub a: JointMetrics,
    /// Result B's errors, with its model and processing.
    pub b: JointMetrics,
}

/// The comparison document (`dvrk-ident compare --json`, Python `compare`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Result A.
    pub a: Summary,
    /// Result B.
    pub b: Summary,
    /// Every leaf of `settings`, `tool` and `robot_source` whose values differ (the
    /// method is `settings.method`), in the document's key order.
    pub differences: Vec<Difference>,
    /// The base parameters with their standard deviations.
    pub base_parameters: BaseComparison,
    /// Every parameter's value, A's order then those only B has (not identified one by
    /// one: least squares gives a representative, zero off the base columns).
    pub parameters: Vec<Pair>,
    /// Each link's mass, kg.
    pub link_masses: Vec<Pair>,
    /// The errors on each test log.
    pub tests: Vec<TestComparison>,
}

/// Refuses two results of different robots, in one line.
pub fn check_robots(a: &Side<'_>, b: &Side<'_>) -> Result<(), IdentError> {
    if a.result.robot == b.result.robot {
        return Ok(());
    }
    Err(IdentError::DifferentRobots {
        a: a.name.to_string(),
        a_robot: a.result.robot.clone(),
        b: b.name.to_string(),
        b_robot: b.result.robot.clone(),
    })
}

/// Compares two results of the same robot, with each one's errors on `tests` over their
/// first `window` processed samples (all if `None`), as `dvrk-ident validate` computes
/// them. Errors name the result or the log at fault.
pub fn compare(
    a: &Side<'_>,
    b: &Side<'_>,
    tests: &[TestLog<'_>],
    window: Option<usize>,
) -> Result<Comparison, IdentError> {
    check_robots(a, b)?;
    let tests = tests
        .iter()
        .map(|t| test_errors(a, b, t, window))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Comparison {
        a: Summary::of(a),
        b: Summary::of(b),
        differences: differences(a.result, b.result),
        base_parameters: base_parameters(a, b),
        parameters: pairs(
            a.result.parameters.iter().map(|(k, v)| (k.as_str(), *v)),
            b.result.parameters.iter().map(|(k, v)| (k.as_str(), *v)),
        ),
        link_masses: pairs(
            a.result.links.iter().map(|l| (l.link.as_str(), l.mass)),
            b.result.links.iter().map(|l| (l.link.as_str(), l.mass)),
        ),
        tests,
    })
}

/// The errors of both results on one test log (an entry of [`Comparison::tests`]),
/// for callers that read their logs one at a time.
pub fn test_errors(
    a: &Side<'_>,
    b: &Side<'_>,
    log: &TestLog<'_>,
    window: Option<usize>,
) -> Result<TestComparison, IdentError> {
    check_robots(a, b)?;
    // Both in the joints of the first result, so that the columns line up.
    let joints = a.result.settings.joints;
    Ok(TestComparison {
        log: log.name.to_string(),
        a: errors(a, log.name, log.samples[0], window, joints)?,
        b: errors(b, log.name, log.samples[1], window, joints)?,
    })
}

/// One result's errors on one log, as `dvrk-ident validate` computes them; refuses
/// metrics that are not numbers.
fn errors(
    side: &Side<'_>,
    name: &str,
    log: &JointLog,
    window: Option<usize>,
    joints: Joints,
) -> Result<JointMetrics, IdentError> {
    let params = side
        .result
        .params_for(side.model)
        .map_err(|e| IdentError::Format {
            file: side.name.to_string(),
            message: e.to_string(),
        })?;
    let evaluated = |error: Box<dyn std::error::Error + Send + Sync>| IdentError::Evaluated {
        result: side.name.to_string(),
        error,
    };
    let data = prepare(side.model, log, &side.result.settings.processing)
        .map_err(|e| evaluated(Box::new(e)))?;
    let joints = JointMap::new(side.model, joints)?;
    let m = joint_metrics(side.model, &params, &data, window, &joints)?;
    m.check_finite(name).map_err(|e| evaluated(Box::new(e)))?;
    Ok(m)
}

/// The part of a result whose differences are listed: its settings, the program that
/// wrote it and its robot's source.
fn compared_part(r: &FitResult) -> Value {
    let mut doc = serde_json::Map::new();
    doc.insert("tool".into(), Value::String(r.tool.clone()));
    doc.insert("robot_source".into(), Value::String(r.robot_source.clone()));
    doc.insert(
        "settings".into(),
        serde_json::to_value(&r.settings).expect("settings serialize"),
    );
    Value::Object(doc)
}

/// Every differing leaf of the two results' settings (and `tool`, `robot_source`).
pub fn differences(a: &FitResult, b: &FitResult) -> Vec<Difference> {
    crate::settings::json_differences(&compared_part(a), &compared_part(b))
}

/// The base parameters of both results matched by name and expression.
fn base_parameters(a: &Side<'_>, b: &Side<'_>) -> BaseComparison {
    let (ba, bb) = (&a.result.base_parameters, &b.result.base_parameters);
    let key = |p: &crate::result::BaseParameterResult| (p.name.clone(), p.expression.clone());
    let estimate = |p: &crate::result::BaseParameterResult| Estimate {
        value: p.value,
        std: p.std,
    };
    let mut rows: Vec<BaseRow> = ba
        .iter()
        .map(|pa| {
            let pb = bb.iter().find(|pb| key(pb) == key(pa));
            row(pa, Some(estimate(pa)), pb.map(estimate))
        })
        .collect();
    rows.extend(
        bb.iter()
            .filter(|pb| !ba.iter().any(|pa| key(pa) == key(pb)))
            .map(|pb| row(pb, None, Some(estimate(pb)))),
    );
    let only_a = rows.iter().filter(|r| r.b.is_none()).count();
    let only_b = rows.iter().filter(|r| r.a.is_none()).count();
    let reason = (only_a + only_b > 0).then(|| {
        let mut why = format!(
            "{} has {} base parameters and {} has {}, {} of them the same combination \
             (name and expression)",
            a.name,
            ba.len(),
            b.name,
            bb.len(),
            rows.len() - only_a - only_b
        );
        let stribeck = (
            a.result.settings.stribeck_velocity,
            b.result.settings.stribeck_velocity,
        );
        if a.result.robot_source != b.result.robot_source {
            why.push_str(&format!(
                ": the robots come from different descriptions ({} and {})",
                a.result.robot_source, b.result.robot_source
            ));
        } else if stribeck.0.is_some() != stribeck.1.is_some() {
            why.push_str(
                ": only one of them adds Stribeck friction terms (settings.stribeck_velocity)",
            );
        } else {
            why.push_str(": their models differ");
        }
        why.push_str("; only the common ones are compared");
        why
    });
    BaseComparison {
        comparable: reason.is_none(),
        reason,
        parameters: rows,
    }
}

fn row(
    p: &crate::result::BaseParameterResult,
    a: Option<Estimate>,
    b: Option<Estimate>,
) -> BaseRow {
    let (difference, sigmas) = match (a, b) {
        (Some(a), Some(b)) => {
            let d = b.value - a.value;
            let s = a.std.hypot(b.std);
            let sigmas = if d == 0.0 {
                Some(0.0)
            } else if s > 0.0 {
                Some(d.abs() / s)
            } else {
                None
            };
            (Some(d), sigmas)
        }
        _ => (None, None),
    };
    BaseRow {
        name: p.name.clone(),
        expression: p.expression.clone(),
        a,
        b,
        difference,
        sigmas,
    }
}

/// Named values of both results: A's in its order, then those only B has.
fn pairs<'n>(
    a: impl Iterator<Item = (&'n str, f64)>,
    b: impl Iterator<Item = (&'n str, f64)>,
) -> Vec<Pair> {
    let b: Vec<(&str, f64)> = b.collect();
    let mut out: Vec<Pair> = a
        .map(|(name, v)| Pair {
            name: name.to_string(),
            a: Some(v),
            b: b.iter().find(|(n, _)| *n == name).map(|(_, v)| *v),
        })
        .collect();
    for (name, v) in b {
        if !out.iter().any(|p| p.name == name) {
            out.push(Pair {
                name: name.to_string(),
                a: None,
                b: Some(v),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn diffs(a: Value, b: Value) -> Vec<(String, Value, Value)> {
        crate::settings::json_differences(&a, &b)
            .into_iter()
            .map(|d| (d.path, d.a, d.b))
            .collect()
    }

    #[test]
    fn differences_are_the_differing_leaves() {
        let a = json!({"s": {"x": 1.0, "v": [1.0, 2.0], "w": [1.0], "f": {"c": 5.4}, "n": null}});
        let b = json!({"s": {"x": 1.0, "v": [1.0, 3.0], "w": [1.0, 2.0], "f": null, "m": 2}});
        // In the document's key order, which depends on serde_json's features: sorted.
        let mut found = diffs(a.clone(), b);
        found.sort_by(|x, y| x.0.cmp(&y.0));
        assert_eq!(
            found,
            vec![
                ("s.f".into(), json!({"c": 5.4}), Value::Null),
                ("s.m".into(), Value::Null, json!(2)),
                ("s.v[1]".into(), json!(2.0), json!(3.0)),
                ("s.w".into(), json!([1.0]), json!([1.0, 2.0])),
            ]
        );
        assert!(diffs(a.clone(), a).is_empty());
    }

    #[test]
    fn sigmas_are_the_difference_over_the_combined_std() {
        let p = crate::result::BaseParameterResult {
            name: "L2xx".into(),
            expression: "L2xx".into(),
            value: 0.0,
            std: 0.0,
        };
        let e = |value, std| Some(Estimate { value, std });
        let r = row(&p, e(1.0, 3.0), e(6.0, 4.0));
        assert_eq!((r.difference, r.sigmas), (Some(5.0), Some(1.0)));
        assert_eq!(row(&p, e(1.0, 0.0), e(1.0, 0.0)).sigmas, Some(0.0));
        assert_eq!(row(&p, e(1.0, 0.0), e(2.0, 0.0)).sigmas, None);
        assert_eq!(row(&p, e(1.0, 0.1), None).difference, None);
    }
}
