//! Generate mode ([`Model::to_urdf`]): a URDF of a whole description, e.g. the DH
//! trees of the dVRK PSM and MTM with their parallelograms and tendon couplings, with
//! `urdf_rs::write_to_string`. Every model frame becomes a link of the same name (the
//! base is the root link). A frame's pose relative to its parent is
//! `pre·J(s)·post` with `J` the rotation about (translation along) z by the joint
//! value `s = a·q + c`; because `post` commutes with `J` whenever it keeps the z axis
//! line (always for the modified-DH and URDF frames), the joint origin is `pre·post`
//! and the axis is z seen from after `post`; otherwise `post` becomes a fixed joint
//! after a massless `{frame}_motion` link. Then:
//! - each coordinate `q_k` is carried by exactly one non-mimic joint named after it: the
//!   first frame whose value is exactly `q_k`, else `q_k + c` (the constant folded into
//!   the origin), else `−q_k + c` (axis −z), so that the URDF's coordinates are the
//!   model's. That needs every coordinate to have such a frame, above every other
//!   frame driven by it: Pinocchio (`mimic=True`) adds a mimic joint only after the
//!   joint it mimics, visiting the tree depth first with each link's child joints in
//!   the order of their names (urdfdom's). Otherwise (the PSM's `1.0186*q5`, the
//!   parallelograms, which mimic `q2` in one branch and `q3` in another) every
//!   coordinate is a massless link `{q_k}_coordinate` hung from the root and every
//!   moving frame a mimic; the root's frames then hang from a massless
//!   `{root}_frames` link whose fixed joint is named after the greatest coordinate
//!   name plus `_frames`, so it sorts after all coordinates. Either way our importer
//!   reads the coordinates back in order (checked on the generated text);
//! - every other frame driven by one coordinate, `s = a·q_k + c`, is a
//!   `<mimic joint="q_k" multiplier="a" offset="c">`;
//! - a frame driven by several coordinates (the MTM parallelogram, `q3 − q2`) is a chain
//!   of joints about the same axis through the same point, one mimic per coordinate,
//!   separated by massless links `{frame}_{q_k}` with identity origins. Rotations about
//!   one axis (translations along it) add, so the chain's total motion is exactly `s`;
//!   no mimic ever refers to another mimic;
//! - Coulomb and viscous friction of a one-coordinate frame go into
//!   `<dynamics friction="Fc" damping="Fv">` of its joint. Offset friction, the friction
//!   of multi-coordinate frames, motor inertias, springs and known forces have no URDF
//!   element; the file's header comment lists their values.
//!
//! Joint limits come from the description's `[[limits]]` on one coordinate (for the
//! dVRK descriptions, the 2019 excitation ranges), mapped through each joint's
//! multiplier and offset; a revolute joint without a known range is `continuous`, a
//! prismatic one gets a `<limit>` without `lower`/`upper`.
//! Effort limits are unknown to an identification and written as 0, as URDF
//! exporters commonly do (urdfdom requires the attribute).
//!
//! Joint-origin rotations are converted to rpy by removing one angle at a time, which
//! reproduces the rotation to rounding also at pitch ±π/2.

use std::fmt::Write as _;

use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::element::Note;
use crate::error::ModelError;
use crate::expr::Affine;
use crate::inertia::{pseudo_inertia_min_eigenvalue, StandardInertia};
use crate::model::*;

mod document;
use document::{Builder, GenerateError, JointSpec, Range};

/// URDF tools assume this gravity along −z of the root link (m/s²).
const URDF_GRAVITY: f64 = 9.81;

/// Roll, pitch, yaw of a rotation in the URDF convention `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
///
/// Each angle is removed from the matrix before the next is read, so the decomposition
/// reproduces `r` to rounding everywhere, including at and near pitch = ±π/2 where DH
/// frames often sit and the textbook `asin` formula loses half the digits.
pub(crate) fn rpy_from_rotation(r: &Matrix3<f64>) -> [f64; 3] {
    // At pitch ±π/2 only yaw − roll (or yaw + roll) is defined; yaw = 0 there, rather than
    // an angle read from rounding noise, keeps the numbers readable.
    let yaw = if r[(1, 0)].hypot(r[(0, 0)]) < 1e-15 {
        0.0
    } else {
        r[(1, 0)].atan2(r[(0, 0)])
    };
    let n = Rotation3::from_axis_angle(&Vector3::z_axis(), -yaw).matrix() * r;
    let pitch = (-n[(2, 0)]).atan2(n[(0, 0)]);
    let m = Rotation3::from_axis_angle(&Vector3::y_axis(), -pitch).matrix() * n;
    let roll = m[(2, 1)].atan2(m[(2, 2)]);
    // `+ 0.0` turns −0 into 0: `rpy="0 -0 0"` is right but reads like a mistake.
    [roll + 0.0, pitch + 0.0, yaw + 0.0]
}

fn motion(kind: JointKind, s: f64) -> Transform {
    match kind {
        JointKind::Revolute => Transform::rot_z(s),
        JointKind::Prismatic => Transform::trans(0.0, 0.0, s),
        JointKind::Fixed => Transform::identity(),
    }
}

/// XML comments may not contain `--`.
fn comment_safe(text: &str) -> String {
    let mut s = text.to_string();
    while s.contains("--") {
        s = s.replace("--", "- -");
    }
    s
}

impl Model {
    /// For each coordinate, the frame whose joint carries it and the sign of its
    /// coefficient: the first frame whose value is exactly `q_k`, else `q_k + c`, else
    /// `−q_k + c`; `None` when no frame qualifies.
    fn coordinate_carriers(&self) -> Vec<Option<(usize, f64)>> {
        (0..self.dof())
            .map(|k| {
                self.frames
                    .iter()
                    .enumerate()
                    .filter(|(_, f)| {
                        f.kind != JointKind::Fixed
                            && f.value.terms.len() == 1
                            && f.value.terms[0].0 == k
                    })
                    .filter_map(|(i, f)| {
                        let a = f.value.terms[0].1;
                        let rank = if a == 1.0 && f.value.offset == 0.0 {
                            0
                        } else if a == 1.0 {
                            1
                        } else if a == -1.0 {
                            2
                        } else {
                            return None;
                        };
                        Some((rank, i + 1, a))
                    })
                    .min_by_key(|&(rank, i, _)| (rank, i))
                    .map(|(_, i, a)| (i, a))
            })
            .collect()
    }

    /// Position ranges and speed bounds of the coordinates, from the limits on a single
    /// coordinate (intersected when there are several).
    fn coordinate_ranges(&self) -> Vec<Range> {
        let mut ranges = vec![Range::default(); self.dof()];
        for lim in &self.limits {
            let [(k, a)] = lim.expr.terms[..] else {
                continue;
            };
            let b = lim.expr.offset;
            let r = &mut ranges[k];
            if let Some([lo, hi]) = lim.position {
                let (x, y) = ((lo - b) / a, (hi - b) / a);
                let (x, y) = (x.min(y), x.max(y));
                r.position = match r.position {
                    Some([l, h]) if x.max(l) <= y.min(h) => Some([x.max(l), y.min(h)]),
                    Some(old) => Some(old),
                    None => Some([x, y]),
                };
            }
            if let Some([lo, hi]) = lim.velocity {
                let v = lo.abs().min(hi.abs()) / a.abs();
                r.velocity = Some(r.velocity.map_or(v, |old: f64| old.min(v)));
            }
        }
        ranges
    }

    /// A URDF of the whole model with the standard inertial parameters of `params` (the
    /// full parameter vector): one link per frame, one non-mimic joint per coordinate,
    /// mimic joints and massless chains for the couplings (see the module documentation
    /// for the construction and why it is exact). The header comment lists what URDF
    /// cannot hold (motor inertias, springs, known forces, offset friction).
    ///
    /// ```
    /// use dvrk_model::Model;
    /// let mtm = Model::builtin("mtm").unwrap();
    /// let mut params = vec![0.0; mtm.n_params()];
    /// for &i in mtm.link_frames() {
    ///     let p0 = mtm.frame(i).inertia.unwrap();
    ///     params[p0 + 9] = 1.0; // a 1 kg point mass at each frame origin
    /// }
    /// let urdf = mtm.to_urdf(&params).unwrap();
    /// let back = Model::from_urdf_str(&urdf, "mtm.urdf").unwrap();
    /// assert_eq!(back.coordinates.len(), 7);
    /// // The forearm turns by q3 − q2: a mimic of q2 then a mimic of q3 about the same axis.
    /// assert!(urdf.contains(r#"<mimic joint="q2" multiplier="-1""#));
    /// ```
    pub fn to_urdf(&self, params: &[f64]) -> Result<String, ModelError> {
        self.check_export_params(params)?;
        let inertials = self.export_inertials(params)?;
        let error = |e: GenerateError| ModelError::Urdf {
            file: self.source.clone(),
            message: e.to_string(),
        };
        let carriers = self.coordinate_carriers();
        if self.carriers_lead(&carriers) {
            let text = self
                .generate(params, &inertials, &carriers)
                .map_err(error)?;
            // Our importer numbers the coordinates in breadth-first order.
            let back = Model::from_urdf_str(&text, &self.source);
            if back.is_ok_and(|b| b.coordinates == self.coordinates) {
                return Ok(text);
            }
        }
        self.generate(params, &inertials, &vec![None; self.dof()])
            .map_err(error)
    }

    /// True if every coordinate has a carrier frame and every other frame driven by
    /// that coordinate hangs below it: then any traversal of the tree meets a
    /// coordinate's joint before its mimics, as Pinocchio's URDF parser (`mimic=True`)
    /// requires, since it adds a mimic joint only after the joint it mimics.
    fn carriers_lead(&self, carriers: &[Option<(usize, f64)>]) -> bool {
        let below = |mut i: usize, ancestor: usize| loop {
            if i == ancestor {
                return true;
            }
            if i == 0 {
                return false;
            }
            i = self.frames[i - 1].parent;
        };
        carriers.iter().all(Option::is_some)
            && self.frames.iter().enumerate().all(|(fi, f)| {
                f.kind == JointKind::Fixed
                    || f.value.terms.iter().all(|&(k, _)| {
                        carriers[k].is_some_and(|(carrier, _)| below(fi + 1, carrier))
                    })
            })
    }

    /// The URDF text with the coordinates carried by `carriers` (frame, sign); a
    /// coordinate without one gets a massless `{q_k}_coordinate` link hung from the
    /// root, written before every other joint (so in order, and ahead of its mimics).
    fn generate(
        &self,
        params: &[f64],
        inertials: &[Option<StandardInertia>],
        carriers: &[Option<(usize, f64)>],
    ) -> Result<String, GenerateError> {
        let mut g = Generator {
            model: self,
            params,
            carriers,
            names: self.frame_names(),
            ranges: self.coordinate_ranges(),
            out: Builder::default(),
            notes: Vec::new(),
        };
        g.gravity()?;
        g.out.link(&g.names[0], None)?;
        for (f, s) in self.frames.iter().zip(&inertials[1..]) {
            g.out.link(&f.name, s.as_ref())?;
        }
        g.coordinate_links()?;
        let top = g.frames_link()?;
        for (fi, f) in self.frames.iter().enumerate() {
            let parent = if f.parent == 0 {
                top.clone()
            } else {
                g.names[f.parent].clone()
            };
            g.frame(fi + 1, f, parent)?;
        }
        g.element_notes();
        g.finish()
    }
}

/// A URDF being generated by [`Model::to_urdf`]: the model and the values written, the
/// coordinates' carrier frames and ranges, and the links, joints and notes so far.
struct Generator<'a> {
    model: &'a Model,
    params: &'a [f64],
    carriers: &'a [Option<(usize, f64)>],
    /// Frame names, base first.
    names: Vec<String>,
    ranges: Vec<Range>,
    out: Builder,
    /// What the URDF cannot hold, for the header comment.
    notes: Vec<String>,
}

impl Generator<'_> {
    fn expr(&self, a: &Affine) -> String {
        a.display(&self.model.coordinates)
    }

    /// Gravity: URDF tools pull along −z of the root link, so a model whose gravity
    /// points elsewhere hangs from a `{root}_world` link turned to match.
    fn gravity(&mut self) -> Result<(), GenerateError> {
        let g = self.model.gravity;
        if g.norm() == 0.0 {
            self.notes
                .push("the model has no gravity; URDF tools apply their own".into());
            return Ok(());
        }
        let down = -Vector3::z();
        if (g.normalize() - down).norm() > 1e-15 {
            let root = format!("{}_world", self.names[0]);
            self.out.link(&root, None)?;
            let r = Rotation3::rotation_between(&g, &down).unwrap_or_else(|| {
                Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
            });
            self.out.joint(JointSpec::fixed(
                format!("{}_joint", root),
                Transform {
                    rotation: *r.matrix(),
                    translation: Vector3::zeros(),
                },
                root.clone(),
                self.names[0].clone(),
            ))?;
        }
        if (g.norm() - URDF_GRAVITY).abs() > 1e-12 {
            self.notes.push(format!(
                "gravity is {} m/s² in the model, URDF tools apply their own (usually {URDF_GRAVITY})",
                g.norm()
            ));
        }
        Ok(())
    }

    /// Coordinates no frame can carry get a massless link of their own.
    fn coordinate_links(&mut self) -> Result<(), GenerateError> {
        let m = self.model;
        for (k, c) in self.carriers.iter().enumerate() {
            if c.is_none() {
                let link = format!("{}_coordinate", m.coordinates[k]);
                self.out.link(&link, None)?;
                self.out.joint(JointSpec {
                    name: m.coordinates[k].clone(),
                    kind: if m.coordinate_is_length[k] {
                        JointKind::Prismatic
                    } else {
                        JointKind::Revolute
                    },
                    origin: Transform::identity(),
                    parent: self.names[0].clone(),
                    child: link,
                    axis: Vector3::z(),
                    range: self.ranges[k],
                    mimic: None,
                    dynamics: None,
                })?;
            }
        }
        Ok(())
    }

    /// The link the root's frames hang from. URDF parsers (urdfdom, so Pinocchio) visit
    /// a link's child joints sorted by name, depth first. When every coordinate is a
    /// root-level `<qk>_coordinate` joint, the frames hanging from the root go under one
    /// massless link whose fixed joint's name extends the greatest coordinate name, so it
    /// sorts after all of them: every coordinate is met before any mimic.
    fn frames_link(&mut self) -> Result<String, GenerateError> {
        let root = self.names[0].clone();
        if !self.carriers.iter().all(Option::is_none) {
            return Ok(root);
        }
        let m = self.model;
        let greatest = m.coordinates.iter().max().cloned().unwrap_or_default();
        let top = format!("{root}_frames");
        self.out.link(&top, None)?;
        self.out.joint(JointSpec::fixed(
            format!("{greatest}_frames"),
            Transform::identity(),
            root,
            top.clone(),
        ))?;
        Ok(top)
    }

    /// The joints of frame `i` (`f`) under link `parent`: a fixed joint, the joint
    /// carrying a coordinate, a mimic of one coordinate, or a chain of mimics.
    fn frame(&mut self, i: usize, f: &Frame, parent: String) -> Result<(), GenerateError> {
        if f.kind == JointKind::Fixed {
            return self.out.joint(JointSpec::fixed(
                format!("{}_joint", f.name),
                self.model.fixed[i],
                parent,
                f.name.clone(),
            ));
        }
        // pre·J(s)·post = (pre·post)·J_u(s) when post keeps the z axis line.
        let fold = match f.kind {
            JointKind::Revolute => f.post.translation.x == 0.0 && f.post.translation.y == 0.0,
            _ => true,
        };
        let (axis, end) = if fold {
            (f.post.rotation.transpose() * Vector3::z(), f.name.clone())
        } else {
            let end = format!("{}_motion", f.name);
            self.out.link(&end, None)?;
            self.out.joint(JointSpec::fixed(
                format!("{}_post", f.name),
                f.post,
                end.clone(),
                f.name.clone(),
            ))?;
            (Vector3::z(), end)
        };
        let origin = |c: f64| {
            let o = f.pre.compose(&motion(f.kind, c));
            if fold {
                o.compose(&f.post)
            } else {
                o
            }
        };
        let c = f.value.offset;
        let dynamics = self.friction_dynamics(f);
        if let [(k, a)] = f.value.terms[..] {
            let m = self.model;
            if let Some((carrier, sign)) = self.carriers[k] {
                if carrier == i {
                    return self.out.joint(JointSpec {
                        name: m.coordinates[k].clone(),
                        kind: f.kind,
                        origin: origin(c),
                        parent,
                        child: end,
                        axis: sign * axis,
                        range: self.ranges[k],
                        mimic: None,
                        dynamics,
                    });
                }
            }
            return self.out.joint(JointSpec {
                name: format!("{}_joint", f.name),
                kind: f.kind,
                origin: origin(0.0),
                parent,
                child: end,
                axis,
                range: self.ranges[k].map(a, c),
                mimic: Some((m.coordinates[k].clone(), a, c)),
                dynamics,
            });
        }
        self.coupled_joints(f, parent, end, axis, origin(0.0))
    }

    /// A frame driven by several coordinates: one joint per coordinate about the same
    /// axis, the first at `origin`, separated by massless links `{frame}_{q_k}`.
    fn coupled_joints(
        &mut self,
        f: &Frame,
        parent: String,
        end: String,
        axis: Vector3<f64>,
        origin: Transform,
    ) -> Result<(), GenerateError> {
        let c = f.value.offset;
        let mut from = parent;
        let last = f.value.terms.len() - 1;
        for (j, &(k, a)) in f.value.terms.iter().enumerate() {
            let coord = &self.model.coordinates[k];
            let child = if j == last {
                end.clone()
            } else {
                let l = format!("{}_{coord}", f.name);
                self.out.link(&l, None)?;
                l
            };
            let offset = if j == 0 { c } else { 0.0 };
            self.out.joint(JointSpec {
                name: format!("{}_joint_{coord}", f.name),
                kind: f.kind,
                origin: if j == 0 {
                    origin
                } else {
                    Transform::identity()
                },
                parent: from,
                child: child.clone(),
                axis,
                range: self.ranges[k].map(a, offset),
                mimic: Some((coord.clone(), a, offset)),
                dynamics: None,
            })?;
            from = child;
        }
        Ok(())
    }

    /// Friction on a one-coordinate joint value as URDF `<dynamics>`; what URDF cannot
    /// hold (offset friction, negative values, friction of coupled frames) as notes.
    fn friction_dynamics(&mut self, f: &Frame) -> Option<urdf_rs::Dynamics> {
        let fr = f.friction()?;
        let (params, names) = (self.params, &self.model.params);
        let (fc, fv, fo) = (params[fr.param], params[fr.param + 1], params[fr.param + 2]);
        let (nc, nv, no) = (
            &names[fr.param].name,
            &names[fr.param + 1].name,
            &names[fr.param + 2].name,
        );
        if f.value.terms.len() > 1 {
            if fc != 0.0 || fv != 0.0 || fo != 0.0 {
                let note = format!(
                    "friction {nc} = {fc}, {nv} = {fv}, {no} = {fo} of frame {} (joint value {}: several coordinates, no single URDF joint)",
                    f.name,
                    self.expr(&f.value)
                );
                self.notes.push(note);
            }
            return None;
        }
        let mut dynamics = None;
        if fc < 0.0 || fv < 0.0 {
            self.notes.push(format!(
                "friction {nc} = {fc}, {nv} = {fv} of frame {} (negative, not written as <dynamics>)",
                f.name
            ));
        } else if fc != 0.0 || fv != 0.0 {
            dynamics = Some(urdf_rs::Dynamics {
                damping: fv,
                friction: fc,
            });
        }
        if fo != 0.0 {
            let note = format!(
                "offset friction {no} = {fo} of frame {} (on {})",
                f.name,
                self.expr(&f.value)
            );
            self.notes.push(note);
        }
        dynamics
    }

    /// The elements' own notes (motor inertias, springs, known forces...).
    fn element_notes(&mut self) {
        let m = self.model;
        for f in &m.frames {
            let on = self.expr(&f.value);
            let note = Note {
                params: self.params,
                names: &m.params,
                coordinates: &m.coordinates,
                frame: &f.name,
                on: &on,
            };
            self.notes
                .extend(f.elements.iter().filter_map(|e| e.note(&note)));
        }
    }

    /// The document: the header comment, then the robot.
    fn finish(self) -> Result<String, GenerateError> {
        let head = self.header();
        let robot = urdf_rs::Robot {
            name: self.model.name.clone(),
            version: None,
            links: self.out.links,
            joints: self.out.joints,
            materials: Vec::new(),
        };
        let body = urdf_rs::write_to_string(&robot)?;
        Ok(format!(
            "<?xml version=\"1.0\"?>\n<!--\n{}-->\n{body}\n",
            comment_safe(&head)
        ))
    }

    /// The header comment: what the file holds, the links that are not physically
    /// consistent, and the notes.
    fn header(&self) -> String {
        let (m, params) = (self.model, self.params);
        let inconsistent: Vec<&str> = m
            .frames
            .iter()
            .filter(|f| {
                f.inertia.is_some_and(|p0| {
                    params[p0 + 9] > 0.0
                        && pseudo_inertia_min_eigenvalue(&params[p0..p0 + 10]) <= 0.0
                })
            })
            .map(|f| f.name.as_str())
            .collect();
        let mut head = String::new();
        let _ = writeln!(
            head,
            "Generated by dvrk-ident from robot `{}` ({}).",
            m.name, m.source
        );
        let _ = writeln!(
            head,
            "One link per model frame (same names, root = `{}`). Joint `qk` carries model\n\
             coordinate qk; other moving joints mimic one coordinate (value = multiplier*qk +\n\
             offset). A frame driven by several coordinates is a chain of joints about one\n\
             axis, one mimic per coordinate, separated by massless links `<frame>_<qk>`: the\n\
             motions add up exactly. Massless `<qk>_coordinate` links hung from the root carry\n\
             the coordinates when some coordinate has no frame of its own or a frame that\n\
             precedes all its mimics in the tree (parallelograms): then all coordinates, in\n\
             order, ahead of every mimic, every moving frame is a mimic, and the root's frames\n\
             hang from a massless `<root>_frames` link (its joint named to sort after the\n\
             coordinates, as URDF parsers visit joints by name). `<frame>_motion`\n\
             links separate a joint from its fixed post-transform.",
            self.names[0]
        );
        let _ = writeln!(
            head,
            "Inertials: identified mass, centre of mass and inertia about it in the link frame.\n\
             <dynamics>: friction = Coulomb Fc, damping = viscous Fv of one-coordinate joints.\n\
             Limits: the description's limits on one coordinate; effort limits unknown (0)."
        );
        if !inconsistent.is_empty() {
            let _ = writeln!(
                head,
                "Not physically consistent (pseudo-inertia not positive definite): {}.",
                inconsistent.join(", ")
            );
        }
        if self.notes.is_empty() {
            let _ = writeln!(head, "Everything identified is in this file.");
        } else {
            let _ = writeln!(head, "Not expressible in URDF, not in this file:");
            for n in &self.notes {
                let _ = writeln!(head, "  {n}");
            }
        }
        head
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_rpy(r: [f64; 3]) -> Matrix3<f64> {
        *Rotation3::from_euler_angles(r[0], r[1], r[2]).matrix()
    }

    #[test]
    fn rpy_reproduces_rotations_also_at_gimbal_lock() {
        let h = std::f64::consts::FRAC_PI_2;
        let mut cases: Vec<Matrix3<f64>> = vec![
            Matrix3::identity(),
            Transform::rot_x(h).compose(&Transform::rot_z(h)).rotation,
            Transform::rot_x(-h).compose(&Transform::rot_z(-h)).rotation,
            from_rpy([0.3, h, -1.1]),
            from_rpy([0.3, -h, 2.0]),
            from_rpy([0.3, h - 1e-9, -1.1]),
            from_rpy([-2.9, -h + 3e-13, 0.4]),
            from_rpy([std::f64::consts::PI, 0.0, 0.0]),
        ];
        let mut rng = dvrk_test_support::Rng::new(123);
        for _ in 0..200 {
            let mut next = || rng.uniform(-3.5, 3.5);
            cases.push(from_rpy([next(), next() / 2.0, next()]));
        }
        for r in cases {
            let back = from_rpy(rpy_from_rotation(&r));
            let d = (back - r).abs().max();
            assert!(d < 2e-15, "rpy round trip error {d:e} for {r}");
        }
    }

    #[test]
    fn comments_never_contain_double_dashes() {
        assert_eq!(comment_safe("a --- b -- c"), "a - - - b - - c");
    }
}
