//! Recordings: input streams saved as JSON Lines, for replay and regression tests.
//!
//! The first line is a [`RecordingHeader`] (format name and version, scene, description); every
//! further line is a [`RecordedSample`]: the time in seconds since the first sample and a
//! tracker, glove or hand-joints sample, e.g.
//!
//! ```text
//! {"format":"vas-recording","version":2,"scene":"demo","description":"reach and grasp"}
//! {"time":0.0,"tracker":{"seq":1,"timestamp_ns":...,"hand":{...},"cart":{...},"sensor_id":0}}
//! {"time":0.011,"glove":{"seq":1,"timestamp_ns":...,"flex":[0.0, ...]}}
//! {"time":0.02,"hand_joints":{"seq":1,"timestamp_ns":...,"joints":[{"position":[...],
//!     "rotation":[...],"radius":0.01,"flags":15}, ...],"side":0}}
//! ```
//!
//! Version 2 added the hand-joints lines; version 1 recordings (tracker and glove only) are read
//! as they are. JSON has no NaN or infinity, so samples with non-finite values cannot be
//! recorded.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vas_protocol::{GloveSample, HandFrame, HandJointsSample, InputStamp, TrackerSample};

/// The `format` value of every recording header.
pub const FORMAT: &str = "vas-recording";
/// The format version this library writes; it reads this one and every earlier one.
pub const VERSION: u32 = 2;

/// First line of a recording.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingHeader {
    /// Always [`FORMAT`].
    pub format: String,
    /// The format version, [`VERSION`] for recordings this library writes.
    pub version: u32,
    /// Name of the scene the input was recorded against.
    pub scene: String,
    /// Free text: what the recording shows.
    pub description: String,
}

impl RecordingHeader {
    /// A header of the current format and version.
    pub fn new(scene: impl Into<String>, description: impl Into<String>) -> Self {
        Self {
            format: FORMAT.to_owned(),
            version: VERSION,
            scene: scene.into(),
            description: description.into(),
        }
    }
}

/// One input sample of any stream.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[expect(
    clippy::large_enum_variant,
    reason = "samples are copied to and from the wire as they are; boxing would allocate per sample"
)]
pub enum InputSample {
    /// A tracker sample.
    Tracker(TrackerSample),
    /// A glove sample.
    Glove(GloveSample),
    /// A hand-joints sample.
    HandJoints(HandJointsSample),
}

impl InputSample {
    /// The sample's sequence number (in its own stream).
    pub fn seq(&self) -> u64 {
        self.stamp().seq
    }

    /// The sample's timestamp in nanoseconds since the Unix epoch.
    pub fn timestamp_ns(&self) -> u64 {
        self.stamp().timestamp_ns
    }

    /// The stamp an output frame carries when it answers this sample.
    pub fn stamp(&self) -> InputStamp {
        match self {
            Self::Tracker(sample) => sample.stamp(),
            Self::Glove(sample) => sample.stamp(),
            Self::HandJoints(sample) => sample.stamp(),
        }
    }

    /// Whether `frame` answers this sample: it is the frame of the sample's hand (its user and
    /// side) and carries the sample's stamp for its stream.
    pub fn is_answered_by(&self, frame: &HandFrame) -> bool {
        let (stamp, user, side) = match self {
            Self::Tracker(sample) => (frame.tracker, sample.user, sample.side),
            Self::Glove(sample) => (frame.glove, sample.user, sample.side),
            Self::HandJoints(sample) => (frame.joints, sample.user, sample.side),
        };
        stamp == self.stamp() && frame.user == user && frame.hand == side
    }

    /// The same sample for the hand of user `user` (an index into the scene's users).
    pub fn with_user(mut self, user: u32) -> Self {
        match &mut self {
            Self::Tracker(sample) => sample.user = user,
            Self::Glove(sample) => sample.user = user,
            Self::HandJoints(sample) => sample.user = user,
        }
        self
    }

    /// The same sample with another timestamp (a replay stamps samples when it sends them).
    pub fn with_timestamp(mut self, timestamp_ns: u64) -> Self {
        match &mut self {
            Self::Tracker(sample) => sample.timestamp_ns = timestamp_ns,
            Self::Glove(sample) => sample.timestamp_ns = timestamp_ns,
            Self::HandJoints(sample) => sample.timestamp_ns = timestamp_ns,
        }
        self
    }

    /// Whether every value is finite (only such samples can be written as JSON).
    pub fn is_finite(&self) -> bool {
        match self {
            Self::Tracker(sample) => sample.hand.is_finite() && sample.cart.is_finite(),
            Self::Glove(sample) => sample.flex.iter().all(|v| v.is_finite()),
            Self::HandJoints(sample) => sample.is_finite(),
        }
    }
}

/// One sample line of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RecordedSample {
    /// Seconds since the first sample of the recording; never decreasing.
    pub time: f64,
    /// The sample.
    #[serde(flatten)]
    pub input: InputSample,
}

impl RecordedSample {
    /// The sample as a replay that started at `start_ns` (ns since the Unix epoch) sends it:
    /// stamped `start_ns` plus its time in the recording, so that the samples keep their
    /// recorded spacing (a server counts sample times, for instance for a hand's tracking
    /// grace).
    pub fn stamped(&self, start_ns: u64) -> InputSample {
        let offset_ns = (self.time * 1e9).round() as u64;
        self.input
            .with_timestamp(start_ns.saturating_add(offset_ns))
    }
}

/// A recording that cannot be read or written.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file cannot be opened, read or written.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system reported: in the message, not as the error's source, so that a
        /// message with its chain of causes says it once.
        error: std::io::Error,
    },
    /// A line is not a header or sample of this format.
    #[error("{}:{line}: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A sample with NaN or infinite values cannot be written as JSON.
    #[error("{}: cannot record a sample with non-finite values (seq {seq})", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The sample's sequence number.
        seq: u64,
    },
}

/// A whole recording in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The header line.
    pub header: RecordingHeader,
    /// The samples, in file order.
    pub samples: Vec<RecordedSample>,
}

impl Recording {
    /// The time from the first sample to the last, in nanoseconds (0 without samples).
    pub fn duration_ns(&self) -> u64 {
        self.samples
            .last()
            .map_or(0, |last| (last.time * 1e9).round() as u64)
    }

    /// Reads and checks a recording file: header format and version, one valid sample (every
    /// value finite) per line, times finite and non-decreasing. Blank lines are skipped.
    pub fn load(path: &Path) -> Result<Self, RecordingError> {
        let file = File::open(path).map_err(|error| RecordingError::Io {
            path: path.to_owned(),
            error,
        })?;
        Self::from_reader(path, BufReader::new(file))
    }

    /// [`Recording::load`] on a recording read from `reader`; `path` names it in errors.
    pub fn from_reader(path: &Path, reader: impl BufRead) -> Result<Self, RecordingError> {
        let io_error = |error| RecordingError::Io {
            path: path.to_owned(),
            error,
        };
        let invalid = |line: usize, reason: String| RecordingError::Invalid {
            path: path.to_owned(),
            line,
            reason,
        };
        let mut header = None;
        let mut samples: Vec<RecordedSample> = Vec::new();
        for (index, text) in reader.lines().enumerate() {
            let line = index + 1;
            let text = text.map_err(io_error)?;
            if text.trim().is_empty() {
                continue;
            }
            if header.is_none() {
                let parsed: RecordingHeader = serde_json::from_str(&text)
                    .map_err(|error| invalid(line, format!("not a recording header: {error}")))?;
                if parsed.format != FORMAT || !(1..=VERSION).contains(&parsed.version) {
                    return Err(invalid(
                        line,
                        format!(
                            "format {:?} version {} is not {FORMAT:?} version 1 to {VERSION}",
                            parsed.format, parsed.version
                        ),
                    ));
                }
                header = Some(parsed);
                continue;
            }
            let sample: RecordedSample = serde_json::from_str(&text)
                .map_err(|error| invalid(line, format!("not a recorded sample: {error}")))?;
            if matches!(sample.input, InputSample::HandJoints(_))
                && header
                    .as_ref()
                    .is_some_and(|h: &RecordingHeader| h.version < 2)
            {
                return Err(invalid(
                    line,
                    "a hand-joints sample in a version 1 recording (they came with version 2)"
                        .to_owned(),
                ));
            }
            // JSON has no infinity, but a number beyond `f32`'s range reads as one.
            if !sample.input.is_finite() {
                return Err(invalid(
                    line,
                    "a value is beyond the range of its type".to_owned(),
                ));
            }
            let previous = samples.last().map_or(0.0, |sample| sample.time);
            if !sample.time.is_finite() || sample.time < previous {
                return Err(invalid(
                    line,
                    format!(
                        "time {} is not finite or goes back from {previous}",
                        sample.time
                    ),
                ));
            }
            samples.push(sample);
        }
        let header = header.ok_or_else(|| invalid(1, "the file is empty".to_owned()))?;
        Ok(Self { header, samples })
    }
}

/// Writes a recording line by line, flushing each line, so that an interrupted recording is
/// still valid up to its last sample.
pub struct RecordingWriter {
    path: PathBuf,
    out: BufWriter<File>,
    first_timestamp_ns: Option<u64>,
    last_time: f64,
}

impl RecordingWriter {
    /// Creates (or truncates) the file and writes the header.
    pub fn create(path: &Path, header: &RecordingHeader) -> Result<Self, RecordingError> {
        let file = File::create(path).map_err(|error| RecordingError::Io {
            path: path.to_owned(),
            error,
        })?;
        let mut writer = Self {
            path: path.to_owned(),
            out: BufWriter::new(file),
            first_timestamp_ns: None,
            last_time: 0.0,
        };
        writer.write_line(header)?;
        Ok(writer)
    }

    /// Appends a sample; its time is taken from its timestamp relative to the first sample
    /// (held back to the previous time if the sender's clock stepped back).
    pub fn write(&mut self, input: &InputSample) -> Result<(), RecordingError> {
        if !input.is_finite() {
            return Err(RecordingError::NonFinite {
                path: self.path.clone(),
                seq: input.seq(),
            });
        }
        let first = *self.first_timestamp_ns.get_or_insert(input.timestamp_ns());
        let since_first = input.timestamp_ns().saturating_sub(first) as f64 * 1e-9;
        self.last_time = since_first.max(self.last_time);
        self.write_line(&RecordedSample {
            time: self.last_time,
            input: *input,
        })
    }

    fn write_line(&mut self, value: &impl Serialize) -> Result<(), RecordingError> {
        let io_error = |error| RecordingError::Io {
            path: self.path.clone(),
            error,
        };
        serde_json::to_writer(&mut self.out, value).map_err(|error| io_error(error.into()))?;
        self.out.write_all(b"\n").map_err(io_error)?;
        self.out.flush().map_err(io_error)
    }
}
