//! A friction selection's record in the result document (`selection`): how the samples
//! were split and each candidate's held-out errors ([`crate::fit::select`] runs it).

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

/// How the samples were split.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Folds {
    /// Each training log held out in turn.
    LeaveOneLogOut {
        /// Logs (folds).
        logs: usize,
    },
    /// One log cut into contiguous blocks in time, each held out in turn.
    Blocked {
        /// Blocks (folds).
        folds: usize,
        /// Training samples dropped on each side of a held-out block, s (the filter's
        /// decay, plus the largest delay and the difference stencils).
        guard_s: f64,
    },
}

impl Folds {
    /// In words: `leave one log out, 2 folds`, `4 blocks in time, guard band 0.260 s`.
    pub fn describe(&self) -> String {
        match self {
            Folds::LeaveOneLogOut { logs } => format!("leave one log out, {logs} folds"),
            Folds::Blocked { folds, guard_s } => {
                format!("{folds} blocks in time, guard band {guard_s:.3} s")
            }
        }
    }
}

/// One candidate's held-out errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// The candidate ([`crate::Candidate::name`]).
    pub candidate: String,
    /// Per joint `‖τ − τ̂‖ / ‖τ‖` over every held-out sample of every fold.
    pub relative_error: Vec<f64>,
    /// Their mean over the joints: the score.
    pub mean: f64,
}

/// A selection's record in the result document (`selection`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// How the samples were split.
    pub folds: Folds,
    /// The joints of the errors (the fit's `joints`).
    pub joints: Vec<String>,
    /// Each candidate's held-out errors, in the order given.
    pub candidates: Vec<CandidateScore>,
    /// The candidate chosen: the lowest mean held-out error.
    pub chosen: String,
}

impl Selection {
    /// The table as the command line prints it: one row per candidate, the mean and
    /// each joint's held-out relative error, the chosen one marked.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "held-out relative error by candidate ({}):",
            self.folds.describe()
        );
        let width = self
            .candidates
            .iter()
            .map(|c| c.candidate.len())
            .max()
            .unwrap_or(0)
            .max(9);
        let _ = write!(out, "  {:<width$} {:>7}", "candidate", "mean");
        for j in &self.joints {
            let _ = write!(out, " {:>7}", truncate(j, 7));
        }
        out.push('\n');
        for c in &self.candidates {
            let mark = if c.candidate == self.chosen { '*' } else { ' ' };
            let _ = write!(out, "{mark} {:<width$} {:>7.4}", c.candidate, c.mean);
            for e in &c.relative_error {
                let _ = write!(out, " {e:>7.4}");
            }
            out.push('\n');
        }
        let _ = writeln!(out, "chosen: {} (refitted on all the data)", self.chosen);
        out
    }
}

fn truncate(s: &str, n: usize) -> &str {
    match s.char_indices().nth(n) {
        Some((i, _)) => &s[..i],
        None => s,
    }
}
