//! The checks of a builder's inputs, each naming the file, the frame and the field:
//! transforms, the frame count, nominal values, bounds and ranges.

use super::*;
use crate::input::InputError;

/// A transform of finite numbers (translation within ±[`input::MAX_LENGTH_M`]) whose
/// rotation is orthonormal with determinant 1 (to 1e-9).
pub(super) fn check_transform(t: &Transform) -> Result<(), InputError> {
    for &x in t.translation.iter() {
        input::check_magnitude(x, input::MAX_LENGTH_M, "m")?;
    }
    let r = &t.rotation;
    if !r.iter().all(|x| x.is_finite()) {
        return Err(InputError::RotationNotFinite);
    }
    let off = (r.transpose() * r - Matrix3::identity()).abs().max();
    if off > 1e-9 || (r.determinant() - 1.0).abs() > 1e-9 {
        return Err(InputError::RotationNotProper);
    }
    Ok(())
}

/// At most [`input::MAX_FRAMES`] frames.
pub(super) fn check_frame_count(source: &str, n_frames: usize) -> Result<(), ModelError> {
    if n_frames > input::MAX_FRAMES {
        return Err(ModelError::field(
            source,
            "frames",
            "",
            format!(
                "{n_frames} frames; at most {} are accepted",
                input::MAX_FRAMES
            ),
        ));
    }
    Ok(())
}

/// A frame's nominal values: a rigid body where they give one (mass, centre of mass and
/// inertia), every other value finite and within range.
pub(super) fn check_nominal(n: &Nominal) -> Result<(), InputError> {
    if let Some(mass) = n.mass.filter(|&m| m < 0.0) {
        return Err(InputError::NegativeMass { mass });
    }
    if let (Some(mass), Some(com), Some(inertia)) = (n.mass, n.com, n.inertia) {
        crate::inertia::check_rigid_body(mass, com, inertia)?;
    }
    let scalars = [
        ("mass", n.mass),
        ("fc", n.fc),
        ("fv", n.fv),
        ("fo", n.fo),
        ("fs", n.fs),
        ("ia", n.ia),
        ("k", n.k),
    ];
    for (name, v) in scalars {
        if let Some(v) = v {
            input::check_magnitude(v, input::MAX_VALUE, "").map_err(|e| e.of(name))?;
        }
    }
    for (name, values) in [
        ("com", n.com.as_ref().map(|c| &c[..])),
        ("inertia", n.inertia.as_ref().map(|i| &i[..])),
    ] {
        for &v in values.unwrap_or(&[]) {
            input::check_magnitude(v, input::MAX_VALUE, "").map_err(|e| e.of(name))?;
        }
    }
    Ok(())
}

/// A frame's bounds: maxima within range, mass and centre-of-mass ranges only on a
/// frame with a link, every range finite and ordered.
pub(super) fn check_frame_bounds(
    file: &str,
    place: &str,
    bounds: &FrameBounds,
    has_link: bool,
) -> Result<(), ModelError> {
    for (field, v) in [
        ("bounds.fc_max", bounds.fc_max),
        ("bounds.fv_max", bounds.fv_max),
        ("bounds.fo_max", bounds.fo_max),
        ("bounds.ia_max", bounds.ia_max),
    ] {
        if let Some(v) = v {
            input::check_magnitude(v, input::MAX_VALUE, "")
                .map_err(|m| ModelError::field(file, place, field, m))?;
        }
    }
    if (bounds.mass.is_some() || bounds.com.is_some() || bounds.ellipsoid.is_some()) && !has_link {
        return Err(ModelError::field(
            file,
            place,
            "bounds",
            "mass/com/ellipsoid bounds on a frame without link inertia",
        ));
    }
    if let Some(e) = &bounds.ellipsoid {
        e.check()
            .map_err(|m| ModelError::field(file, place, "bounds.ellipsoid", m))?;
    }
    check_range(file, place, "bounds.mass", bounds.mass)?;
    check_range(file, place, "bounds.spring", bounds.spring)?;
    if let Some(com) = bounds.com {
        for r in com {
            check_range(file, place, "bounds.com", Some(r))?;
        }
    }
    Ok(())
}

/// A range `[lo, hi]`, finite and ordered, if any.
pub(super) fn check_range(
    file: &str,
    place: &str,
    field: &str,
    r: Option<[f64; 2]>,
) -> Result<(), ModelError> {
    if let Some([lo, hi]) = r {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(ModelError::field(
                file,
                place,
                field,
                format!("invalid range [{lo}, {hi}]"),
            ));
        }
    }
    Ok(())
}
