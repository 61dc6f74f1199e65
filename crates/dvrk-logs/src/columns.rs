//! The column grammar of a table of joint samples, one for every table a log comes in:
//! the headered CSV (`log::csv`) and, in the Python module, a pandas DataFrame.
//!
//! A column is `time` (s) or `<signal>.<joint>`, where the signal is `position` (also
//! `q`), `velocity` (`dq`) or `effort` (`tau`, `torque`) and the joint any name (dots
//! allowed: the signal ends at the first dot). The joints are those of the position
//! columns, in their order; each has one effort column and either every joint or none
//! a velocity column. Only the names are read here, so each reader keeps its own way
//! of getting the values and of naming its input in errors.

use thiserror::Error;

use crate::joint_log::Signal;

/// What one column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColumnKind {
    /// The sample times.
    Time,
    /// A signal of the joint at this index of [`ColumnLayout::joints`].
    Joint(Signal, usize),
}

/// The columns of a table, classified: what each holds and the joints they name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnLayout {
    /// One entry per column, in the table's order.
    pub kinds: Vec<ColumnKind>,
    /// The joints, in the order of their position columns.
    pub joints: Vec<String>,
    /// Whether the table has velocity columns (then one for every joint).
    pub with_velocity: bool,
}

/// Why a table's column names are not a log's.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum ColumnError {
    /// Two columns of the same signal and joint, or two time columns.
    #[error("duplicate column {column:?}")]
    Duplicate {
        /// The second of the two.
        column: String,
    },
    /// A name that is neither the time nor `<signal>.<joint>`.
    #[error("unknown column {column:?}: expected {time}, position.<joint>, velocity.<joint> or effort.<joint> (also q., dq., tau.)")]
    Unknown {
        /// The name.
        column: String,
        /// The time column's name.
        time: String,
    },
    /// A velocity or effort column for a joint without a position column.
    #[error("column {column:?} has no matching \"position.{joint}\" column")]
    Orphan {
        /// The name.
        column: String,
        /// Its joint.
        joint: String,
    },
    /// A joint without an effort column.
    #[error(
        "missing effort column for joint {joint:?} (expected a column named \"effort.{joint}\")"
    )]
    MissingEffort {
        /// The joint.
        joint: String,
    },
    /// Velocity columns for some joints only.
    #[error("missing velocity column for joint {joint:?}: velocity columns must be given for all joints or none")]
    PartialVelocity {
        /// The first joint without one.
        joint: String,
    },
    /// No position column.
    #[error("no position.<joint> column: the joint list is taken from the position columns")]
    NoJoints,
}

/// The signal a column-name prefix stands for (`position`/`q`, `velocity`/`dq`,
/// `effort`/`tau`/`torque`).
pub fn signal_of(prefix: &str) -> Option<Signal> {
    match prefix {
        "position" | "q" => Some(Signal::Position),
        "velocity" | "dq" => Some(Signal::Velocity),
        "effort" | "tau" | "torque" => Some(Signal::Effort),
        _ => None,
    }
}

/// Whether `joints` are the model coordinates' names `q1, q2, ..., qn` in order: what a
/// log in model coordinates names its joints (measured joints carry the robot's joint
/// names), so a table without a robot at hand tells the two apart by its names.
pub fn are_model_coordinate_names(joints: &[String]) -> bool {
    !joints.is_empty()
        && joints
            .iter()
            .enumerate()
            .all(|(k, j)| j.strip_prefix('q') == Some((k + 1).to_string().as_str()))
}

impl ColumnLayout {
    /// Classifies `names` (the header of a CSV, the columns of a DataFrame), where
    /// `time` is the time column's name. The time column may be absent (a DataFrame's
    /// index can hold the times); a reader that needs it checks [`Self::time`].
    ///
    /// ```
    /// use dvrk_logs::columns::{ColumnKind, ColumnLayout};
    /// use dvrk_logs::Signal;
    /// let names = ["time", "q.yaw", "tau.yaw", "position.pitch", "effort.pitch"];
    /// let layout = ColumnLayout::parse(&names, "time").unwrap();
    /// assert_eq!(layout.joints, ["yaw", "pitch"]);
    /// assert_eq!(layout.kinds[2], ColumnKind::Joint(Signal::Effort, 0));
    /// assert!(!layout.with_velocity);
    /// ```
    pub fn parse<S: AsRef<str>>(names: &[S], time: &str) -> Result<Self, ColumnError> {
        let mut parsed: Vec<Option<(Signal, &str)>> = Vec::with_capacity(names.len());
        let mut joints: Vec<String> = Vec::new();
        for (i, name) in names.iter().map(AsRef::as_ref).enumerate() {
            let duplicate = || ColumnError::Duplicate {
                column: name.to_string(),
            };
            if name == time {
                if parsed.iter().any(Option::is_none) {
                    return Err(duplicate());
                }
                parsed.push(None);
                continue;
            }
            let split = name
                .split_once('.')
                .and_then(|(prefix, joint)| Some((signal_of(prefix)?, joint)))
                .filter(|(_, joint)| !joint.is_empty());
            let Some((signal, joint)) = split else {
                return Err(ColumnError::Unknown {
                    column: name.to_string(),
                    time: time.to_string(),
                });
            };
            if parsed[..i].contains(&Some((signal, joint))) {
                return Err(duplicate());
            }
            if signal == Signal::Position {
                joints.push(joint.to_string());
            }
            parsed.push(Some((signal, joint)));
        }
        if joints.is_empty() {
            return Err(ColumnError::NoJoints);
        }
        let mut kinds = Vec::with_capacity(names.len());
        let mut have = vec![[false; 2]; joints.len()]; // velocity, effort
        for (name, column) in names.iter().zip(&parsed) {
            let Some((signal, joint)) = *column else {
                kinds.push(ColumnKind::Time);
                continue;
            };
            let Some(j) = joints.iter().position(|x| x == joint) else {
                return Err(ColumnError::Orphan {
                    column: name.as_ref().to_string(),
                    joint: joint.to_string(),
                });
            };
            match signal {
                Signal::Velocity => have[j][0] = true,
                Signal::Effort => have[j][1] = true,
                _ => {}
            }
            kinds.push(ColumnKind::Joint(signal, j));
        }
        if let Some(j) = have.iter().position(|h| !h[1]) {
            return Err(ColumnError::MissingEffort {
                joint: joints[j].clone(),
            });
        }
        let with_velocity = have.iter().any(|h| h[0]);
        if let Some(j) = have.iter().position(|h| with_velocity && !h[0]) {
            return Err(ColumnError::PartialVelocity {
                joint: joints[j].clone(),
            });
        }
        Ok(ColumnLayout {
            kinds,
            joints,
            with_velocity,
        })
    }

    /// The index of the time column, if the table has one.
    pub fn time(&self) -> Option<usize> {
        self.kinds.iter().position(|k| *k == ColumnKind::Time)
    }

    /// The index of the column of `signal` for joint `joint` (an index into
    /// [`Self::joints`]), if the table has one.
    pub fn column(&self, signal: Signal, joint: usize) -> Option<usize> {
        self.kinds
            .iter()
            .position(|k| *k == ColumnKind::Joint(signal, joint))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(names: &[&str]) -> Result<ColumnLayout, ColumnError> {
        ColumnLayout::parse(names, "time")
    }

    #[test]
    fn the_joints_follow_the_position_columns_and_aliases_mix() {
        let l = parse(&[
            "effort.b",
            "time",
            "q.a",
            "dq.a",
            "position.b",
            "velocity.b",
            "torque.a",
        ])
        .unwrap();
        assert_eq!(l.joints, ["a", "b"]);
        assert!(l.with_velocity);
        assert_eq!(l.time(), Some(1));
        assert_eq!(l.column(Signal::Effort, 1), Some(0));
        assert_eq!(l.column(Signal::Effort, 0), Some(6));
        assert_eq!(l.column(Signal::Velocity, 0), Some(3));
        // A joint name may hold dots: the signal ends at the first.
        let l = parse(&["time", "position.arm.j1", "effort.arm.j1"]).unwrap();
        assert_eq!(l.joints, ["arm.j1"]);
    }

    #[test]
    fn each_problem_is_named() {
        let cases: [(&[&str], ColumnError); 8] = [
            (
                &["time", "position.a", "q.a", "effort.a"],
                ColumnError::Duplicate {
                    column: "q.a".into(),
                },
            ),
            (
                &["time", "time", "position.a", "effort.a"],
                ColumnError::Duplicate {
                    column: "time".into(),
                },
            ),
            (
                &["time", "position.a", "effort.a", "speed.a"],
                ColumnError::Unknown {
                    column: "speed.a".into(),
                    time: "time".into(),
                },
            ),
            (
                &["time", "position.", "effort."],
                ColumnError::Unknown {
                    column: "position.".into(),
                    time: "time".into(),
                },
            ),
            (
                &["time", "position.a", "effort.a", "effort.b"],
                ColumnError::Orphan {
                    column: "effort.b".into(),
                    joint: "b".into(),
                },
            ),
            (
                &["time", "position.a", "position.b", "effort.a"],
                ColumnError::MissingEffort { joint: "b".into() },
            ),
            (
                &[
                    "time",
                    "position.a",
                    "position.b",
                    "effort.a",
                    "effort.b",
                    "velocity.b",
                ],
                ColumnError::PartialVelocity { joint: "a".into() },
            ),
            (&["time", "effort.a"], ColumnError::NoJoints),
        ];
        for (names, expected) in cases {
            assert_eq!(parse(names), Err(expected), "{names:?}");
        }
    }

    #[test]
    fn model_coordinate_names_are_q1_to_qn_in_order() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(are_model_coordinate_names(&names(&["q1", "q2", "q3"])));
        assert!(!are_model_coordinate_names(&names(&["q2", "q1"])));
        assert!(!are_model_coordinate_names(&names(&["q1", "yaw"])));
        assert!(!are_model_coordinate_names(&[]));
    }
}
