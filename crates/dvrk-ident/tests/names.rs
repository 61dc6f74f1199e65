//! Every option enum's names (`dvrk_ident::Named`): what the CLI's flags and
//! Python's keyword arguments both parse. Kept out of `names.rs` so that the trait's
//! module depends on none of the enums that implement it.

use dvrk_ident::excite::optimize::Criterion;
use dvrk_ident::log::mcap::TimeSource;
use dvrk_ident::log::LogFormat;
use dvrk_ident::Coordinates;
use dvrk_ident::Named;
use dvrk_ident::PriorMetric;
use dvrk_ident::{BoundsSet, Method};

/// Every name parses back to its value in any case and with `-` for `_`; the
/// canonical names cover every value; an unknown name lists them.
fn check<T: Named + PartialEq + std::fmt::Debug>(values: &[T]) {
    for &(name, value) in T::NAMES {
        assert_eq!(T::parse_name(name), Ok(value), "{name}");
        assert_eq!(T::parse_name(&name.to_ascii_uppercase()), Ok(value));
        assert_eq!(T::parse_name(&name.replace('_', "-")), Ok(value));
        assert_eq!(T::parse_name(value.name()), Ok(value));
    }
    for v in values {
        assert!(
            T::names().any(|n| n == v.name()),
            "{v:?} has no canonical name"
        );
    }
    assert_eq!(T::names().count(), values.len());
    let e = T::parse_name("no-such-name").unwrap_err();
    assert_eq!((e.what, e.text.as_str()), (T::WHAT, "no-such-name"));
    assert_eq!(e.expected, T::names().collect::<Vec<_>>());
    let e = e.to_string();
    assert!(
        e.starts_with(&format!("unknown {} \"no-such-name\"", T::WHAT)),
        "{e}"
    );
    for n in T::names() {
        assert!(e.contains(n), "{e} does not list {n}");
    }
}

#[test]
fn every_option_name_parses_back() {
    check(&[Method::Ols, Method::Wls, Method::Irls, Method::Sdp]);
    check(&[BoundsSet::Physical, BoundsSet::Wang2019]);
    check(&[Criterion::Condition, Criterion::LogDet]);
    check(&[PriorMetric::Entropic, PriorMetric::Euclidean]);
    check(&[Coordinates::Measured, Coordinates::Model]);
    check(&[
        TimeSource::HeaderStamp,
        TimeSource::LogTime,
        TimeSource::PublishTime,
    ]);
    check(&[
        LogFormat::Wpi,
        LogFormat::Csv,
        LogFormat::Mcap,
        LogFormat::Rosbag2,
        LogFormat::Sqlite3,
        LogFormat::Ros1,
    ]);
    // The 2019 layout's other spellings.
    for alias in ["wpi-csv", "WPI_CSV", "2019"] {
        assert_eq!(LogFormat::parse_name(alias), Ok(LogFormat::Wpi));
    }
}
