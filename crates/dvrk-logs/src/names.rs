//! The names of the option enums (estimator, criterion, log format, time source, ...),
//! in one place: the command line, Python and result documents parse and print them
//! through [`Named`], so an option spelled one way in one front end is spelled the
//! same in the other.
//!
//! The trait lives with the logs, the lowest crate that names options (log formats, time
//! sources, coordinates); dvrk-ident implements it for its own (estimators, criteria...)
//! and re-exports the trait as `dvrk_ident::Named`.
//!
//! ```
//! use dvrk_logs::log::LogFormat;
//! use dvrk_logs::names::Named;
//! assert_eq!("CSV".parse::<LogFormat>().unwrap(), LogFormat::Csv);
//! assert_eq!(LogFormat::Wpi.name(), "wpi");
//! let e = "parquet".parse::<LogFormat>().unwrap_err();
//! assert_eq!(e.to_string(), "unknown log format \"parquet\": expected wpi, csv, mcap, rosbag2, sqlite3 or ros1");
//! ```

/// An option enum with one canonical name per value, and accepted aliases.
pub trait Named: Sized + Copy + 'static {
    /// What the option is called in messages (`method`, `criterion`, ...).
    const WHAT: &'static str;
    /// `(name, value)`, canonical names first in the order they are listed, then aliases.
    const NAMES: &'static [(&'static str, Self)];
    /// How many leading entries of [`Named::NAMES`] are canonical.
    const CANONICAL: usize;

    /// The canonical name.
    fn name(self) -> &'static str
    where
        Self: PartialEq,
    {
        Self::NAMES
            .iter()
            .find(|(_, v)| *v == self)
            .map(|(n, _)| *n)
            .expect("every value has a name")
    }

    /// The canonical names, for help texts.
    fn names() -> impl Iterator<Item = &'static str> {
        Self::NAMES[..Self::CANONICAL].iter().map(|(n, _)| *n)
    }

    /// Case-insensitive, `-` and `_` alike; the error lists the canonical names.
    fn parse_name(text: &str) -> Result<Self, UnknownName> {
        let key = |s: &str| s.to_ascii_lowercase().replace('-', "_");
        let wanted = key(text);
        Self::NAMES
            .iter()
            .find(|(n, _)| key(n) == wanted)
            .map(|(_, v)| *v)
            .ok_or_else(|| UnknownName {
                what: Self::WHAT,
                text: text.to_string(),
                expected: Self::names().collect(),
            })
    }
}

/// A text that names none of an option's values ([`Named::parse_name`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// What the option is called ([`Named::WHAT`]).
    pub what: &'static str,
    /// The text given.
    pub text: String,
    /// The option's canonical names, in their order.
    pub expected: Vec<&'static str>,
}

impl std::fmt::Display for UnknownName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let list = match self.expected.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => self.expected.join(""),
        };
        write!(f, "unknown {} {:?}: expected {list}", self.what, self.text)
    }
}

impl std::error::Error for UnknownName {}
