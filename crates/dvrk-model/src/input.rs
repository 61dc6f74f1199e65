//! What the program accepts as input: sizes and physical ranges, checked where a number
//! or a file enters (descriptions, URDF, result and parameter files, limits files), so
//! that nothing downstream meets a NaN, an overflow or an allocation it cannot make.
//! The book's "Bad input" (docs/book/src/bad-input.md) lists the same limits.

use std::io::Read;
use std::path::Path;

use crate::inertia::sym3;

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
pub fn check_parameter_count(parameters: usize) -> Result<(), String> {
    if parameters > MAX_PARAMETERS {
        Err(format!(
            "{parameters} parameters; at most {MAX_PARAMETERS} are accepted (the base \
             parameters cost the cube of the count: 500 take about 2 s, 1000 about 20 s)"
        ))
    } else {
        Ok(())
    }
}

/// Checks that `value` is finite and at most `max` in magnitude; the message says what
/// is wrong (the caller names the file and field).
pub fn check_magnitude(value: f64, max: f64, unit: &str) -> Result<f64, String> {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    if !value.is_finite() {
        Err(format!("must be a finite number, got {value}"))
    } else if value.abs() > max {
        Err(format!(
            "{}{unit} is beyond the accepted ±{max:e}{unit}",
            show(value)
        ))
    } else {
        Ok(value)
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

/// Checks that mass (kg), centre of mass (m) and inertia about the centre of mass
/// `[xx, xy, xz, yy, yz, zz]` (kg·m²) describe a rigid body: finite and within range,
/// mass ≥ 0, principal moments ≥ 0 and each at most the sum of the other two (the
/// triangle inequality: no mass distribution has others). Moments are compared with a
/// relative tolerance of 1e-6 so that inertias rounded to a few digits (CAD exports)
/// pass. Returns a message naming the broken condition.
pub fn check_rigid_body(mass: f64, com: [f64; 3], inertia_com: [f64; 6]) -> Result<(), String> {
    check_magnitude(mass, MAX_MASS_KG, "kg").map_err(|m| format!("mass: {m}"))?;
    if mass < 0.0 {
        return Err(format!("mass {mass} kg: must be non-negative"));
    }
    for c in com {
        check_magnitude(c, MAX_LENGTH_M, "m").map_err(|m| format!("centre of mass: {m}"))?;
    }
    for i in inertia_com {
        check_magnitude(i, MAX_VALUE, "kg·m²").map_err(|m| format!("inertia: {m}"))?;
    }
    let mut moments: Vec<f64> = sym3(&inertia_com)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    moments.sort_by(f64::total_cmp);
    let tol = 1e-6 * moments[2].abs().max(f64::MIN_POSITIVE);
    if moments[0] < -tol {
        return Err(format!(
            "inertia about the centre of mass has a negative principal moment \
             ({}, {}, {} kg·m²): no rigid body has it",
            show_approx(moments[0]),
            show_approx(moments[1]),
            show_approx(moments[2])
        ));
    }
    if moments[2] > moments[0] + moments[1] + tol {
        return Err(format!(
            "principal moments {}, {}, {} kg·m² break the triangle inequality \
             (the largest exceeds the sum of the other two): no rigid body has them",
            // Enough digits to show a breach just beyond the 1e-6 tolerance.
            show_significant(moments[0], 9),
            show_significant(moments[1], 9),
            show_significant(moments[2], 9)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_bodies() {
        // A uniform box 0.1 × 0.2 × 0.3 m of 2 kg: I = m/12 (b² + c², ...).
        let m = 2.0;
        let (a, b, c): (f64, f64, f64) = (0.1, 0.2, 0.3);
        let i = [
            m / 12.0 * (b * b + c * c),
            0.0,
            0.0,
            m / 12.0 * (a * a + c * c),
            0.0,
            m / 12.0 * (a * a + b * b),
        ];
        check_rigid_body(m, [0.0, 0.1, 0.0], i).unwrap();
        // A thin rod (one moment zero, the other two equal) and a massless link.
        check_rigid_body(1.0, [0.0; 3], [0.1, 0.0, 0.0, 0.1, 0.0, 0.0]).unwrap();
        check_rigid_body(0.0, [0.0; 3], [0.0; 6]).unwrap();
        // ixx < 0, and a triangle inequality broken (3 > 1 + 1).
        let e = check_rigid_body(1.0, [0.0; 3], [-0.1, 0.0, 0.0, 0.1, 0.0, 0.1]).unwrap_err();
        assert!(e.contains("negative principal moment"), "{e}");
        let e = check_rigid_body(1.0, [0.0; 3], [1.0, 0.0, 0.0, 1.0, 0.0, 3.0]).unwrap_err();
        assert!(e.contains("triangle inequality"), "{e}");
        // Rotated: the products of inertia count (eigenvalues 3, 1, -1).
        let e = check_rigid_body(1.0, [0.0; 3], [1.0, 2.0, 0.0, 1.0, 0.0, 1.0]).unwrap_err();
        assert!(e.contains("negative"), "{e}");
        let e = check_rigid_body(-1.0, [0.0; 3], [0.0; 6]).unwrap_err();
        assert!(e.contains("non-negative"), "{e}");
        let e = check_rigid_body(f64::NAN, [0.0; 3], [0.0; 6]).unwrap_err();
        assert!(e.contains("finite"), "{e}");
        let e = check_rigid_body(1e299, [0.0; 3], [0.0; 6]).unwrap_err();
        assert!(e.contains("beyond"), "{e}");
    }

    #[test]
    fn text_files_are_bounded() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("larger than 64 MiB"), "{e}");
    }
}
