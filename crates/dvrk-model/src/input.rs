//! What the program accepts as input: sizes and physical ranges, checked where a number
//! or a file enters (descriptions, URDF, result and parameter files, limits files), so
//! that nothing downstream meets a NaN, an overflow or an allocation it cannot make.
//! The book's "Bad input" (docs/book/src/bad-input.md) lists the same limits.

use std::io::Read;
use std::path::Path;

/// Largest text file read whole (descriptions, URDF, results, parameter, trajectory and
/// limits files), bytes: the largest of them is a few hundred kB.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// Most frames (joints of a URDF) in a model.
pub const MAX_FRAMES: usize = 1000;

/// Most coordinates (degrees of freedom) of a model.
pub const MAX_COORDINATES: usize = 100;

/// Most parameters of a model. The base parameters cost about the cube of the parameter
/// count (PSM, 115 parameters: 5 ms; 500: 1.7 s; 1000: 17 s and 370 MB on a 2-core
/// machine), and every fit and excitation needs them; 600 (60 links with inertia)
/// keeps them to a few seconds.
pub const MAX_PARAMETERS: usize = 600;

/// Largest magnitude of a length (m): DH `a`, `d`, origins, centres of mass, limits on
/// lengths.
pub const MAX_LENGTH_M: f64 = 1e3;

/// Largest magnitude of an angle (rad) or of a coefficient of a coordinate in a joint
/// value, a coupling or a limit expression.
pub const MAX_ANGLE_RAD: f64 = 1e3;

/// Largest magnitude of gravity, m/s².
pub const MAX_GRAVITY: f64 = 1e3;

/// Largest mass of a link, kg.
pub const MAX_MASS_KG: f64 = 1e6;

/// Largest magnitude of any other physical number of a description or a parameter file
/// (inertias kg·m², friction N·m or N, motor inertias, stiffnesses, bounds).
pub const MAX_VALUE: f64 = 1e9;

/// Reads a whole text file of at most [`MAX_TEXT_BYTES`], refusing a longer one (or an
/// endless one such as `/dev/zero`) before reading it all. The error carries the OS error
/// or the reason; the caller names the file.
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    file.take(MAX_TEXT_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_TEXT_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "larger than {} MiB, more than any text file dvrk-ident reads (description, \
                 result, parameters, rosbag2 metadata)",
                MAX_TEXT_BYTES >> 20
            ),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
}

/// Checks a model's parameter count against [`MAX_PARAMETERS`], before the base
/// parameters (cubic in it) are computed.
pub fn check_parameter_count(parameters: usize) -> Result<(), InputError> {
    if parameters > MAX_PARAMETERS {
        Err(InputError::TooManyParameters { count: parameters })
    } else {
        Ok(())
    }
}

/// Checks that `value` is finite and at most `max` in magnitude (`unit` for the
/// message, `""` for none); the error says what is wrong (the caller names the file and
/// field).
pub fn check_magnitude(value: f64, max: f64, unit: &str) -> Result<f64, InputError> {
    if !value.is_finite() {
        Err(InputError::NotFinite { value })
    } else if value.abs() > max {
        Err(InputError::BeyondRange {
            value,
            max,
            unit: unit.to_string(),
        })
    } else {
        Ok(value)
    }
}

/// Checks that `value` is positive, finite and at most [`MAX_VALUE`]: a stiffness, a
/// period. The error names `quantity` (`the Dahl stiffness sigma`) and its `unit`.
pub fn check_positive(
    value: f64,
    quantity: &'static str,
    unit: &'static str,
) -> Result<f64, InputError> {
    check_magnitude(value, MAX_VALUE, unit).map_err(|e| InputError::Quantity {
        quantity,
        problem: Box::new(e),
    })?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(InputError::NotPositive {
            quantity,
            unit,
            value,
        })
    }
}

/// A number, size or body that is not accepted where it enters. The text says what is
/// wrong and echoes the value; the caller adds the file and the field (e.g. with
/// [`InputError::of`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// NaN or an infinity.
    #[error("must be a finite number, got {value}")]
    NotFinite {
        /// The value given.
        value: f64,
    },
    /// Finite, but beyond the accepted magnitude.
    #[error("{}{} is beyond the accepted ±{max:e}{}", show(*.value), spaced(.unit), spaced(.unit))]
    BeyondRange {
        /// The value given.
        value: f64,
        /// The largest accepted magnitude.
        max: f64,
        /// The value's unit (`m`, `kg·m²`), empty when it has none.
        unit: String,
    },
    /// More parameters than [`MAX_PARAMETERS`].
    #[error(
        "{count} parameters; at most {MAX_PARAMETERS} are accepted (the base parameters \
         cost the cube of the count: 500 take about 2 s, 1000 about 20 s)"
    )]
    TooManyParameters {
        /// The model's parameter count.
        count: usize,
    },
    /// A negative mass (kg).
    #[error("mass {mass} kg: must be non-negative")]
    NegativeMass {
        /// The mass given, kg.
        mass: f64,
    },
    /// An inertia about the centre of mass with a negative principal moment (kg·m²).
    #[error(
        "inertia about the centre of mass has a negative principal moment ({}, {}, {} \
         kg·m²): no rigid body has it",
        show_approx(.moments[0]), show_approx(.moments[1]), show_approx(.moments[2])
    )]
    NegativeMoment {
        /// The principal moments, ascending, kg·m².
        moments: [f64; 3],
    },
    /// Principal moments whose largest exceeds the sum of the other two (kg·m²).
    // Enough digits to show a breach just beyond the 1e-6 tolerance.
    #[error(
        "principal moments {}, {}, {} kg·m² break the triangle inequality (the largest \
         exceeds the sum of the other two): no rigid body has them",
        show_significant(.moments[0], 9), show_significant(.moments[1], 9),
        show_significant(.moments[2], 9)
    )]
    TriangleInequality {
        /// The principal moments, ascending, kg·m².
        moments: [f64; 3],
    },
    /// A rotation with a non-finite entry.
    #[error("the rotation is not finite")]
    RotationNotFinite,
    /// A rotation that is not orthonormal with determinant 1 (to 1e-9).
    #[error("the rotation is not orthonormal with determinant 1")]
    RotationNotProper,
    /// A semi-axis of an ellipsoid that is not a positive length within
    /// [`MAX_LENGTH_M`].
    #[error(
        "semi_axes: each must be a positive length of at most {MAX_LENGTH_M:e} m, got {value}"
    )]
    SemiAxis {
        /// The semi-axis given, m.
        value: f64,
    },
    /// A quantity that must be positive and is not.
    #[error("{quantity} must be positive ({unit}), got {value}")]
    NotPositive {
        /// What it is, e.g. `the Dahl stiffness sigma`.
        quantity: &'static str,
        /// Its unit, e.g. `1/rad or 1/m`.
        unit: &'static str,
        /// The value given.
        value: f64,
    },
    /// A series order out of its range.
    #[error("{quantity} must be 1 to {max}, got {value}")]
    Order {
        /// What it is, e.g. `the position torque's order`.
        quantity: &'static str,
        /// The largest accepted order.
        max: usize,
        /// The order given.
        value: usize,
    },
    /// A mounting pitch that is not finite or beyond ±180°.
    #[error("mounting pitch must be a finite angle within ±180°, got {}", show(*.pitch_deg))]
    MountingPitch {
        /// The pitch given, degrees.
        pitch_deg: f64,
    },
    /// A problem of one named part of a value: `{name}: {problem}` (a field such as
    /// `mass`, `com`, `center`).
    #[error("{name}: {problem}")]
    Named {
        /// The part, e.g. `centre of mass`.
        name: String,
        /// What is wrong with it.
        #[source]
        problem: Box<InputError>,
    },
    /// A problem of a quantity named in a sentence: `{quantity} {problem}`, e.g. `the
    /// Dahl stiffness sigma must be a finite number, got NaN`.
    #[error("{quantity} {problem}")]
    Quantity {
        /// The quantity, e.g. `the Dahl stiffness sigma`.
        quantity: &'static str,
        /// What is wrong with it.
        #[source]
        problem: Box<InputError>,
    },
}

impl InputError {
    /// This problem as one of the part `name` of a value: `{name}: {self}`.
    pub fn of(self, name: impl Into<String>) -> InputError {
        InputError::Named {
            name: name.into(),
            problem: Box::new(self),
        }
    }
}

/// ` unit`, or nothing for no unit.
fn spaced(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

/// A number as people write it: plain for ordinary magnitudes, with an exponent for
/// very large or small ones (`1e300`, not 301 digits).
pub fn show(value: f64) -> String {
    let a = value.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// A measured or derived number for a message: [`show`] of the value rounded to 6
/// significant digits, so that the round-off of a computation does not reach the
/// reader (a rate measured from time stamps as `200.00000000000426` Hz reads `200`; a
/// ratio of `1.499999999999968` reads `1.5`). A value the user gave is echoed with
/// [`show`], every digit as given.
///
/// ```
/// use dvrk_model::input::show_approx;
/// assert_eq!(show_approx(200.00000000000426), "200");
/// assert_eq!(show_approx(1.499999999999968), "1.5");
/// assert_eq!(show_approx(0.0011), "0.0011");
/// assert_eq!(show_approx(123456789.0), "123457000");
/// assert_eq!(show_approx(-2.5e-7), "-2.5e-7");
/// assert_eq!(show_approx(f64::NAN), "NaN");
/// ```
pub fn show_approx(value: f64) -> String {
    show_significant(value, 6)
}

/// [`show`] of `value` rounded to `digits` significant digits (at least 1): for a
/// message that compares numbers within a relative tolerance, enough digits to show
/// the difference.
///
/// ```
/// use dvrk_model::input::show_significant;
/// assert_eq!(show_significant(0.020000100000000003, 9), "0.0200001");
/// assert_eq!(show_significant(0.020000100000000003, 3), "0.02");
/// ```
pub fn show_significant(value: f64, digits: usize) -> String {
    let decimals = digits.max(1) - 1;
    match format!("{value:.decimals$e}").parse::<f64>() {
        Ok(rounded) if value.is_finite() => show(rounded),
        _ => show(value),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnitudes_without_a_unit() {
        // No unit, no space.
        let e = check_magnitude(-1e16, MAX_VALUE, "").unwrap_err();
        assert_eq!(e.to_string(), "-1e16 is beyond the accepted ±1e9");
    }

    /// The texts the CLI, Python and the C ABI show, word for word: a positive quantity
    /// (`--dahl`, a description's `position_torque.period`), a series order and a
    /// mounting pitch.
    #[test]
    fn element_and_setting_texts() {
        let sigma = |v| check_positive(v, "the Dahl stiffness sigma", "1/rad or 1/m");
        assert_eq!(sigma(20.0), Ok(20.0));
        assert_eq!(
            sigma(0.0).unwrap_err().to_string(),
            "the Dahl stiffness sigma must be positive (1/rad or 1/m), got 0"
        );
        assert_eq!(
            sigma(f64::NAN).unwrap_err().to_string(),
            "the Dahl stiffness sigma must be a finite number, got NaN"
        );
        assert_eq!(
            sigma(-1e300).unwrap_err().to_string(),
            "the Dahl stiffness sigma -1e300 1/rad or 1/m is beyond the accepted ±1e9 1/rad or 1/m"
        );
        let order = InputError::Order {
            quantity: "the position torque's order",
            max: 3,
            value: 4,
        };
        assert_eq!(
            order.to_string(),
            "the position torque's order must be 1 to 3, got 4"
        );
        assert_eq!(
            InputError::MountingPitch { pitch_deg: 1e300 }.to_string(),
            "mounting pitch must be a finite angle within ±180°, got 1e300"
        );
        assert_eq!(
            check_parameter_count(MAX_PARAMETERS + 1)
                .unwrap_err()
                .to_string(),
            "601 parameters; at most 600 are accepted (the base parameters cost the cube of \
             the count: 500 take about 2 s, 1000 about 20 s)"
        );
    }

    #[test]
    fn text_files_are_bounded() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("larger than 64 MiB"), "{e}");
    }
}
