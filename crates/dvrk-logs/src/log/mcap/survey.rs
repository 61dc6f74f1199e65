//! The passes over an MCAP file that come before its samples: choosing the topics,
//! checking every message, and the timing checks of the merged clock, all without
//! keeping the samples.
//!
//! The first pass decodes and checks the messages of every candidate topic and keeps,
//! per topic, its stamp statistics: count, first and last stamps, order violations and
//! the median step ([`crate::median`]). Further passes read only the chosen topics'
//! stamps, and only when needed: to finish a median over very many distinct steps, to
//! redo the clock's statistics over the span the other topics cover, and to count and
//! locate irregular steps for an error message or the report of a resampled log.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::bag::Bag;
use super::container::{scan, MessageRef, Scanner};
use super::problem::mcap_error;
use super::topic::{decode, is_joint_state, JointRow, TopicState};
use super::{McapOptions, McapProblem, TimeSource, TopicInfo, GAP_FACTOR, JITTER_TOLERANCE};
use crate::log::LogError;
use crate::median::{ExactMedian, MedianPass};

/// The joint states of one topic as recorded: one row per message, columns in the
/// joint order of the first message.
#[derive(Clone, Debug, PartialEq)]
pub struct JointStateSeries {
    /// Topic name.
    pub topic: String,
    /// Joint names (the first message's order). Messages without names get
    /// `joint_1`, `joint_2`, ...
    pub joint_names: Vec<String>,
    /// `header.frame_id` of the first message.
    pub frame_id: String,
    /// Sample times, ns since the epoch, from the chosen [`TimeSource`].
    pub stamps_ns: Vec<i64>,
    /// Positions, rad or m.
    pub position: DMatrix<f64>,
    /// Velocities; `None` when the messages' velocity arrays are empty.
    pub velocity: Option<DMatrix<f64>>,
    /// Efforts; `None` when the messages' effort arrays are empty.
    pub effort: Option<DMatrix<f64>>,
}

/// What the timing checks found on the clock topic (before any resampling).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimingReport {
    /// Number of samples checked.
    pub samples: usize,
    /// Median time step, s.
    pub median_step_s: f64,
    /// Steps longer than [`GAP_FACTOR`] median steps.
    pub gaps: usize,
    /// Other steps off the median by more than [`JITTER_TOLERANCE`] (relative).
    pub jittered: usize,
    /// Longest step, s.
    pub largest_step_s: f64,
    /// Index of the second sample of the first gap or jittered step.
    pub first_irregular: Option<usize>,
    /// The rate the log was resampled to, Hz, if it was.
    pub resampled_hz: Option<f64>,
}

/// Order, count and step statistics of a stamp sequence, fed one stamp at a time.
#[derive(Clone, Debug, Default)]
pub(super) struct StampStats {
    pub count: usize,
    pub first: i64,
    pub last: i64,
    /// The first stamp that does not increase: its index, the previous and its stamp.
    pub first_bad: Option<(usize, i64, i64)>,
    pub backwards: usize,
    pub duplicates: usize,
    median: ExactMedian,
    /// Twice the median step, ns (half-nanoseconds stay integers), once known.
    pub median2: Option<i128>,
    /// Shortest and longest steps, ns.
    pub steps: Option<(i128, i128)>,
}

impl StampStats {
    fn observe(&mut self, stamp: i64) {
        if self.count == 0 {
            self.first = stamp;
        } else {
            if stamp <= self.last {
                if stamp == self.last {
                    self.duplicates += 1;
                } else {
                    self.backwards += 1;
                }
                self.first_bad.get_or_insert((self.count, self.last, stamp));
            } else {
                self.median
                    .observe((i128::from(stamp) - i128::from(self.last)) as u64);
            }
        }
        self.last = stamp;
        self.count += 1;
    }

    /// Ends a pass; `true` once the median is known.
    fn end_pass(&mut self) -> bool {
        if self.steps.is_none() {
            self.steps = self
                .median
                .range()
                .map(|(lo, hi)| (i128::from(lo), i128::from(hi)));
        }
        match self.median.end_pass() {
            MedianPass::Again => false,
            MedianPass::Done(m) => {
                self.median2 = m.map(|(a, b)| {
                    if self.median.count() % 2 == 1 {
                        2 * i128::from(a)
                    } else {
                        i128::from(a) + i128::from(b)
                    }
                });
                true
            }
        }
    }

    /// Another pass over the steps, for the median (stamps already checked).
    fn observe_step(&mut self, previous: i64, stamp: i64) {
        self.median
            .observe((i128::from(stamp) - i128::from(previous)) as u64);
    }

    /// Whether a step is a gap (longer than [`GAP_FACTOR`] median steps).
    fn has_gap(&self) -> bool {
        match (self.median2, self.steps) {
            (Some(m2), Some((_, hi))) => is_gap(hi, m2),
            _ => false,
        }
    }

    /// Whether a step is a gap or jittered.
    fn is_irregular(&self) -> bool {
        match (self.median2, self.steps) {
            (Some(m2), Some((lo, hi))) => {
                [lo, hi].iter().any(|&s| is_gap(s, m2) || is_jitter(s, m2))
            }
            _ => false,
        }
    }
}

fn is_gap(step: i128, median2: i128) -> bool {
    (2 * step) as f64 > GAP_FACTOR * median2 as f64
}

fn is_jitter(step: i128, median2: i128) -> bool {
    ((2 * step - median2).abs() as f64) > JITTER_TOLERANCE * median2 as f64
}

pub(super) fn seconds_between(a: i64, b: i64) -> f64 {
    (i128::from(b) - i128::from(a)) as f64 / 1e9
}

/// Rows of a topic kept by [`read_joint_states`](super::read_joint_states).
#[derive(Debug, Default)]
struct SeriesRows {
    stamps: Vec<i64>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

/// A topic during the first pass.
#[derive(Debug)]
pub(super) struct TopicSurvey {
    pub state: TopicState,
    /// Automatic mode: the first problem, reported only if the topic is chosen.
    error: Option<LogError>,
    pub stats: StampStats,
    rows: Option<SeriesRows>,
}

impl TopicSurvey {
    fn new(topic: &str, keep_rows: bool) -> TopicSurvey {
        TopicSurvey {
            state: TopicState::new(topic),
            error: None,
            stats: StampStats::default(),
            rows: keep_rows.then(SeriesRows::default),
        }
    }

    /// The kept rows as a series.
    pub(super) fn into_series(self) -> JointStateSeries {
        let rows = self.rows.unwrap_or_default();
        let (n, dof) = (rows.stamps.len(), self.state.names.len());
        let matrix = |v: Vec<f64>| DMatrix::from_row_slice(n, dof, &v);
        JointStateSeries {
            topic: self.state.topic,
            joint_names: self.state.names,
            frame_id: self.state.frame_id,
            stamps_ns: rows.stamps,
            position: matrix(rows.position),
            velocity: self.state.has_velocity.then(|| matrix(rows.velocity)),
            effort: self.state.has_effort.then(|| matrix(rows.effort)),
        }
    }
}

/// The first pass: decodes and checks the JointStates of the requested topics (or of
/// every candidate topic in automatic mode), then picks the topics (see the module
/// docs of [`super`]). With `keep_rows` the chosen topics' rows are kept.
pub(super) fn survey(
    bag: &Arc<Bag>,
    topics: &[String],
    joints: &[String],
    time_source: TimeSource,
    keep_rows: bool,
) -> Result<Vec<TopicSurvey>, LogError> {
    let path = bag.path.as_path();
    let auto = topics.is_empty();
    let mut surveys: BTreeMap<String, TopicSurvey> = BTreeMap::new();
    if !auto {
        for (k, t) in topics.iter().enumerate() {
            if topics[..k].contains(t) {
                return Err(mcap_error(path, Some(t), McapProblem::RepeatedTopic));
            }
            surveys.insert(t.clone(), TopicSurvey::new(t, keep_rows));
        }
    }
    let mut row = JointRow::default();
    let on_message = |m: MessageRef<'_>| -> Result<(), LogError> {
        let topic = m.channel.topic.as_str();
        if !is_joint_state(m.channel) {
            if !auto && surveys.contains_key(topic) {
                return Err(mcap_error(
                    path,
                    Some(topic),
                    McapProblem::WrongType {
                        schema_name: m.channel.schema_name.clone(),
                        message_encoding: m.channel.message_encoding.clone(),
                    },
                ));
            }
            return Ok(());
        }
        let s = match surveys.get_mut(topic) {
            Some(s) => s,
            None if auto => surveys
                .entry(topic.to_owned())
                .or_insert_with(|| TopicSurvey::new(topic, keep_rows)),
            None => return Ok(()),
        };
        if s.state.rejected.is_some() || s.error.is_some() {
            return Ok(());
        }
        let checked = decode(&m, s.state.count, time_source)
            .and_then(|(msg, stamp)| s.state.check(msg, stamp, auto, &mut row));
        match checked {
            Ok(false) => Ok(()),
            Ok(true) => {
                s.stats.observe(row.stamp);
                if let Some(r) = &mut s.rows {
                    r.stamps.push(row.stamp);
                    r.position.extend_from_slice(&row.position);
                    r.velocity.extend_from_slice(&row.velocity);
                    r.effort.extend_from_slice(&row.effort);
                }
                Ok(())
            }
            Err(problem) => {
                let e = LogError::Mcap {
                    path: path.to_path_buf(),
                    topic: Some(topic.to_owned()),
                    problem,
                };
                if auto {
                    s.error = Some(e);
                    Ok(())
                } else {
                    Err(e)
                }
            }
        }
    };
    let scanned = scan(bag, on_message)?;
    choose(path, topics, joints, surveys, scanned.topics)
}

/// The surveyed topics to read: the requested ones, or the automatic choice among the
/// candidates (`topics` empty); each must have held messages without error.
fn choose(
    path: &Path,
    topics: &[String],
    joints: &[String],
    mut surveys: BTreeMap<String, TopicSurvey>,
    available: Vec<TopicInfo>,
) -> Result<Vec<TopicSurvey>, LogError> {
    let auto = topics.is_empty();
    let chosen: Vec<TopicSurvey> = if auto {
        let candidates: Vec<&TopicSurvey> = surveys
            .values()
            .filter(|s| s.state.rejected.is_none())
            .collect();
        if candidates.is_empty() {
            let rejected = surveys
                .values()
                .filter_map(|s| {
                    s.state
                        .rejected
                        .map(|why| format!("{}: {why}", s.state.topic))
                })
                .collect();
            return Err(mcap_error(
                path,
                None,
                McapProblem::NoJointStates {
                    available,
                    rejected,
                },
            ));
        }
        let picked = auto_pick(&candidates, joints)
            .map_err(|candidates| mcap_error(path, None, McapProblem::Ambiguous { candidates }))?;
        picked
            .iter()
            .map(|t| surveys.remove(t).expect("picked from the surveys"))
            .collect()
    } else {
        topics
            .iter()
            .map(|t| surveys.remove(t).expect("one survey per topic"))
            .collect()
    };
    let mut out = Vec::with_capacity(chosen.len());
    for mut s in chosen {
        if let Some(e) = s.error.take() {
            return Err(e);
        }
        if s.state.count == 0 {
            let problem = if available.iter().any(|i| i.topic == s.state.topic) {
                McapProblem::EmptyTopic
            } else {
                McapProblem::TopicNotFound {
                    available: available.clone(),
                }
            };
            return Err(mcap_error(path, Some(&s.state.topic), problem));
        }
        out.push(s);
    }
    Ok(out)
}

/// The automatic topic choice among the candidates (JointState topics with positions
/// and efforts), the clock first; `Err` lists the candidates when there is no single
/// answer.
///
/// Knowing the joints the caller needs (`joints`, e.g. a robot's measured joints): the
/// one candidate that holds them all (one ending in `measured_js` if several do); else
/// the dVRK 2.x convention, `X/measured_js` with `X/jaw/measured_js`, if exactly one such
/// pair holds them together. Otherwise (or without `joints`): the only candidate, or
/// the only one ending in `measured_js`.
fn auto_pick(candidates: &[&TopicSurvey], joints: &[String]) -> Result<Vec<String>, Vec<String>> {
    let measured = |list: &[&TopicSurvey]| -> Option<String> {
        let m: Vec<&&TopicSurvey> = list
            .iter()
            .filter(|s| s.state.topic.ends_with("measured_js"))
            .collect();
        (m.len() == 1).then(|| m[0].state.topic.clone())
    };
    if !joints.is_empty() {
        let holds =
            |names: &[&[String]]| joints.iter().all(|j| names.iter().any(|n| n.contains(j)));
        let full: Vec<&TopicSurvey> = candidates
            .iter()
            .copied()
            .filter(|s| holds(&[&s.state.names]))
            .collect();
        match full.len() {
            1 => return Ok(vec![full[0].state.topic.clone()]),
            0 => {}
            _ => {
                return measured(&full)
                    .map(|t| vec![t])
                    .ok_or_else(|| full.iter().map(|s| s.state.topic.clone()).collect())
            }
        }
        let mut pairs = Vec::new();
        for arm in candidates {
            let Some(prefix) = arm.state.topic.strip_suffix("measured_js") else {
                continue;
            };
            let jaw_topic = format!("{prefix}jaw/measured_js");
            if let Some(jaw) = candidates.iter().find(|s| s.state.topic == jaw_topic) {
                if holds(&[&arm.state.names, &jaw.state.names]) {
                    pairs.push(vec![arm.state.topic.clone(), jaw_topic]);
                }
            }
        }
        match pairs.len() {
            1 => return Ok(pairs.remove(0)),
            0 => {}
            _ => return Err(pairs.iter().map(|p| p.join(" + ")).collect()),
        }
    }
    if candidates.len() == 1 {
        return Ok(vec![candidates[0].state.topic.clone()]);
    }
    measured(candidates)
        .map(|t| vec![t])
        .ok_or_else(|| candidates.iter().map(|s| s.state.topic.clone()).collect())
}

/// Calls `f(topic, stamp)` for every message of the chosen topics, in file order (a
/// pass that only needs the stamps; the messages were checked by the first pass).
fn stamp_pass(
    bag: &Arc<Bag>,
    topics: &[String],
    time_source: TimeSource,
    mut f: impl FnMut(usize, i64),
) -> Result<(), LogError> {
    let path = bag.path.as_path();
    let mut counts = vec![0usize; topics.len()];
    let mut scanner = Scanner::open(bag)?;
    loop {
        let step = scanner.next_message(|m| {
            let Some(k) = topics.iter().position(|t| *t == m.channel.topic) else {
                return Ok(());
            };
            if !is_joint_state(m.channel) {
                return Ok(());
            }
            let (_, stamp) =
                decode(&m, counts[k], time_source).map_err(|problem| LogError::Mcap {
                    path: path.to_path_buf(),
                    topic: Some(topics[k].clone()),
                    problem,
                })?;
            counts[k] += 1;
            f(k, stamp);
            Ok(())
        })?;
        if step.is_none() {
            return Ok(());
        }
    }
}

/// Passes over topic `k`'s stamps within `lo..=hi` until the median of `stats` is
/// known (`stats` has seen the first pass).
fn finish_median(
    bag: &Arc<Bag>,
    topics: &[String],
    time_source: TimeSource,
    k: usize,
    (lo, hi): (i64, i64),
    stats: &mut StampStats,
) -> Result<(), LogError> {
    while !stats.end_pass() {
        let mut previous: Option<i64> = None;
        stamp_pass(bag, topics, time_source, |t, stamp| {
            if t == k && (lo..=hi).contains(&stamp) {
                if let Some(p) = previous {
                    stats.observe_step(p, stamp);
                }
                previous = Some(stamp);
            }
        })?;
    }
    Ok(())
}

/// Where the first irregular step of a stamp sequence is, ns.
#[derive(Clone, Copy, Debug, Default)]
struct Irregular {
    /// The sequence's first stamp.
    first: i64,
    /// The stamps before and after the step.
    previous: i64,
    stamp: i64,
}

/// The timing report of topic `k`'s stamps within `lo..=hi` (strictly increasing,
/// median known), and where its first irregular step is.
fn classify(
    bag: &Arc<Bag>,
    topics: &[String],
    time_source: TimeSource,
    k: usize,
    (lo, hi): (i64, i64),
    stats: &StampStats,
) -> Result<(TimingReport, Option<Irregular>), LogError> {
    let median2 = stats.median2.unwrap_or(0);
    let mut report = TimingReport {
        samples: stats.count,
        median_step_s: median2 as f64 / 2e9,
        gaps: 0,
        jittered: 0,
        largest_step_s: stats.steps.map_or(0.0, |(_, hi)| hi as f64 / 1e9),
        first_irregular: None,
        resampled_hz: None,
    };
    let mut around = None;
    if !stats.is_irregular() {
        return Ok((report, around));
    }
    let (mut index, mut previous) = (0usize, None::<i64>);
    let mut first = None;
    stamp_pass(bag, topics, time_source, |t, stamp| {
        if t != k || !(lo..=hi).contains(&stamp) {
            return;
        }
        first.get_or_insert(stamp);
        if let Some(p) = previous {
            let step = i128::from(stamp) - i128::from(p);
            let irregular = if is_gap(step, median2) {
                report.gaps += 1;
                true
            } else if is_jitter(step, median2) {
                report.jittered += 1;
                true
            } else {
                false
            };
            if irregular && report.first_irregular.is_none() {
                report.first_irregular = Some(index);
                around = Some(Irregular {
                    first: first.unwrap_or(stamp),
                    previous: p,
                    stamp,
                });
            }
        }
        previous = Some(stamp);
        index += 1;
    })?;
    Ok((report, around))
}

fn non_uniform(
    path: &Path,
    topic: &str,
    report: &TimingReport,
    around: Option<Irregular>,
    time_source: TimeSource,
) -> LogError {
    let Irregular {
        first,
        previous,
        stamp,
    } = around.unwrap_or_default();
    let suggested = if report.median_step_s > 0.0 {
        (1.0 / report.median_step_s).round().max(1.0)
    } else {
        1.0
    };
    mcap_error(
        path,
        Some(topic),
        McapProblem::NonUniform {
            index: report.first_irregular.unwrap_or(1),
            time_s: seconds_between(first, stamp),
            step_s: seconds_between(previous, stamp),
            median_step_s: report.median_step_s,
            gaps: report.gaps,
            jittered: report.jittered,
            largest_step_s: report.largest_step_s,
            samples: report.samples,
            time_source,
            suggested_hz: suggested,
        },
    )
}

/// What the block reader needs to know about a file before its first sample.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    /// The topics read, the clock first.
    pub topics: Vec<String>,
    /// Joint names per topic.
    pub joints: Vec<Vec<String>>,
    /// Every topic has velocities.
    pub with_velocity: bool,
    /// Clock samples are kept within `lo..=hi` (the span of the other topics).
    pub span: (i64, i64),
    /// The first kept clock stamp: `t = 0`.
    pub start_time_ns: i64,
    pub trimmed: (usize, usize),
    pub timing: TimingReport,
    pub time_source: TimeSource,
    pub resample_hz: Option<f64>,
    /// Samples the reader will give (after resampling).
    pub samples: usize,
}

/// The passes before the samples: topic choice and message checks, then the checks of
/// the merged clock (joint names unique across topics, stamps increasing, no gap in the
/// other topics, overlapping spans, a uniform clock unless resampling), in the order the
/// whole-log reader made them.
pub(super) fn plan(bag: &Arc<Bag>, options: &McapOptions) -> Result<Plan, LogError> {
    let path = bag.path.as_path();
    if let Some(rate) = options.resample_hz {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(LogError::InvalidRate {
                path: path.to_path_buf(),
                what: "the resampling rate",
                setting: crate::hint::Hint::Resample,
                rate_hz: rate,
            });
        }
    }
    let ts = options.time_source;
    let mut surveys = survey(bag, &options.topics, &options.joints, ts, false)?;
    check_topics(path, &surveys, ts)?;
    let topics: Vec<String> = surveys.iter().map(|s| s.state.topic.clone()).collect();
    // Gaps in the other topics would be bridged by interpolation: refuse them too.
    for k in 0..surveys.len() {
        let full = (surveys[k].stats.first, surveys[k].stats.last);
        finish_median(bag, &topics, ts, k, full, &mut surveys[k].stats)?;
        if k > 0 && options.resample_hz.is_none() && surveys[k].stats.has_gap() {
            let (report, around) = classify(bag, &topics, ts, k, full, &surveys[k].stats)?;
            return Err(non_uniform(path, &topics[k], &report, around, ts));
        }
    }
    let (mut lo, mut hi) = (i64::MIN, i64::MAX);
    for s in &surveys[1..] {
        lo = lo.max(s.stats.first);
        hi = hi.min(s.stats.last);
    }
    let clock = &surveys[0].stats;
    let span = (lo.max(clock.first), hi.min(clock.last));
    let (stats, trimmed) = if span == (clock.first, clock.last) {
        (clock.clone(), (0, 0))
    } else {
        clock_within(bag, &topics, ts, &surveys, (lo, hi))?
    };
    let (mut timing, around) = classify(bag, &topics, ts, 0, span, &stats)?;
    if options.resample_hz.is_none() && timing.first_irregular.is_some() {
        return Err(non_uniform(path, &topics[0], &timing, around, ts));
    }
    let samples = sample_count(path, &topics[0], options.resample_hz, &stats, &mut timing)?;
    Ok(Plan {
        with_velocity: surveys.iter().all(|s| s.state.has_velocity),
        joints: surveys.iter().map(|s| s.state.names.clone()).collect(),
        topics,
        span,
        start_time_ns: stats.first,
        trimmed,
        timing,
        time_source: ts,
        resample_hz: options.resample_hz,
        samples,
    })
}

/// The checks of the chosen topics before their clocks: efforts on every topic, joint
/// names unique across topics, stamps strictly increasing.
fn check_topics(path: &Path, surveys: &[TopicSurvey], ts: TimeSource) -> Result<(), LogError> {
    for s in surveys {
        if !s.state.has_effort {
            return Err(mcap_error(
                path,
                Some(&s.state.topic),
                McapProblem::NoEffort,
            ));
        }
    }
    // Joint names unique across topics.
    let mut owner: HashMap<&str, &str> = HashMap::new();
    for s in surveys {
        for n in &s.state.names {
            if let Some(first) = owner.insert(n.as_str(), s.state.topic.as_str()) {
                return Err(mcap_error(
                    path,
                    Some(&s.state.topic),
                    McapProblem::DuplicateJoint {
                        joint: n.clone(),
                        context: format!(
                            "also on topic {first}; merged topics need distinct joint names"
                        ),
                    },
                ));
            }
        }
    }
    for s in surveys {
        if let Some((index, previous, stamp)) = s.stats.first_bad {
            let st = &s.stats;
            return Err(mcap_error(
                path,
                Some(&s.state.topic),
                McapProblem::NotIncreasing {
                    index,
                    time_s: seconds_between(st.first, stamp),
                    previous_s: seconds_between(st.first, previous),
                    backwards: st.backwards,
                    duplicates: st.duplicates,
                    samples: st.count,
                    time_source: ts,
                },
            ));
        }
    }
    Ok(())
}

/// The clock's statistics over the span `lo..=hi` the other topics cover, and the clock
/// samples below and above it (a pass over the file).
fn clock_within(
    bag: &Arc<Bag>,
    topics: &[String],
    ts: TimeSource,
    surveys: &[TopicSurvey],
    (lo, hi): (i64, i64),
) -> Result<(StampStats, (usize, usize)), LogError> {
    let path = bag.path.as_path();
    let clock = &surveys[0].stats;
    // The clock's statistics over the span the other topics cover.
    let (mut below, mut above) = (0, 0);
    let mut stats = StampStats::default();
    stamp_pass(bag, topics, ts, |t, stamp| {
        if t != 0 {
        } else if stamp < lo {
            below += 1;
        } else if stamp > hi {
            above += 1;
        } else {
            stats.observe(stamp);
        }
    })?;
    if stats.count == 0 {
        let mut detail = String::new();
        let t0 = clock.first;
        for s in surveys {
            let _ = write!(
                detail,
                "{}{} from {} s to {} s",
                if detail.is_empty() { "" } else { ", " },
                s.state.topic,
                seconds_between(t0, s.stats.first),
                seconds_between(t0, s.stats.last)
            );
        }
        return Err(mcap_error(path, None, McapProblem::NoOverlap { detail }));
    }
    finish_median(bag, topics, ts, 0, (lo, hi), &mut stats)?;
    Ok((stats, (below, above)))
}

/// The number of samples the reader gives: the clock's, or the resampled grid's (then
/// recorded in `timing`).
fn sample_count(
    path: &Path,
    clock_topic: &str,
    resample_hz: Option<f64>,
    stats: &StampStats,
    timing: &mut TimingReport,
) -> Result<usize, LogError> {
    Ok(match resample_hz {
        Some(rate) => {
            let r = crate::resample::Resampler::new(1, rate).map_err(|e| {
                mcap_error(
                    path,
                    Some(clock_topic),
                    McapProblem::Resample {
                        reason: e.to_string(),
                    },
                )
            })?;
            timing.resampled_hz = Some(rate);
            if stats.count < 2 {
                0
            } else {
                r.grid_len(0.0, seconds_between(stats.first, stats.last))
            }
        }
        None => stats.count,
    })
}
