//! Logs of any format read block by block: what a fit of a log larger than memory reads,
//! and what [`super::ReadOptions::read`] collects.

use std::path::{Path, PathBuf};

use nalgebra::DMatrix;

use super::csv::{HeaderedBlocks, WpiBlocks};
#[cfg(feature = "recordings")]
use super::mcap::{McapBlocks, McapReader};
use super::{detect_format, LogError, LogFormat, ReadOptions};
use crate::joint_log::{Coordinates, JointLog};
use crate::resample::Resampler;

/// A log opened for reading in blocks, as many times as needed (each
/// [`LogReader::blocks`] is one pass over the file). Opening reads the header (CSV), the
/// first row (2019 layout) or makes every check of the MCAP reader
/// ([`McapReader::open`]).
#[derive(Debug)]
pub struct LogReader {
    path: PathBuf,
    format: LogFormat,
    /// The 2019 layout's sampling rate, Hz.
    rate_hz: Option<f64>,
    /// The 2019 layout's expected number of joints.
    dof: Option<usize>,
    /// Resampling of the CSV formats (MCAP logs resample while merging).
    resample_hz: Option<f64>,
    #[cfg(feature = "recordings")]
    mcap: Option<McapReader>,
    joint_names: Vec<String>,
    coordinates: Coordinates,
    has_velocity: bool,
}

impl LogReader {
    /// Opens `path` with `options` (the public entry point is [`ReadOptions::open`]).
    pub(super) fn open(path: &Path, options: &ReadOptions) -> Result<LogReader, LogError> {
        let format = match options.format {
            Some(f) => f,
            None => detect_format(path)?,
        };
        options.check_format(path, format)?;
        let rate_hz = options.rate_hz;
        let mut reader = LogReader {
            path: path.to_path_buf(),
            format,
            rate_hz,
            dof: options.dof,
            resample_hz: options.resample_hz,
            #[cfg(feature = "recordings")]
            mcap: None,
            joint_names: Vec::new(),
            coordinates: Coordinates::Measured,
            has_velocity: false,
        };
        match format {
            LogFormat::Wpi => {
                let rate = rate_hz.ok_or_else(|| LogError::MissingRate {
                    path: path.to_path_buf(),
                })?;
                let first = WpiBlocks::open(path, rate, options.dof)?
                    .next_block(1)?
                    .ok_or_else(|| LogError::Empty {
                        path: path.to_path_buf(),
                        what: "no rows",
                    })?;
                reader.set_header(&first);
            }
            LogFormat::Csv => {
                let b = HeaderedBlocks::open(path)?;
                reader.joint_names = b.joint_names().to_vec();
                reader.coordinates = b.coordinates();
                reader.has_velocity = b.has_velocity();
            }
            #[cfg(not(feature = "recordings"))]
            other => return Err(super::recordings_not_built(path, other)),
            #[cfg(feature = "recordings")]
            _ => {
                let m = McapReader::open(path, &options.recording())?;
                reader.format = m.format();
                reader.joint_names = m.joint_names();
                reader.has_velocity = m.has_velocity();
                reader.resample_hz = None;
                reader.mcap = Some(m);
            }
        }
        Ok(reader)
    }

    fn set_header(&mut self, block: &JointLog) {
        self.joint_names = block.joint_names.clone();
        self.coordinates = block.coordinates;
        self.has_velocity = block.dq.is_some();
    }

    /// The samples in blocks of about `block_samples` (exactly, unless resampled), in
    /// order: one pass over the file.
    pub fn blocks(&self, block_samples: usize) -> Result<LogBlocks<'_>, LogError> {
        let path = self.path.as_path();
        #[cfg(feature = "recordings")]
        let recording = match &self.mcap {
            Some(m) => Some(Source::Mcap(Box::new(m.blocks(block_samples)?))),
            None => None,
        };
        #[cfg(not(feature = "recordings"))]
        let recording = None;
        let source = match (recording, self.format) {
            (Some(s), _) => s,
            (None, LogFormat::Wpi) => Source::Wpi(WpiBlocks::open(
                path,
                self.rate_hz.unwrap_or(f64::NAN),
                self.dof,
            )?),
            (None, _) => Source::Csv(HeaderedBlocks::open(path)?),
        };
        let resampler = match self.resample_hz {
            Some(hz) => Some(BlockResampler::new(
                path,
                hz,
                self.joint_names.len(),
                self.has_velocity,
            )?),
            None => None,
        };
        Ok(LogBlocks {
            source,
            resampler,
            block: block_samples.max(1),
            last: None,
            done: false,
            rows: 0,
            last_time: None,
            path: self.path.clone(),
        })
    }

    /// Every sample in memory: the blocks of one pass, collected.
    pub fn read_all(&self) -> Result<JointLog, LogError> {
        let mut all = super::JointLogBuilder::default();
        for block in self.blocks(super::BLOCK_SAMPLES)? {
            all.push(&block?);
        }
        Ok(all.build())
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its format.
    pub fn format(&self) -> LogFormat {
        self.format
    }

    /// The joints of the samples.
    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }

    /// The joint space of the samples.
    pub fn coordinates(&self) -> Coordinates {
        self.coordinates
    }

    /// Whether the samples have measured velocities.
    pub fn has_velocity(&self) -> bool {
        self.has_velocity
    }

    /// The topics read (recordings; the clock first), empty for CSV logs.
    pub fn topics(&self) -> &[String] {
        #[cfg(feature = "recordings")]
        return self.mcap.as_ref().map_or(&[], |m| m.topics());
        #[cfg(not(feature = "recordings"))]
        &[]
    }

    /// Number of samples, when known without a pass over the file (MCAP).
    pub fn samples(&self) -> Option<usize> {
        #[cfg(feature = "recordings")]
        return self.mcap.as_ref().map(McapReader::samples);
        #[cfg(not(feature = "recordings"))]
        None
    }
}

impl ReadOptions {
    /// Opens `path` for reading block by block (every check of the header, the first
    /// row or the recording's index is made here).
    pub fn open(&self, path: impl AsRef<Path>) -> Result<LogReader, LogError> {
        LogReader::open(path.as_ref(), self)
    }

    /// Every sample of `path` in memory (one pass of [`ReadOptions::open`]'s blocks).
    pub fn read(&self, path: impl AsRef<Path>) -> Result<JointLog, LogError> {
        self.open(path)?.read_all()
    }
}

enum Source<'a> {
    Wpi(WpiBlocks),
    Csv(HeaderedBlocks),
    #[cfg(feature = "recordings")]
    Mcap(Box<McapBlocks<'a>>),
    /// Keeps the lifetime of the blocks of a recording in builds without them.
    #[cfg(not(feature = "recordings"))]
    #[allow(dead_code)]
    Never(std::marker::PhantomData<&'a ()>, std::convert::Infallible),
}

/// One pass over a log, block by block (see [`LogReader::blocks`]).
pub struct LogBlocks<'a> {
    source: Source<'a>,
    resampler: Option<BlockResampler>,
    block: usize,
    /// The last block read, for the resampler's last samples.
    last: Option<JointLog>,
    done: bool,
    path: PathBuf,
    /// Samples read and the last time, to validate the blocks as parts of one log.
    rows: usize,
    last_time: Option<f64>,
}

impl LogBlocks<'_> {
    fn next_block(&mut self) -> Result<Option<JointLog>, LogError> {
        loop {
            let raw = match &mut self.source {
                Source::Wpi(b) => b.next_block(self.block)?,
                Source::Csv(b) => b.next_block(self.block)?,
                #[cfg(feature = "recordings")]
                Source::Mcap(b) => b.next().transpose()?,
                #[cfg(not(feature = "recordings"))]
                Source::Never(_, never) => match *never {},
            };
            let Some(r) = &mut self.resampler else {
                // Every sample a reader gives is valid (in range, time increasing): the
                // resampler checks its input itself.
                if let Some(block) = &raw {
                    let path = self.path.clone();
                    block
                        .validate_rows(self.rows, self.last_time)
                        .map_err(|source| LogError::Samples { path, source })?;
                    self.rows += block.len();
                    self.last_time = block.time.last().copied().or(self.last_time);
                }
                return Ok(raw);
            };
            let out = match raw {
                Some(block) => {
                    let out = r.push(&block)?;
                    self.last = Some(block);
                    out
                }
                None => match self.last.take() {
                    Some(last) => r.finish(&last)?,
                    None => return Ok(None),
                },
            };
            if !out.is_empty() {
                return Ok(Some(out));
            }
        }
    }
}

impl Iterator for LogBlocks<'_> {
    type Item = Result<JointLog, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let r = self.next_block().transpose();
        self.done = !matches!(r, Some(Ok(_)));
        r
    }
}

/// The `--resample` of logs without their own resampling, block by block: each block
/// is validated (rows numbered from the log's start) and its samples interpolated onto
/// the uniform grid.
pub(crate) struct BlockResampler {
    path: PathBuf,
    rate_hz: f64,
    dof: usize,
    with_velocity: bool,
    resampler: Resampler,
    rows: usize,
    last_time: Option<f64>,
}

impl BlockResampler {
    pub(crate) fn new(
        path: &Path,
        rate_hz: f64,
        dof: usize,
        with_velocity: bool,
    ) -> Result<BlockResampler, LogError> {
        Ok(BlockResampler {
            resampler: Resampler::new(3 * dof, rate_hz).map_err(|source| LogError::Resample {
                path: path.to_path_buf(),
                rate_hz,
                source,
            })?,
            path: path.to_path_buf(),
            rate_hz,
            dof,
            with_velocity,
            rows: 0,
            last_time: None,
        })
    }

    fn error(&self, source: crate::resample::ResampleError) -> LogError {
        LogError::Resample {
            path: self.path.clone(),
            rate_hz: self.rate_hz,
            source,
        }
    }

    /// The grid samples that `block` completes (with the block's names and source).
    pub(crate) fn push(&mut self, block: &JointLog) -> Result<JointLog, LogError> {
        block
            .validate_rows(self.rows, self.last_time)
            .map_err(|source| LogError::Samples {
                path: self.path.clone(),
                source,
            })?;
        self.rows += block.len();
        self.last_time = block.time.last().copied().or(self.last_time);
        let n = self.dof;
        let (mut times, mut values) = (Vec::new(), Vec::new());
        let mut row = vec![0.0; 3 * n];
        for k in 0..block.len() {
            block.stacked_row(k, &mut row);
            self.resampler
                .push(block.time[k], &row, &mut times, &mut values)
                .map_err(|e| self.error(e))?;
        }
        Ok(self.assemble(block, times, values))
    }

    /// The last grid samples (named like `last`, the log's last block).
    pub(crate) fn finish(&mut self, last: &JointLog) -> Result<JointLog, LogError> {
        let (mut times, mut values) = (Vec::new(), Vec::new());
        self.resampler
            .finish(&mut times, &mut values)
            .map_err(|e| self.error(e))?;
        Ok(self.assemble(last, times, values))
    }

    fn assemble(&self, like: &JointLog, time: Vec<f64>, values: Vec<f64>) -> JointLog {
        let (rows, n) = (time.len(), self.dof);
        let all = DMatrix::from_row_slice(rows, 3 * n, &values);
        JointLog {
            time,
            q: all.columns(0, n).into_owned(),
            dq: self.with_velocity.then(|| all.columns(n, n).into_owned()),
            tau: all.columns(2 * n, n).into_owned(),
            joint_names: like.joint_names.clone(),
            coordinates: like.coordinates,
            source: like.source.clone(),
        }
    }
}
