//! A frame's joint and fixed placement turned into its pose and motion: the DH
//! conventions ([`dh_geometry`]) and a joint along an axis after a fixed transform.

use super::check::check_transform;
use super::*;

impl Joint {
    /// The frame's pose and motion; `place` names the frame in messages.
    pub(crate) fn geometry(
        &self,
        file: &str,
        place: &str,
        n_coordinates: usize,
    ) -> Result<Geometry, ModelError> {
        let err = |field: &str, m: String| ModelError::field(file, place, field, m);
        let check = |field: &str, a: &Affine, max: f64| -> Result<(), ModelError> {
            if let Some(&(k, _)) = a.terms.iter().find(|t| t.0 >= n_coordinates) {
                return Err(err(
                    field,
                    format!("coordinate {k} does not exist ({n_coordinates} coordinates)"),
                ));
            }
            let sorted = a.terms.windows(2).all(|w| w[0].0 < w[1].0);
            if !sorted || a.terms.iter().any(|t| t.1 == 0.0) {
                return Err(err(
                    field,
                    "terms must be sorted by coordinate, each coordinate once, coefficients \
                     non-zero"
                        .into(),
                ));
            }
            for x in a.terms.iter().map(|t| t.1).chain([a.offset]) {
                input::check_magnitude(x, max, "").map_err(|e| err(field, e.to_string()))?;
            }
            Ok(())
        };
        match self {
            Joint::Dh {
                convention,
                a,
                alpha,
                theta,
                d,
            } => {
                let (length, angle) = (input::MAX_LENGTH_M, input::MAX_ANGLE_RAD);
                input::check_magnitude(*a, length, "m").map_err(|e| err("a", e.to_string()))?;
                input::check_magnitude(*alpha, angle, "rad")
                    .map_err(|e| err("alpha", e.to_string()))?;
                check("theta", theta, angle)?;
                check("d", d, length)?;
                dh_geometry(*convention, *a, *alpha, theta, d)
                    .map_err(|m| err("theta/d", m.to_string()))
            }
            Joint::Transform {
                kind,
                value,
                pre,
                post,
            } => {
                check(
                    "value",
                    value,
                    input::MAX_ANGLE_RAD.max(input::MAX_LENGTH_M),
                )?;
                if (*kind == JointKind::Fixed) != value.is_constant() {
                    return Err(err(
                        "value",
                        match kind {
                            JointKind::Fixed => "a fixed frame's value must be constant",
                            _ => "a moving frame's value must depend on the coordinates",
                        }
                        .into(),
                    ));
                }
                for (field, t) in [("pre", pre), ("post", post)] {
                    check_transform(t).map_err(|e| err(field, e.to_string()))?;
                }
                Ok(Geometry {
                    kind: *kind,
                    value: value.clone(),
                    pre: *pre,
                    post: *post,
                })
            }
        }
    }
}

/// The pose and motion of a DH frame: the joint value is whichever of `theta` and `d`
/// depends on the coordinates (neither: a fixed frame).
pub(crate) fn dh_geometry(
    convention: Convention,
    a: f64,
    alpha: f64,
    theta: &Affine,
    d: &Affine,
) -> Result<Geometry, &'static str> {
    if !theta.is_constant() && !d.is_constant() {
        return Err("only one of theta and d may depend on the coordinates");
    }
    let kind = if !theta.is_constant() {
        JointKind::Revolute
    } else if !d.is_constant() {
        JointKind::Prismatic
    } else {
        JointKind::Fixed
    };
    let (th0, d0) = (theta.offset, d.offset);
    let (rot_x, trans_x) = (Transform::rot_x(alpha), Transform::trans(a, 0.0, 0.0));
    let (pre, post, value) = match (convention, kind) {
        (Convention::Modified, JointKind::Revolute) => (
            rot_x.compose(&trans_x),
            Transform::trans(0.0, 0.0, d0),
            theta.clone(),
        ),
        (Convention::Modified, JointKind::Prismatic) => (
            rot_x.compose(&trans_x).compose(&Transform::rot_z(th0)),
            Transform::identity(),
            d.clone(),
        ),
        (Convention::Modified, JointKind::Fixed) => (
            rot_x
                .compose(&trans_x)
                .compose(&Transform::rot_z(th0))
                .compose(&Transform::trans(0.0, 0.0, d0)),
            Transform::identity(),
            Affine::constant(0.0),
        ),
        (Convention::Standard, JointKind::Revolute) => (
            Transform::identity(),
            Transform::trans(0.0, 0.0, d0)
                .compose(&trans_x)
                .compose(&rot_x),
            theta.clone(),
        ),
        (Convention::Standard, JointKind::Prismatic) => {
            (Transform::rot_z(th0), trans_x.compose(&rot_x), d.clone())
        }
        (Convention::Standard, JointKind::Fixed) => (
            Transform::rot_z(th0)
                .compose(&Transform::trans(0.0, 0.0, d0))
                .compose(&trans_x)
                .compose(&rot_x),
            Transform::identity(),
            Affine::constant(0.0),
        ),
    };
    Ok(Geometry {
        kind,
        value,
        pre,
        post,
    })
}
