//! The settings an error message suggests ("give the sampling rate with --rate HZ"), as
//! typed values, so that each front end spells them its own way in one function: the
//! command line as its flags (`--rate HZ`), Python as its keywords (`rate=HZ`).
//!
//! A message writes a hint as the [`Hint`] in its format string
//! (`#[error("... with {}", Hint::RateHz)]`), and `Display` writes the hint with the
//! spelling in force: the command line's ([`Hint::flag`]) unless a front end renders
//! the message with its own through [`spelled`]. The spelling is a context of the
//! rendering rather than a parameter of every `Display`, so that each message stays
//! written once, in its error's `#[error]`, and a nested error (a log's error inside
//! the fit's) is spelled whole. A new hint is one variant here, its flag in
//! [`Hint::flag`] and its keyword in Python's spelling (crates/dvrk-py, `errors.rs`):
//! both are exhaustive `match`es, so a hint that a front end does not spell does not
//! compile.
//!
//! A message that keeps its text as a `String` has spelled its hints when it was made:
//! an error that suggests a setting keeps the hint as a value (a variant whose
//! `#[error]` names it, or the nested error itself) until it is shown.
//!
//! ```rust
//! use dvrk_logs::hint::{spelled, Hint};
//!
//! fn keyword(hint: Hint) -> String {
//!     match hint {
//!         Hint::RateHz => "rate=HZ".into(),
//!         other => other.flag(),
//!     }
//! }
//! let message = format!("give the sampling rate with {}", Hint::RateHz);
//! assert_eq!(message, "give the sampling rate with --rate HZ");
//! let error = dvrk_logs::log::LogError::MissingRate { path: "a.csv".into() };
//! assert!(error.to_string().contains("with --rate HZ"));
//! assert!(spelled(&error, keyword).contains("with rate=HZ"));
//! ```

use std::cell::Cell;
use std::fmt;

/// A setting a message suggests, with what it suggests giving it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hint {
    /// The 2019 layout's sampling rate, named: `--rate`.
    Rate,
    /// The sampling rate, to give in Hz: `--rate HZ`.
    RateHz,
    /// The rate the log is resampled to, named: `--resample`.
    Resample,
    /// The resampling rate, to give in Hz: `--resample HZ`.
    ResampleHz,
    /// A resampling rate to try, Hz: `--resample 200`.
    ResampleAt(f64),
    /// The topic to read, or the topics whose joints to merge: `--topic (repeat --topic
    /// to merge ...)`.
    Topics,
    /// Reading a recording's times from the log rather than the header stamps:
    /// `--time log`.
    LogTimes,
    /// The motion's low-pass cut-off, named: `--cutoff`.
    Cutoff,
    /// The samples dropped at each end of a processed log, named: `--trim`.
    Trim,
    /// The test logs' window, named: `--test-window`.
    TestWindow,
    /// The bound on what a compressed recording may decompress to, named:
    /// `--max-unpacked-mib`.
    MaxUnpackedMib,
    /// The excitation trajectory the logs were recorded on, named: `--excitation`.
    Excitation,
    /// The semidefinite fit, physically consistent: `--method sdp`.
    MethodSdp,
    /// The dVRK's MTM gravity-compensation export: `export --dvrk-gc`.
    DvrkGc,
    /// The exports for other controllers: `export --urdf or --wpi-json`.
    OtherExports,
}

/// How a front end writes a hint.
pub type Spelling = fn(Hint) -> String;

impl Hint {
    /// The command line's spelling, its flags: the default, so that a message shown
    /// as Rust's `Display` reads as the command line's.
    pub fn flag(self) -> String {
        match self {
            Hint::Rate => "--rate".into(),
            Hint::RateHz => "--rate HZ".into(),
            Hint::Resample => "--resample".into(),
            Hint::ResampleHz => "--resample HZ".into(),
            Hint::ResampleAt(hz) => format!("--resample {hz}"),
            Hint::Topics => "--topic (repeat --topic to merge the joints of several topics, \
                             e.g. an arm and its jaw)"
                .into(),
            Hint::LogTimes => "--time log".into(),
            Hint::Cutoff => "--cutoff".into(),
            Hint::Trim => "--trim".into(),
            Hint::TestWindow => "--test-window".into(),
            Hint::MaxUnpackedMib => "--max-unpacked-mib".into(),
            Hint::Excitation => "--excitation".into(),
            Hint::MethodSdp => "--method sdp".into(),
            Hint::DvrkGc => "export --dvrk-gc (Python FitResult.dvrk_gc())".into(),
            Hint::OtherExports => "export --urdf or --wpi-json".into(),
        }
    }
}

thread_local! {
    /// The spelling of the message being shown on this thread ([`spelled`]).
    static SPELLING: Cell<Spelling> = const { Cell::new(Hint::flag as Spelling) };
}

impl fmt::Display for Hint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&SPELLING.with(Cell::get)(*self))
    }
}

/// `message` (an error, with every error nested in it) as text, its hints written by
/// `spelling`.
pub fn spelled(message: &dyn fmt::Display, spelling: Spelling) -> String {
    /// Puts the previous spelling back, also when `Display` panics.
    struct Restore(Spelling);
    impl Drop for Restore {
        fn drop(&mut self) {
            SPELLING.with(|s| s.set(self.0));
        }
    }
    let _restore = Restore(SPELLING.with(|s| s.replace(spelling)));
    message.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn upper(hint: Hint) -> String {
        hint.flag().to_uppercase()
    }

    #[test]
    fn a_spelling_holds_for_one_message_and_nests() {
        struct Outer;
        impl fmt::Display for Outer {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                // A message that renders another with its own spelling inside.
                let inner = spelled(&Hint::Trim, Hint::flag);
                write!(
                    f,
                    "{} then {inner} then {}",
                    Hint::Cutoff,
                    Hint::ResampleAt(150.0)
                )
            }
        }
        assert_eq!(
            spelled(&Outer, upper),
            "--CUTOFF then --trim then --RESAMPLE 150"
        );
        // Back to the command line's afterwards.
        assert_eq!(Hint::Cutoff.to_string(), "--cutoff");
    }
}
