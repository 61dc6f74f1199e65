//! The identified inertials as a URDF `<inertial>` holds them, checked the same way for
//! both exports: a URDF link is a rigid body, which a parameter vector need not be.

use crate::error::ModelError;
use crate::inertia::{barycentric_from_standard, standard_from_barycentric, StandardInertia};
use crate::model::*;

pub(super) fn urdf_inertial(s: Option<&StandardInertia>) -> urdf_rs::Inertial {
    match s {
        None => urdf_rs::Inertial::default(),
        Some(s) => {
            let i = &s.inertia_com;
            urdf_rs::Inertial {
                origin: urdf_rs::Pose {
                    xyz: urdf_rs::Vec3(s.com),
                    rpy: urdf_rs::Vec3([0.0; 3]),
                },
                mass: urdf_rs::Mass { value: s.mass },
                inertia: urdf_rs::Inertia {
                    ixx: i[0],
                    ixy: i[1],
                    ixz: i[2],
                    iyy: i[3],
                    iyz: i[4],
                    izz: i[5],
                },
            }
        }
    }
}

impl Model {
    /// Checks a parameter vector before writing it anywhere: right length, all finite.
    pub(super) fn check_export_params(&self, params: &[f64]) -> Result<(), ModelError> {
        let numeric = |message: String| ModelError::Numeric {
            model: self.name.clone(),
            message,
        };
        if params.len() != self.n_params() {
            return Err(numeric(format!(
                "{} parameter values for a model with {} parameters",
                params.len(),
                self.n_params()
            )));
        }
        if let Some((p, v)) = self.params.iter().zip(params).find(|(_, v)| !v.is_finite()) {
            return Err(numeric(format!("parameter {} is not finite ({v})", p.name)));
        }
        Ok(())
    }

    /// Checks that `params` (the full vector, SI units) are exportable: the right length,
    /// finite, and every link a rigid body (what a URDF inertial must hold). Every
    /// export of identified parameters to another tool (URDF, a controller's gravity
    /// compensation) goes through here: a controller fed a negative mass pushes the arm
    /// the wrong way.
    pub fn check_rigid_bodies(&self, params: &[f64]) -> Result<(), ModelError> {
        self.check_export_params(params)?;
        self.export_inertials(params).map(|_| ())
    }

    /// Standard inertials per frame index (`None` for the base and frames without link
    /// inertia), refusing what a URDF `<inertial>` cannot hold exactly: a negative mass,
    /// or a first moment without mass (a least-squares representative is typically
    /// such: the base parameters spread over columns with no physical meaning).
    pub(super) fn export_inertials(
        &self,
        params: &[f64],
    ) -> Result<Vec<Option<StandardInertia>>, ModelError> {
        let mut out = vec![None];
        let mut bad = Vec::new();
        for f in &self.frames {
            let Some(p0) = f.inertia else {
                out.push(None);
                continue;
            };
            let p = &params[p0..p0 + 10];
            let m = p[9];
            if m < 0.0 {
                bad.push(format!("{} (mass {m})", f.name));
            } else if m == 0.0 && p[6..9].iter().any(|&x| x != 0.0) {
                bad.push(format!(
                    "{} (mass 0 with first moment [{}, {}, {}])",
                    f.name, p[6], p[7], p[8]
                ));
            } else {
                let s = standard_from_barycentric(p);
                let back = barycentric_from_standard(s.mass, s.com, s.inertia_com);
                let scale = p.iter().fold(1.0f64, |a, x| a.max(x.abs()));
                let err = back
                    .iter()
                    .zip(p)
                    .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                if err > 1e-12 * scale {
                    bad.push(format!(
                        "{} (mass {m} too small for its first moment: the centre of mass \
                         cannot be written exactly)",
                        f.name
                    ));
                } else if let Err(why) =
                    crate::inertia::check_rigid_body(s.mass, s.com, s.inertia_com)
                {
                    bad.push(format!("{} ({why})", f.name));
                }
                out.push(Some(s));
                continue;
            }
            out.push(None);
        }
        if !bad.is_empty() {
            return Err(ModelError::Numeric {
                model: self.name.clone(),
                message: format!(
                    "{} {} {}: an exported link (a URDF inertial, a \
                     controller's gravity model) is a rigid body (mass ≥ 0, no first moment \
                     without mass, principal moments ≥ 0 within the triangle inequality); \
                     these parameters are not \
                     (e.g. a least-squares representative of the base parameters), use \
                     physically consistent ones",
                    if bad.len() > 1 { "links" } else { "link" },
                    bad.join(", "),
                    if bad.len() > 1 {
                        "are not rigid bodies"
                    } else {
                        "is not a rigid body"
                    }
                ),
            });
        }
        Ok(out)
    }
}
