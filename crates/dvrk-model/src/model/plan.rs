//! What [`Model::finish`] derives from a model's frames for the per-sample passes: the
//! moving bodies with their joint axes ([`Body`], [`Axis`]), the regressor's link blocks
//! ([`RegressorPlan`]) and the flat list of elements ([`ElementPlan`]).

use nalgebra::{Matrix3, Vector3};

use super::*;
use crate::element::Element;
use crate::expr::Affine;

/// The elements in a flat list, each with its frame's joint value: frames in order and
/// within a frame its forces before its acceleration terms (the order of the sums of the
/// first results, which stay identical to the bit). The per-sample passes run one loop
/// over contiguous memory, with no frame lookup and nothing for frames without elements.
/// A copy of `Frame::elements`, derived in `finish` (and again by `Model::add_stribeck`).
#[derive(Clone, Debug, Default)]
pub(crate) struct ElementPlan {
    /// Every element, with its frame's joint value.
    pub all: Vec<(Affine, Element)>,
    /// The forces alone (not `Element::inertial`), in the same order: forward dynamics
    /// has the acceleration terms in the mass matrix.
    pub forces: Vec<(Affine, Element)>,
    /// The acceleration terms alone (`Element::inertial`), for the mass matrix.
    pub inertial: Vec<Element>,
    /// The hysteresis (Dahl) elements: their frame's joint value, their state's column
    /// and their `σ` (1/rad or 1/m), for [`Model::advance_hysteresis`].
    pub hysteresis: Vec<(Affine, usize, f64)>,
    /// The load friction elements: their `Fl`'s column and their coordinate, for
    /// [`Model::loaded_inverse_dynamics`].
    pub load: Vec<(usize, usize)>,
}

/// Where the link columns of the regressor come from: each link `j` adds `a·S_kᵀ·Y_j`
/// to row `c` for each moving frame `k` on its path to the base and each term `a·q_c`
/// of `k`'s joint value. The regressor runs over the bodies (fixed links merged, see
/// [`Body`]): their kinematics once, then each body's links, each against the joints
/// of the body's path, several joints at a time. The first addition to a (row, link)
/// block writes it instead, and only the entries no link block writes are zeroed: most
/// of a regressor row is link blocks.
#[derive(Clone, Debug, Default)]
pub(crate) struct RegressorPlan {
    /// The bodies that carry links, parents first.
    pub bodies: Vec<PlanBody>,
    /// Per [`PlanBody`], its joints: the bodies (1-based) from itself down to the base,
    /// padded to an even number with 0 (the base: no motion, nothing written), as the
    /// regressor takes them two at a time.
    pub joints: Vec<usize>,
    pub links: Vec<PlanLink>,
    /// See [`PlanLink::columns`].
    pub columns: Vec<(usize, usize)>,
    /// Per link and joint of its body (in the order of [`RegressorPlan::joints`]), the
    /// range of [`RegressorPlan::terms`] it adds to.
    pub targets: Vec<std::ops::Range<usize>>,
    /// `(row, a, write rather than add)` per term `a·q_row` of a joint's value.
    pub terms: Vec<(usize, f64, bool)>,
    /// Per row (coordinate), the first columns of the link blocks written, increasing.
    pub blocks: Vec<Vec<usize>>,
    /// The stretches of the rows that no link block writes, as `(row, first column,
    /// end column)` with `None` for the end of the row (the element columns follow the
    /// link columns, and their number may grow, see [`Model::add_stribeck`]).
    pub gaps: Vec<(usize, usize, Option<usize>)>,
}

#[derive(Clone, Debug)]
pub(crate) struct PlanBody {
    /// Body index (1-based, as in [`Model::bodies`] + 1).
    pub body: usize,
    /// `joints[start..end]` of the plan.
    pub joints: std::ops::Range<usize>,
    /// `links[start..end]` of the plan.
    pub links: std::ops::Range<usize>,
}

/// Links of one body at the same pose in it, whose rows are therefore the same (e.g. a
/// gripper's two fingers): computed once, written to each link's columns.
#[derive(Clone, Debug)]
pub(crate) struct PlanLink {
    /// The links' pose in their body's frame (`None`: the body's own frame).
    pub pose: Option<Transform>,
    /// `columns[start..end]` of the plan: per link, the column of its `L{j}xx` and its
    /// first entry in [`RegressorPlan::targets`] (one per joint of the body).
    pub columns: std::ops::Range<usize>,
}

/// A moving frame with link dynamics in its subtree, and the links rigidly attached to
/// it. Inverse dynamics, gravity, the mass matrix and forward dynamics run over bodies
/// rather than frames: a fixed frame costs nothing per sample (its transform is folded
/// into its child's `pre`, its link into its moving ancestor's inertia), as Pinocchio
/// merges fixed joints, while the regressor keeps a column block per frame.
#[derive(Clone, Debug)]
pub(crate) struct Body {
    /// Frame index (1-based).
    pub frame: usize,
    /// Parent body, 1-based like frames (0: the base, or a frame fixed to it).
    pub parent: usize,
    /// Parent body's frame → this frame's joint frame: the fixed frames between, then
    /// the frame's own `pre`.
    pub pre: Transform,
    /// The links merged into this body: parameter offset of `L{i}xx`, and the link
    /// frame's pose in the body's frame (`None`: the body's own link).
    pub links: Vec<(usize, Option<Transform>)>,
    /// The joint's motion subspace in the body's coordinates.
    pub axis: Axis,
    /// `(c, a)` when the joint value moves with one coordinate only, `s = a·q_c + b`
    /// (every joint of a serial chain): the mass matrix then skips the term loops.
    pub coordinate: Option<(usize, f64)>,
}

impl Body {
    /// `a·x` of the joint value `value` (this body's frame's): its rate for coordinate
    /// rates `x`, the same number as [`Affine::dot`] without its loop for one term.
    #[inline(always)]
    pub fn rate(&self, value: &Affine, x: &[f64]) -> f64 {
        match self.coordinate {
            Some((c, a)) => a * x[c],
            None => value.dot(x),
        }
    }
}

/// A joint's unit motion `(ω, v)` in its frame's coordinates. Most joints turn about or
/// slide along their frame's own z axis (DH frames, URDF joints about z); the mass
/// matrix then reads one component where a general axis takes a dot product.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Axis {
    /// `(z, 0)`
    RevoluteZ,
    /// `(0, z)`
    PrismaticZ,
    General(Vector3<f64>, Vector3<f64>),
}

impl Axis {
    fn new((w, v): (Vector3<f64>, Vector3<f64>)) -> Axis {
        if w == Vector3::z() && v == Vector3::zeros() {
            Axis::RevoluteZ
        } else if w == Vector3::zeros() && v == Vector3::z() {
            Axis::PrismaticZ
        } else {
            Axis::General(w, v)
        }
    }

    /// `Sᵀ·F` of a spatial force `F = [n; f]` (moment, force).
    #[inline(always)]
    pub fn dot(&self, force: &[f64; 6]) -> f64 {
        match self {
            Axis::RevoluteZ => force[2],
            Axis::PrismaticZ => force[5],
            Axis::General(w, v) => {
                w[0] * force[0]
                    + w[1] * force[1]
                    + w[2] * force[2]
                    + v[0] * force[3]
                    + v[1] * force[4]
                    + v[2] * force[5]
            }
        }
    }

    /// `I·S` for barycentric inertia `p` (about this frame's origin): the spatial force
    /// `[L·ω + l × v; m·v + ω × l]` of a unit joint rate.
    #[inline(always)]
    pub fn inertia_times(&self, p: &[f64; 10]) -> [f64; 6] {
        let (h, m) = ([p[6], p[7], p[8]], p[9]);
        match self {
            Axis::RevoluteZ => [p[2], p[4], p[5], -h[1], h[0], 0.0],
            Axis::PrismaticZ => [h[1], -h[0], 0.0, 0.0, 0.0, m],
            Axis::General(w, v) => {
                let l = crate::inertia::sym3(&p[0..6]);
                let hv = Vector3::from(h);
                let n = l * w + hv.cross(v);
                let f = v * m + w.cross(&hv);
                [n[0], n[1], n[2], f[0], f[1], f[2]]
            }
        }
    }
}

impl Model {
    /// Derives the per-sample lookup tables; called by every constructor.
    pub(crate) fn finish(mut self) -> Self {
        let n_frames = self.frames.len();
        self.links = (1..=n_frames)
            .filter(|&i| self.frames[i - 1].inertia.is_some())
            .collect();
        // Frames with a link in their subtree: the links and their ancestors.
        let mut carries = vec![false; n_frames + 1];
        for &j in &self.links {
            let mut k = j;
            while k != 0 && !carries[k] {
                carries[k] = true;
                k = self.frames[k - 1].parent;
            }
        }
        self.active = (1..=n_frames).filter(|&k| carries[k]).collect();
        self.motion = std::iter::once((Vector3::zeros(), Vector3::zeros()))
            .chain(self.frames.iter().map(|f| {
                // Body coordinates of the unit joint twist about/along z of the joint
                // frame: rotate by post⁻¹ and move the reference point to the origin.
                let rt = f.post.rotation.transpose();
                let z = Vector3::z();
                match f.kind {
                    JointKind::Revolute => (rt * z, rt * z.cross(&f.post.translation)),
                    JointKind::Prismatic => (Vector3::zeros(), rt * z),
                    JointKind::Fixed => (Vector3::zeros(), Vector3::zeros()),
                }
            }))
            .collect();
        self.post_identity = std::iter::once((true, true))
            .chain(self.frames.iter().map(|f| {
                (
                    f.post.rotation == Matrix3::identity(),
                    f.post.translation == Vector3::zeros(),
                )
            }))
            .collect();
        self.fixed = std::iter::once(Transform::identity())
            .chain(self.frames.iter().map(|f| {
                let s = f.value.offset;
                let joint = match f.kind {
                    JointKind::Revolute => Transform::rot_z(s),
                    JointKind::Prismatic => Transform::trans(0.0, 0.0, s),
                    JointKind::Fixed => Transform::identity(),
                };
                f.pre.compose(&joint).compose(&f.post)
            }))
            .collect();
        self.element_plan = self.derive_element_plan();
        self.bodies = self.derive_bodies();
        self.regressor_plan = self.derive_regressor_plan();
        self
    }

    /// The elements' plan (see [`ElementPlan`]).
    pub(crate) fn derive_element_plan(&self) -> ElementPlan {
        let mut plan = ElementPlan::default();
        for f in &self.frames {
            // Known forces are no part of `H·π` (`Model::add_known_forces` adds them).
            let forces = f.elements.iter().filter(|e| !e.inertial() && !e.is_known());
            let inertial = f.elements.iter().filter(|e| e.inertial());
            plan.all.extend(
                forces
                    .clone()
                    .chain(inertial.clone())
                    .map(|e| (f.value.clone(), e.clone())),
            );
            plan.forces
                .extend(forces.clone().map(|e| (f.value.clone(), e.clone())));
            plan.inertial.extend(inertial.cloned());
            plan.hysteresis
                .extend(f.elements.iter().filter_map(|e| match e {
                    Element::Dahl(d) => Some((f.value.clone(), d.param, d.sigma)),
                    _ => None,
                }));
            plan.load.extend(f.elements.iter().filter_map(|e| match e {
                Element::LoadFriction(l) => Some((l.param, l.coordinate)),
                _ => None,
            }));
        }
        plan
    }

    /// The regressor's plan (see [`RegressorPlan`]), in the order the regressor adds.
    fn derive_regressor_plan(&self) -> RegressorPlan {
        let mut written = std::collections::BTreeSet::new();
        let mut plan = RegressorPlan::default();
        for (k, body) in self.bodies.iter().enumerate() {
            if body.links.is_empty() {
                continue;
            }
            let j0 = plan.joints.len();
            let mut b = k + 1;
            while b != 0 {
                plan.joints.push(b);
                b = self.bodies[b - 1].parent;
            }
            if (plan.joints.len() - j0) % 2 == 1 {
                plan.joints.push(0);
            }
            let l0 = plan.links.len();
            let mut poses: Vec<Option<Transform>> = Vec::new();
            for (_, pose) in &body.links {
                if !poses.contains(pose) {
                    poses.push(*pose);
                }
            }
            for pose in poses {
                let c0 = plan.columns.len();
                for (col0, _) in body.links.iter().filter(|(_, x)| *x == pose) {
                    plan.columns.push((*col0, plan.targets.len()));
                    for &b in &plan.joints[j0..] {
                        let t0 = plan.terms.len();
                        if b != 0 {
                            let value = &self.frames[self.bodies[b - 1].frame - 1].value;
                            for &(c, a) in &value.terms {
                                plan.terms.push((c, a, written.insert((c, *col0))));
                            }
                        }
                        plan.targets.push(t0..plan.terms.len());
                    }
                }
                plan.links.push(PlanLink {
                    pose,
                    columns: c0..plan.columns.len(),
                });
            }
            plan.bodies.push(PlanBody {
                body: k + 1,
                joints: j0..plan.joints.len(),
                links: l0..plan.links.len(),
            });
        }
        plan.blocks = vec![Vec::new(); self.dof()];
        for (c, col0) in written {
            plan.blocks[c].push(col0);
        }
        for (r, blocks) in plan.blocks.iter().enumerate() {
            let mut from = 0;
            for &c in blocks {
                if c > from {
                    plan.gaps.push((r, from, Some(c)));
                }
                from = c + 10;
            }
            plan.gaps.push((r, from, None));
        }
        plan
    }

    /// The bodies of the tree (see [`Body`]), from `active` and `fixed`.
    fn derive_bodies(&self) -> Vec<Body> {
        let moving = |f: usize| f != 0 && self.frames[f - 1].kind != JointKind::Fixed;
        // Nearest moving ancestor-or-self of frame `f` (0: none) and the pose of `f` in
        // its frame.
        let anchor = |mut f: usize| {
            let mut x = Transform::identity();
            while f != 0 && !moving(f) {
                x = self.fixed[f].compose(&x);
                f = self.frames[f - 1].parent;
            }
            (f, x)
        };
        let mut body_of = vec![0usize; self.frames.len() + 1];
        let mut bodies = Vec::new();
        for &fi in self.active.iter().filter(|&&f| moving(f)) {
            let frame = &self.frames[fi - 1];
            let (p, x) = anchor(frame.parent);
            bodies.push(Body {
                frame: fi,
                parent: body_of[p],
                pre: x.compose(&frame.pre),
                links: Vec::new(),
                axis: Axis::new(self.motion[fi]),
                coordinate: match frame.value.terms.as_slice() {
                    &[term] => Some(term),
                    _ => None,
                },
            });
            body_of[fi] = bodies.len();
        }
        for &j in &self.links {
            let offset = self.frames[j - 1].inertia.expect("link frame");
            let (f, x) = anchor(j);
            // A link fixed to the base exerts nothing on the coordinates.
            if f != 0 {
                let pose = (f != j).then_some(x);
                bodies[body_of[f] - 1].links.push((offset, pose));
            }
        }
        bodies
    }
}
