//! The excitation options, each declared once: its field of [`ExciteOptions`] with its
//! default, its name (the command line's flag `--name`, Python's keyword `name=`) and
//! its documentation, whose first paragraph is the flag's help. The `excite_options!`
//! list below generates the struct, its `Default`, the [`ExciteOption`] that names each
//! option a front end sets, and the one conversion of their values
//! ([`ExciteOptions::from_values`]) both front ends use.
//!
//! **Adding an excitation option**: one entry in the list (doc, field, type, default,
//! variant, name); the command line's flag details (heading, value name, parser) in
//! dvrk-cli's `cmd/excite.rs`, whose exhaustive `match` does not compile without them;
//! Python takes it as a keyword with no edit but the type stub, which a test checks
//! against [`ExciteOption::ALL`] and the defaults.

use super::criterion::Criterion;
use super::FourierTrajectory;
use crate::options::parse_text_or_value;

macro_rules! excite_options {
    (
        options {$(
            $(#[doc = $doc:literal])*
            $field:ident: $ty:ty = $default:expr => $variant:ident($name:literal);
        )*}
        internal {$(
            $(#[doc = $idoc:literal])*
            $ifield:ident: $ity:ty = $idefault:expr;
        )*}
    ) => {
        /// Options of [`optimize`](super::optimize::optimize) (and, for the criterion's
        /// and the check's, of [`evaluate`](super::optimize::evaluate)). The first
        /// fields are the front ends' options ([`ExciteOption`]); the others are the
        /// search's own, set only from Rust.
        #[derive(Clone, Debug)]
        pub struct ExciteOptions {
            $(
                $(#[doc = $doc])*
                pub $field: $ty,
            )*
            $(
                $(#[doc = $idoc])*
                pub $ifield: $ity,
            )*
        }

        impl Default for ExciteOptions {
            fn default() -> Self {
                ExciteOptions {
                    $($field: $default,)*
                    $($ifield: $idefault,)*
                }
            }
        }

        /// An excitation option a front end sets, by identity: each front end spells it
        /// its own way (`--check-rate`, `check_rate=`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum ExciteOption {
            $(
                #[doc = concat!("`", $name, "` ([`ExciteOptions::", stringify!($field), "`]).")]
                $variant,
            )*
        }

        impl ExciteOption {
            /// Every option, in the order of [`ExciteOptions`].
            pub const ALL: &'static [ExciteOption] = &[$(ExciteOption::$variant),*];

            /// The option's name: Python's keyword, the flag's stem.
            pub fn name(self) -> &'static str {
                match self {
                    $(ExciteOption::$variant => $name,)*
                }
            }

            /// The first paragraph of the option's documentation, one line (the command
            /// line's help).
            pub fn doc(self) -> String {
                let lines: &[&str] = match self {
                    $(ExciteOption::$variant => &[$($doc),*],)*
                };
                lines
                    .iter()
                    .map(|l| l.trim())
                    .take_while(|l| !l.is_empty())
                    .collect::<Vec<_>>()
                    .join(" ")
            }

            /// The default ([`ExciteOptions::default`]) as the help shows it; `None` for a
            /// switch (a flag given or not).
            pub fn default_text(self) -> Option<String> {
                let d = ExciteOptions::default();
                match self {
                    $(ExciteOption::$variant => Shown::shown(&d.$field),)*
                }
            }

            /// The default ([`ExciteOptions::default`]) as a value (Python's default).
            pub fn default_value(self) -> serde_json::Value {
                let d = ExciteOptions::default();
                match self {
                    $(ExciteOption::$variant => {
                        serde_json::to_value(&d.$field).expect("an option's value serializes")
                    })*
                }
            }
        }

        impl ExciteOptions {
            /// Sets one option from a value: the option's own (a number, a boolean, a
            /// name) or its text as the command line gives it (`"0.18"`); an error names
            /// the option.
            pub fn set(
                &mut self,
                option: ExciteOption,
                value: serde_json::Value,
            ) -> Result<(), ExciteOptionError> {
                let error = |e: crate::options::TextOrValueError| ExciteOptionError {
                    option,
                    message: e.to_string(),
                };
                match option {
                    $(ExciteOption::$variant => self.$field = parse_text_or_value(value).map_err(error)?,)*
                }
                Ok(())
            }
        }
    };
}

excite_options! {
    options {
        /// Number of harmonics L
        order: usize = 6 => Order("order");
        /// Base frequency f0 (Hz): the period is 1/f0
        base_frequency_hz: f64 = 0.18 => F0("f0");
        /// Optimality criterion: `condition` (the condition number of the
        /// column-normalized base regressor, minimized) or `log_det` (its log-determinant,
        /// maximized)
        criterion: Criterion = Criterion::Condition => Criterion("criterion");
        /// Seed of the random starts (the search is deterministic for a seed)
        seed: u64 = 0 => Seed("seed");
        /// Number of random starts (each explored with a weak limit penalty)
        starts: usize = 8 => Starts("starts");
        /// Number of explored starts (the best by their merit) refined to a feasible
        /// trajectory
        refine: usize = 3 => Refine("refine");
        /// L-BFGS iterations of each of the 2 exploring stages
        ///
        /// Longer exploration is not better: the starts sink into their infeasible basins
        /// and their merits rank the basins worse (MTM: 150 gives a worse best-of-3 than
        /// 110).
        iterations_per_stage: usize = 110 => Iterations("iterations");
        /// L-BFGS iterations of each of the 5 refining stages
        refine_iterations_per_stage: usize = 180 => RefineIterations("refine_iterations");
        /// Regressor samples per period per harmonic for the criterion (its grid: this ×
        /// order instants)
        samples_per_harmonic: usize = 15 => SamplesPerHarmonic("samples_per_harmonic");
        /// Zero velocity and acceleration at the start and end of the period
        rest: bool = false => Rest("rest");
        /// Smooth stages first: a soft-max/soft-min surrogate of the condition number,
        /// sharpened stage by stage, is optimized before the exact one; `--no-smooth`
        /// (Python `smooth=False`) optimizes the exact condition number from the start
        smooth: bool = true => Smooth("smooth");
        /// Rate of the dense feasibility check (Hz; at least 1000)
        check_rate_hz: f64 = 1000.0 => CheckRate("check_rate");
    }
    internal {
        /// Random oscillations drawn per start: each runs the first exploring stage and the
        /// best by merit continues as the start. Where a start ends is chaotic (the last
        /// bits of a sum change the MTM's basin), so the best of few samples is luck:
        /// more draws per start is the cheap way to more samples, since a draw's first stage
        /// costs a fifteenth of a refinement.
        draws: usize = 4;
        /// Perturbations of the best refined trajectory, each refined again and kept when
        /// better (basin hopping, two at a time from the best so far). Refining the same
        /// point again barely moves it; a hop lands in a nearby basin, often a better one
        /// (MTM seed 1: 220.7 to 216.2 in four hops).
        hops: usize = 4;
        /// Size of a hop: the standard deviation of each harmonic coefficient's change, in
        /// units of its coordinate's room (a unit moves the coordinate's position by its
        /// room). 0.3 scatters the MTM into worse basins; 0.1 finds better ones.
        hop_size: f64 = 0.1;
        /// Bounds moved inward by this fraction of their range while optimizing.
        margin: f64 = 0.001;
        /// Warm start: the first start refines this trajectory (same order and base
        /// frequency), first pulled inside the limits toward a static pose if needed.
        init: Option<FourierTrajectory> = None;
        /// While optimizing, the Coulomb friction columns use `tanh(ṡ/ε)` instead of
        /// `sign(ṡ)`, with `ε` this value in rad/s (a tenth of it in m/s for prismatic
        /// joints); 0 keeps the sign. The sign jumps when a joint's velocity crosses zero at
        /// a criterion sample, a jump the gradient cannot see: without smoothing, the
        /// optimizer parks velocities at zero on the side where the jump would cost and
        /// stalls there. Reported criteria always use the exact sign.
        coulomb_smoothing: f64 = 0.01;
    }
}

impl ExciteOption {
    /// The options of an evaluation (`excite --evaluate`, Python's
    /// `evaluate_trajectory`): the criterion and the dense check.
    pub const EVALUATE: &'static [ExciteOption] = &[
        ExciteOption::Criterion,
        ExciteOption::SamplesPerHarmonic,
        ExciteOption::CheckRate,
    ];

    /// The option of this name ([`ExciteOption::name`]).
    pub fn from_name(name: &str) -> Option<ExciteOption> {
        ExciteOption::ALL.iter().copied().find(|o| o.name() == name)
    }
}

impl ExciteOptions {
    /// The defaults with these options set: the one conversion of the front ends' flags
    /// and keyword arguments (an error names the option).
    ///
    /// ```rust
    /// use dvrk_ident::excite::optimize::{Criterion, ExciteOption, ExciteOptions};
    /// use serde_json::json;
    ///
    /// let o = ExciteOptions::from_values([
    ///     (ExciteOption::Order, json!("4")),
    ///     (ExciteOption::Criterion, json!("log_det")),
    ///     (ExciteOption::Smooth, json!(false)),
    /// ])
    /// .unwrap();
    /// assert_eq!((o.order, o.criterion, o.smooth), (4, Criterion::LogDet, false));
    /// assert_eq!(o.starts, ExciteOptions::default().starts);
    /// let e = ExciteOptions::from_values([(ExciteOption::F0, json!("fast"))]).unwrap_err();
    /// assert_eq!(e.option, ExciteOption::F0);
    /// ```
    pub fn from_values(
        values: impl IntoIterator<Item = (ExciteOption, serde_json::Value)>,
    ) -> Result<ExciteOptions, ExciteOptionError> {
        let mut opts = ExciteOptions::default();
        for (option, value) in values {
            opts.set(option, value)?;
        }
        Ok(opts)
    }
}

/// A value refused for an excitation option: the option, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct ExciteOptionError {
    /// The option.
    pub option: ExciteOption,
    /// What is wrong with the value given.
    pub message: String,
}

/// How the help shows a default: a number or name as its text, a switch not at all.
trait Shown {
    fn shown(&self) -> Option<String>;
}

macro_rules! shown_as_text {
    ($($ty:ty),*) => {$(
        impl Shown for $ty {
            fn shown(&self) -> Option<String> {
                Some(self.to_string())
            }
        }
    )*};
}

shown_as_text!(usize, u64, f64);

impl Shown for bool {
    fn shown(&self) -> Option<String> {
        None
    }
}

impl Shown for Criterion {
    fn shown(&self) -> Option<String> {
        Some(self.name().into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Every option has a distinct name, a one-line help, a default that reads back as
    /// itself, and the same value from its text (the command line) and from a value
    /// (Python).
    #[test]
    fn names_defaults_and_values() {
        let mut names: Vec<&str> = ExciteOption::ALL.iter().map(|o| o.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), ExciteOption::ALL.len());
        for &o in ExciteOption::ALL {
            assert!(!o.doc().is_empty() && !o.doc().contains("  "), "{o:?}");
            assert_eq!(ExciteOption::from_name(o.name()), Some(o));
            let mut from_default = ExciteOptions::default();
            from_default.set(o, o.default_value()).unwrap();
            if let Some(text) = o.default_text() {
                let mut from_text = ExciteOptions::default();
                from_text.set(o, json!(text)).unwrap();
                assert_eq!(
                    format!("{from_text:?}"),
                    format!("{from_default:?}"),
                    "{o:?}"
                );
            }
        }
        assert!(!ExciteOption::Iterations
            .doc()
            .contains("Longer exploration"));
        let text = ExciteOptions::from_values([
            (ExciteOption::F0, json!("0.25")),
            (ExciteOption::Seed, json!("3")),
            (ExciteOption::Criterion, json!("logdet")),
        ])
        .unwrap();
        let values = ExciteOptions::from_values([
            (ExciteOption::F0, json!(0.25)),
            (ExciteOption::Seed, json!(3)),
            (ExciteOption::Criterion, json!("log_det")),
        ])
        .unwrap();
        assert_eq!(format!("{text:?}"), format!("{values:?}"));
        assert_eq!((values.seed, values.criterion), (3, Criterion::LogDet));
        let e = ExciteOptions::from_values([(ExciteOption::Starts, json!(-1))]).unwrap_err();
        assert_eq!(e.option, ExciteOption::Starts);
        assert!(e.message.contains("-1"), "{}", e.message);
        let e = ExciteOptions::from_values([(ExciteOption::Criterion, json!("trace"))]);
        assert!(e.unwrap_err().message.contains("trace"));
    }
}
