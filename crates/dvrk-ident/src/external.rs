//! Joint torques as a time series in a CSV file: `time` (s), then one column per model
//! coordinate (N·m or N). `simulate --external-torque` reads it (the external torque
//! added to the simulated torques) and `residual --out` writes its estimates in the
//! same layout, so a residual can be fed back into a simulation.
//!
//! ```text
//! time,outer_yaw,outer_pitch,...      # optional header: time and the coordinates
//! 0.0,0.0,0.0,...
//! 1.0,0.0,0.0,...
//! 1.0,0.1,0.0,...                     # a repeated time is a step
//! ```
//!
//! Between rows the torque is linear in time; outside the file's span it is zero. Empty
//! lines and lines starting with `#` are skipped.

use std::path::Path;

use nalgebra::DMatrix;

use crate::error::IdentError;

/// A torque per model coordinate over time (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalTorque {
    /// Sample times, s, non-decreasing.
    pub time: Vec<f64>,
    /// One row per time, one column per coordinate, N·m or N.
    pub tau: DMatrix<f64>,
}

impl ExternalTorque {
    /// Reads a CSV file for a model with coordinates `coordinates`.
    pub fn read_csv(path: &Path, coordinates: &[String]) -> Result<ExternalTorque, IdentError> {
        let file = path.display().to_string();
        let text = dvrk_model::input::read_text(path).map_err(|source| IdentError::Io {
            file: file.clone(),
            source,
        })?;
        ExternalTorque::parse_csv(&text, &file, coordinates)
    }

    /// [`ExternalTorque::read_csv`] of a file's text (`file` names it in errors).
    pub fn parse_csv(
        text: &str,
        file: &str,
        coordinates: &[String],
    ) -> Result<ExternalTorque, IdentError> {
        let n = coordinates.len();
        let format = |line: usize, message: String| IdentError::Format {
            file: file.into(),
            message: format!("line {line}: {message}"),
        };
        let (mut time, mut values) = (Vec::new(), Vec::new());
        let mut first = true;
        for (k, line) in text.lines().enumerate() {
            let line_no = k + 1;
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if std::mem::take(&mut first) && fields[0].parse::<f64>().is_err() {
                let expected: Vec<&str> = std::iter::once("time")
                    .chain(coordinates.iter().map(String::as_str))
                    .collect();
                if fields != expected {
                    return Err(format(
                        line_no,
                        format!(
                            "the header must be `{}` (time, then the model's coordinates)",
                            expected.join(",")
                        ),
                    ));
                }
                continue;
            }
            if fields.len() != n + 1 {
                return Err(format(
                    line_no,
                    format!(
                        "{} fields; expected {} (time and {n} coordinates)",
                        fields.len(),
                        n + 1
                    ),
                ));
            }
            let mut row = Vec::with_capacity(n + 1);
            for (c, f) in fields.iter().enumerate() {
                let v: f64 = f.parse().map_err(|_| {
                    format(line_no, format!("field {}: `{f}` is not a number", c + 1))
                })?;
                if !v.is_finite() || v.abs() > dvrk_model::input::MAX_VALUE {
                    return Err(format(
                        line_no,
                        format!(
                            "field {}: {v} is not a finite number of sensible size",
                            c + 1
                        ),
                    ));
                }
                row.push(v);
            }
            if let Some(&last) = time.last() {
                if row[0] < last {
                    return Err(format(
                        line_no,
                        format!("time {} s goes back (previous {last} s)", row[0]),
                    ));
                }
            }
            time.push(row[0]);
            values.extend_from_slice(&row[1..]);
        }
        if time.is_empty() {
            return Err(IdentError::Format {
                file: file.into(),
                message: "no rows of torques".into(),
            });
        }
        let tau = DMatrix::from_row_slice(time.len(), n, &values);
        Ok(ExternalTorque { time, tau })
    }

    /// The torque at `t` (s) into `out` (one per coordinate): linear between rows, the
    /// later row's value at a repeated time, zero outside the rows' span.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        out.fill(0.0);
        let (first, last) = (self.time[0], *self.time.last().expect("rows"));
        if !(t >= first && t <= last) {
            return;
        }
        // The last row at or before t.
        let k = self.time.partition_point(|&x| x <= t) - 1;
        if k + 1 == self.time.len() || self.time[k] == t {
            for (j, o) in out.iter_mut().enumerate() {
                *o = self.tau[(k, j)];
            }
            return;
        }
        let w = (t - self.time[k]) / (self.time[k + 1] - self.time[k]);
        for (j, o) in out.iter_mut().enumerate() {
            *o = (1.0 - w) * self.tau[(k, j)] + w * self.tau[(k + 1, j)];
        }
    }

    /// The CSV text of the torques: a header `time,<names>`, then one row per sample.
    /// `{}` prints the shortest decimal that reads back as the same number.
    pub fn to_csv(&self, names: &[String]) -> String {
        let mut out = String::from("time");
        for n in names {
            out.push(',');
            out.push_str(n);
        }
        out.push('\n');
        for (k, t) in self.time.iter().enumerate() {
            out.push_str(&t.to_string());
            for v in self.tau.row(k).iter() {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out.push('\n');
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        vec!["a".into(), "b".into()]
    }

    #[test]
    fn interpolates_steps_and_is_zero_outside() {
        let text = "time,a,b\n# a step at 1 s\n0,0,1\n1,1,1\n1,3,-1\n2,3,-1\n";
        let e = ExternalTorque::parse_csv(text, "x.csv", &names()).unwrap();
        let mut out = [0.0; 2];
        e.at(0.5, &mut out);
        assert_eq!(out, [0.5, 1.0]);
        e.at(1.0, &mut out);
        assert_eq!(out, [3.0, -1.0]);
        e.at(1.5, &mut out);
        assert_eq!(out, [3.0, -1.0]);
        e.at(2.5, &mut out);
        assert_eq!(out, [0.0, 0.0]);
        e.at(-0.1, &mut out);
        assert_eq!(out, [0.0, 0.0]);
        let back = ExternalTorque::parse_csv(&e.to_csv(&names()), "y.csv", &names()).unwrap();
        assert_eq!(back, e);
    }

    #[test]
    fn bad_files_are_refused_with_the_line() {
        let err = |text: &str| {
            ExternalTorque::parse_csv(text, "x.csv", &names())
                .unwrap_err()
                .to_string()
        };
        assert!(err("time,a,c\n0,1,2\n").contains("header must be `time,a,b`"));
        assert!(err("0,1\n").contains("line 1: 2 fields; expected 3"));
        assert!(err("0,1,2\n1,x,2\n").contains("line 2: field 2: `x`"));
        assert!(err("0,1,nan\n").contains("not a finite number"));
        assert!(err("1,1,2\n0,1,2\n").contains("line 2: time 0 s goes back"));
        assert!(err("time,a,b\n").contains("x.csv: no rows"));
    }
}
