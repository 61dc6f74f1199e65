//! The checks on the JointState messages of one topic, message by message: the same
//! code for the survey of a file, for reading it block by block and for
//! [`super::read_joint_states`].

use std::collections::HashMap;

use super::channels::ChannelInfo;
use super::container::MessageRef;
use super::joint_state::{self, JointStateMsg};
use super::{McapProblem, TimeSource, JOINT_STATE_TYPE};
use crate::joint_log::Signal;

/// Whether a channel holds JointState messages this reader decodes.
pub(super) fn is_joint_state(c: &ChannelInfo) -> bool {
    let enc = c.message_encoding.as_str();
    (c.schema_name == JOINT_STATE_TYPE && (enc == "cdr" || enc == "json"))
        || (c.schema_name == "sensor_msgs/JointState" && (enc == "json" || enc == "ros1"))
}

/// Decodes message `index` of its topic and takes its time from `time_source`, ns.
pub(super) fn decode(
    m: &MessageRef<'_>,
    index: usize,
    time_source: TimeSource,
) -> Result<(JointStateMsg, i64), Box<McapProblem>> {
    let msg = match m.channel.message_encoding.as_str() {
        "json" => joint_state::decode_json(m.data),
        "ros1" => joint_state::decode_ros1(m.data),
        _ => joint_state::decode_cdr(m.data),
    }
    .map_err(|reason| Box::new(McapProblem::Decode { index, reason }))?;
    let stamp = match time_source {
        TimeSource::HeaderStamp => Ok(msg.header.stamp.as_nanos()),
        TimeSource::LogTime => i64::try_from(m.log_time).map_err(|_| m.log_time),
        TimeSource::PublishTime => i64::try_from(m.publish_time).map_err(|_| m.publish_time),
    }
    .map_err(|value| {
        Box::new(McapProblem::TimeOutOfRange {
            index,
            time_source,
            value,
        })
    })?;
    Ok((msg, stamp))
}

/// One checked message, in the joint order of the topic's first message. `velocity`
/// and `effort` are empty when the topic has none.
#[derive(Clone, Debug, Default)]
pub(super) struct JointRow {
    pub stamp: i64,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// What is known about a topic's messages so far.
#[derive(Debug)]
pub(super) struct TopicState {
    pub topic: String,
    /// Automatic mode: not a candidate (no positions or no efforts in message 0), why.
    pub rejected: Option<&'static str>,
    /// Messages seen (including a rejected first one).
    pub count: usize,
    pub names: Vec<String>,
    index_of: HashMap<String, usize>,
    /// Last message order that differed from `names`, and its permutation:
    /// `perm[j]` = index in the message of `names[j]`.
    reorder: Option<(Vec<String>, Vec<usize>)>,
    pub frame_id: String,
    pub has_velocity: bool,
    pub has_effort: bool,
    first_stamp: Option<i64>,
}

impl TopicState {
    pub(super) fn new(topic: &str) -> TopicState {
        TopicState {
            topic: topic.to_owned(),
            rejected: None,
            count: 0,
            names: Vec::new(),
            index_of: HashMap::new(),
            reorder: None,
            frame_id: String::new(),
            has_velocity: false,
            has_effort: false,
            first_stamp: None,
        }
    }

    /// Checks the next message; fills `row` with it unless the topic was just rejected
    /// (automatic mode, then `Ok(false)`).
    pub(super) fn check(
        &mut self,
        mut msg: JointStateMsg,
        stamp: i64,
        auto: bool,
        row: &mut JointRow,
    ) -> Result<bool, Box<McapProblem>> {
        let index = self.count;
        self.count += 1;
        let names = if msg.name.is_empty() {
            (1..=msg.position.len())
                .map(|k| format!("joint_{k}"))
                .collect()
        } else {
            std::mem::take(&mut msg.name)
        };
        if index == 0 && !self.first_message(&msg, &names, auto)? {
            return Ok(false);
        }
        // The permutation from this message's order to the first message's.
        let perm: Option<&[usize]> = if names == self.names {
            None
        } else {
            self.reorder_to(&names, index)?;
            self.reorder.as_ref().map(|(_, p)| p.as_slice())
        };
        self.check_arrays(&msg, &names, index, stamp)?;
        // (Empty arrays stay empty: a topic without velocities or efforts.)
        let copy = |out: &mut Vec<f64>, values: &[f64]| {
            out.clear();
            match perm {
                _ if values.is_empty() => {}
                None => out.extend_from_slice(values),
                Some(p) => out.extend(p.iter().map(|&k| values[k])),
            }
        };
        copy(&mut row.position, &msg.position);
        copy(&mut row.velocity, &msg.velocity);
        copy(&mut row.effort, &msg.effort);
        row.stamp = stamp;
        self.first_stamp.get_or_insert(stamp);
        Ok(true)
    }

    /// Message 0 sets the joints and which arrays the topic has; `Ok(false)`: the topic
    /// is rejected (automatic mode: no positions or no efforts).
    fn first_message(
        &mut self,
        msg: &JointStateMsg,
        names: &[String],
        auto: bool,
    ) -> Result<bool, Box<McapProblem>> {
        if auto && msg.position.is_empty() {
            self.rejected = Some("no positions");
            return Ok(false);
        }
        if auto && msg.effort.is_empty() {
            self.rejected = Some("no efforts");
            return Ok(false);
        }
        if names.is_empty() {
            return Err(Box::new(McapProblem::NoJoints { index: 0 }));
        }
        for (k, n) in names.iter().enumerate() {
            if self.index_of.insert(n.clone(), k).is_some() {
                return Err(Box::new(McapProblem::DuplicateJoint {
                    joint: n.clone(),
                    context: "in message 0".into(),
                }));
            }
        }
        self.names = names.to_vec();
        self.frame_id = msg.header.frame_id.clone();
        self.has_velocity = !msg.velocity.is_empty();
        self.has_effort = !msg.effort.is_empty();
        Ok(true)
    }

    /// Caches the permutation from the order `names` of message `index` to the first
    /// message's, or refuses a changed set of joints.
    fn reorder_to(&mut self, names: &[String], index: usize) -> Result<(), Box<McapProblem>> {
        let joints = self.names.len();
        let cached = matches!(&self.reorder, Some((order, _)) if *order == names);
        if !cached {
            let changed = || {
                Box::new(McapProblem::JointsChanged {
                    index,
                    first: self.names.clone(),
                    found: names.to_vec(),
                })
            };
            if names.len() != joints {
                return Err(changed());
            }
            let mut perm = vec![usize::MAX; joints];
            for (k, n) in names.iter().enumerate() {
                match self.index_of.get(n) {
                    Some(&j) if perm[j] == usize::MAX => perm[j] = k,
                    _ => return Err(changed()),
                }
            }
            self.reorder = Some((names.to_vec(), perm));
        }
        Ok(())
    }

    /// Every array of message `index`: present as in message 0, one value per joint,
    /// finite.
    fn check_arrays(
        &self,
        msg: &JointStateMsg,
        names: &[String],
        index: usize,
        stamp: i64,
    ) -> Result<(), Box<McapProblem>> {
        let joints = self.names.len();
        let arrays = [
            ("position", Signal::Position, &msg.position, true),
            (
                "velocity",
                Signal::Velocity,
                &msg.velocity,
                self.has_velocity,
            ),
            ("effort", Signal::Effort, &msg.effort, self.has_effort),
        ];
        for (field, signal, values, expected) in arrays {
            if values.is_empty() && field != "position" {
                if expected {
                    return Err(Box::new(McapProblem::Inconsistent {
                        index,
                        field,
                        empty: true,
                    }));
                }
                continue;
            }
            if !expected {
                return Err(Box::new(McapProblem::Inconsistent {
                    index,
                    field,
                    empty: false,
                }));
            }
            if values.len() != joints {
                return Err(Box::new(McapProblem::ArrayLength {
                    index,
                    field,
                    len: values.len(),
                    joints,
                }));
            }
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                let time_s = self
                    .first_stamp
                    .map_or(0.0, |s0| (i128::from(stamp) - i128::from(s0)) as f64 / 1e9);
                return Err(Box::new(McapProblem::NonFinite {
                    index,
                    time_s,
                    signal,
                    joint: names[k].clone(),
                    value: values[k],
                }));
            }
        }
        Ok(())
    }
}
