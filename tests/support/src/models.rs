//! Robot descriptions that the tests of several crates share, kept as files under
//! `tests/fixtures/` so that each is written once.

/// `tests/fixtures/one_link.toml`: one revolute link on q1 about the base's −y axis
/// (modified DH, α = π/2), ten inertial parameters, gravity −9.81 m/s² along z.
pub const ONE_LINK: &str = include_str!("../../fixtures/one_link.toml");

/// [`ONE_LINK`] with `lines` appended to its only frame (its elements and bounds, e.g.
/// `"friction = true\n"`), as a description text.
pub fn one_link_with(lines: &str) -> String {
    format!("{ONE_LINK}{lines}")
}

/// `tests/fixtures/dh_odd.toml`: a standard-DH robot of three coordinates whose URDF
/// export needs every fallback (a rotated root, reversed and doubled coordinates, no
/// frame turning by `w` alone), shared with the Python export test.
pub const DH_ODD: &str = include_str!("../../fixtures/dh_odd.toml");
