//! pandas and numpy conventions for `JointLog`: sample times in any of numpy's time types
//! (converted exactly), joint columns named `position.<joint>` (or a MultiIndex), and
//! DataFrames out. pandas is imported only when a DataFrame is asked for.

use dvrk_ident::{Coordinates, Signal};
use dvrk_logs::columns::{are_model_coordinate_names, signal_of, ColumnLayout};
use dvrk_model::Model;
use nalgebra::DMatrix;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{float_array, fmt_shape};
use crate::errors::input;

/// Seconds from the first of integer nanoseconds, computed in integers and rounded once
/// (as the recording readers do: a 200 Hz log gives exactly `k / 200`).
fn from_first(ns: &[i64]) -> Vec<f64> {
    let t0 = ns.first().copied().unwrap_or(0);
    ns.iter()
        .map(|&t| (i128::from(t) - i128::from(t0)) as f64 / 1e9)
        .collect()
}

/// Sample times in seconds from `obj`: float seconds as they are; `datetime64`,
/// `timedelta64` (any unit), pandas datetimes (time-zone aware too) or integers
/// (nanoseconds) relative to the first sample, converted exactly before any rounding.
pub fn times(py: Python<'_>, obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("asarray", (obj,))
        .map_err(|e| input(format!("{name}: not an array: {e}")))?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if shape.len() != 1 {
        return Err(input(format!(
            "{name}: expected a 1-D array of N sample times, got shape {}",
            fmt_shape(&shape)
        )));
    }
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    let ns: Vec<i64> = match kind.as_str() {
        "M" | "m" => {
            let unit = if kind == "M" {
                "datetime64[ns]"
            } else {
                "timedelta64[ns]"
            };
            arr.call_method1("astype", (unit,))?
                .call_method1("view", ("int64",))?
                .call_method0("tolist")?
                .extract()?
        }
        "i" | "u" => arr
            .call_method0("tolist")?
            .extract()
            .map_err(|_| input(format!("{name}: integer times (ns) beyond 64 bits")))?,
        // pandas' time-zone aware datetimes come out of numpy as objects.
        "O" => {
            let pd = py
                .import("pandas")
                .map_err(|_| input(format!("{name}: an array of objects, not times")))?;
            let index = pd
                .call_method1("DatetimeIndex", (obj,))
                .map_err(|e| input(format!("{name}: neither numbers nor datetimes: {e}")))?;
            index.getattr("asi8")?.call_method0("tolist")?.extract()?
        }
        "b" => return Err(input(format!("{name}: booleans are not times"))),
        _ => {
            let arr = float_array(py, obj, name)?;
            let ro = numpy::PyArrayMethods::readonly(&arr);
            return Ok(ro.as_array().iter().copied().collect());
        }
    };
    if let Some(k) = ns.iter().position(|&t| t == i64::MIN) {
        return Err(input(format!("{name}: not a time (NaT) at sample {k}")));
    }
    Ok(from_first(&ns))
}

/// Joint names from a DataFrame's columns (or `None` for an object without columns),
/// a `signal.` prefix removed.
pub fn column_names(obj: &Bound<'_, PyAny>) -> PyResult<Option<Vec<String>>> {
    let Ok(columns) = obj.getattr("columns") else {
        return Ok(None);
    };
    let mut names = Vec::new();
    for c in columns.try_iter()? {
        let c = c?;
        let name = match c.extract::<(String, String)>() {
            Ok((_, joint)) => joint,
            Err(_) => c.str()?.to_string(),
        };
        let joint = match name.split_once('.') {
            Some((prefix, joint)) if signal_of(prefix).is_some() => joint.to_string(),
            _ => name,
        };
        names.push(joint);
    }
    Ok(Some(names))
}

/// Model coordinates when every name is one of the robot's coordinates (without a
/// robot: the names are `q1..qn` in order, as the headered CSV decides), measured joints when every name is one of its measured
/// joints (without a robot: otherwise); an error naming what fits neither.
pub fn infer_coordinates(names: &[String], model: Option<&Model>) -> PyResult<Coordinates> {
    match model {
        Some(m) => {
            if names.iter().all(|n| m.coordinates.contains(n)) {
                Ok(Coordinates::Model)
            } else if names.iter().all(|n| m.measured.joints.contains(n)) {
                Ok(Coordinates::Measured)
            } else {
                let unknown: Vec<&str> = names
                    .iter()
                    .filter(|n| !m.coordinates.contains(n) && !m.measured.joints.contains(n))
                    .map(String::as_str)
                    .collect();
                Err(input(format!(
                    "columns {unknown:?} are neither coordinates of robot {} ({}) nor its measured joints ({}); every column must be one or the other",
                    m.name,
                    m.coordinates.join(", "),
                    m.measured.joints.join(", ")
                )))
            }
        }
        None => Ok(if are_model_coordinate_names(names) {
            Coordinates::Model
        } else {
            Coordinates::Measured
        }),
    }
}

/// A DataFrame's samples by signal: joint names (the position columns' order) and the
/// `q`, `dq` (if every joint has one), `tau` matrices, and the time column or index.
pub struct Columns<'py> {
    pub joints: Vec<String>,
    pub q: DMatrix<f64>,
    pub dq: Option<DMatrix<f64>>,
    pub tau: DMatrix<f64>,
    pub time: Bound<'py, PyAny>,
}

/// Reads a DataFrame laid out as the headered CSV (its column grammar,
/// `dvrk_logs::columns`: `time`, `position.<joint>`, `velocity.<joint>`,
/// `effort.<joint>`, also `q.`, `dq.`, `tau.`) or with a two-level column MultiIndex
/// `(signal, joint)`, read as `signal.joint`; the time is the `time_column` (default
/// `"time"` if there is one) or the index.
pub fn read_frame<'py>(
    py: Python<'py>,
    df: &Bound<'py, PyAny>,
    time_column: Option<&str>,
) -> PyResult<Columns<'py>> {
    let columns = df
        .getattr("columns")
        .map_err(|_| input("df: expected a pandas DataFrame (no columns attribute)"))?;
    let wanted_time = time_column.unwrap_or("time");
    let mut keys = Vec::new();
    let mut names = Vec::new();
    for c in columns.try_iter()? {
        let c = c?;
        names.push(match c.extract::<(String, String)>() {
            Ok((signal, joint)) => format!("{signal}.{joint}"),
            Err(_) => c.str()?.to_string(),
        });
        keys.push(c);
    }
    let layout = ColumnLayout::parse(&names, wanted_time).map_err(|e| input(format!("df: {e}")))?;
    if time_column.is_some() && layout.time().is_none() {
        return Err(input(format!("df: no column {wanted_time:?}")));
    }
    let time = match layout.time() {
        Some(k) => df.get_item(&keys[k])?,
        None => {
            let index = df.getattr("index")?;
            let kind: String = index.getattr("dtype")?.getattr("kind")?.extract()?;
            let range = index.get_type().name()? == "RangeIndex";
            if range || !matches!(kind.as_str(), "M" | "m" | "f" | "i" | "u") {
                return Err(input(
                    "df: no sample times: give a time column (s, datetime64, timedelta64 or integer ns) or a datetime, timedelta or float index",
                ));
            }
            index
        }
    };
    let n: usize = df.call_method0("__len__")?.extract()?;
    // The matrix of one signal (the layout has checked that every joint has a column
    // of it, or, for the velocity, that none has).
    let gather = |signal: Signal| -> PyResult<DMatrix<f64>> {
        let mut m = DMatrix::zeros(n, layout.joints.len());
        for (j, joint) in layout.joints.iter().enumerate() {
            let k = layout
                .column(signal, j)
                .ok_or_else(|| input(format!("df: no {signal} column for joint {joint:?}")))?;
            let arr = float_array(py, &df.get_item(&keys[k])?, &format!("df[{:?}]", names[k]))?;
            let ro = numpy::PyArrayMethods::readonly(&arr);
            for (i, v) in ro.as_array().iter().enumerate() {
                m[(i, j)] = *v;
            }
        }
        Ok(m)
    };
    Ok(Columns {
        q: gather(Signal::Position)?,
        dq: layout
            .with_velocity
            .then(|| gather(Signal::Velocity))
            .transpose()?,
        tau: gather(Signal::Effort)?,
        joints: layout.joints.clone(),
        time,
    })
}

/// A DataFrame of `columns` (name, values by row), in order.
pub fn dataframe<'py>(
    py: Python<'py>,
    columns: Vec<(String, Vec<f64>)>,
) -> PyResult<Bound<'py, PyAny>> {
    let pd = py
        .import("pandas")
        .map_err(|_| input("to_dataframe needs pandas (pip install pandas)"))?;
    let data = PyDict::new(py);
    let order = PyList::empty(py);
    for (name, values) in columns {
        let n = values.len();
        data.set_item(&name, crate::convert::array(py, values, &[n]))?;
        order.append(name)?;
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("columns", order)?;
    pd.call_method("DataFrame", (data,), Some(&kwargs))
}

/// Columns `"{prefix}.{joint}"` of a samples × joints matrix.
pub fn matrix_columns(
    prefix: &str,
    joints: &[String],
    m: &DMatrix<f64>,
) -> Vec<(String, Vec<f64>)> {
    joints
        .iter()
        .enumerate()
        .map(|(j, name)| {
            (
                format!("{prefix}.{name}"),
                m.column(j).iter().copied().collect(),
            )
        })
        .collect()
}
