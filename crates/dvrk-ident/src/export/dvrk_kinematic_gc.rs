//! The dVRK controller's kinematic gravity-compensation file (the physical-DH JSON its
//! `kinematic_gc` configuration key names) for the ECM, the PSM Si and the ECM Si, from
//! an identified model, so that the controller compensates the identified gravity instead
//! of the CAD/hand masses it ships ("suitable for gravity compensation ('statics') but
//! should not be used to actual dynamic compensation").
//!
//! What the controller does with the file (jhu-dvrk/sawIntuitiveResearchKit,
//! `mtsIntuitiveResearchKitPSM.cpp` `GravityCompensationPSM`,
//! `mtsIntuitiveResearchKitECM.cpp` `GravityCompensationECM`,
//! `mtsIntuitiveResearchKitArm.cpp`; jhu-cisst/cisst `robManipulator::LoadRobot`,
//! `CCG_MDH`):
//!
//! - the controller's file ignores the PSM's instrument (psm_si_tool: its coordinates
//!   after the arm's three, which move no link with mass), whose efforts it leaves at 0;
//! - `LoadRobot` reads `DH.joints` (or `links`): per link the modified-DH `alpha`, `A`,
//!   `theta`, `D`, `type`, `offset`, and a point mass `mass` at `cx cy cz` (link frame);
//!   other keys are ignored. The PSM needs 7 links, the ECM 6 (Si) or 4 (Classic);
//! - each control cycle, the arm's joints `j` become the links' joint values (PSM Si
//!   `[j1, 0, j2, −j2, j2, j3/2, j3/2]`, ECM Si `[j1, 0, j2, −j2, j2, j3]`, Classic ECM `j`
//!   itself), `CCG_MDH` computes each link's holding effort `e` for the "up" vector
//!   `(0, 9.81·sin p, 9.81·cos p)` of the configured `mounting_pitch` `p`, and the arm's
//!   efforts are PSM Si `[e0, e2 − e3 + e4, e6]`, ECM Si `[e0, e2 − e3 + e4, e5]` (roll 0),
//!   Classic ECM `e`;
//! - the ECM's endoscope: the controller overwrites the mass of the insertion link
//!   (link 6 of the Si file, link 3 of the Classic one) with its endoscope type's mass
//!   (`mtsIntuitiveResearchKit.h`), keeping the file's centre of mass.
//!
//! The effort maps are not the transposes of the position maps (the PSM Si's first
//! insertion stage, moving at `j3/2`, does not weigh on the insertion effort), so the
//! file's masses are not simply the identified links'. [`dvrk_kinematic_gc`] fits them:
//! the controller's efforts are linear in each link's mass `m` and first moment `m·c`;
//! over a regular grid of the joint ranges, it solves in least squares for the 4 numbers
//! per link (the endoscope link's mass fixed at its type's), closest to the identified
//! links' own values, so that the controller's computation reproduces the identified
//! model's gravity torque at the result's gravity (mounting pitch). Where the file cannot
//! represent it exactly (the ECM Si insertion with another mass than the endoscope type's,
//! a roll centre of mass off the ECM Si's axis, which the controller does not compensate)
//! the residual is reported per joint.

use dvrk_model::{JointKind, Model, Workspace};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::IdentError;
use dvrk_logs::hint::Hint;

/// The dVRK's endoscope types (`mtsIntuitiveResearchKitEndoscopeTypes.cdg`, the ECM
/// configuration's `endoscope` value) and the mass (kg) the controller puts on the ECM's
/// insertion link for each (`mtsIntuitiveResearchKit.h`, `ECM::ClassicSDMass` 1.5,
/// `ClassicHDMass` 2.5, `SiHDMass` 1.8, `CustomMass` 0.8; anything else `EmptyMass` 0.1).
pub const ENDOSCOPES: [(&str, f64); 13] = [
    ("NONE", 0.1),
    ("Classic_SD_STRAIGHT", 1.5),
    ("Classic_SD_UP", 1.5),
    ("Classic_SD_DOWN", 1.5),
    ("Classic_HD_STRAIGHT", 2.5),
    ("Classic_HD_UP", 2.5),
    ("Classic_HD_DOWN", 2.5),
    ("Si_HD_STRAIGHT", 1.8),
    ("Si_HD_UP", 1.8),
    ("Si_HD_DOWN", 1.8),
    ("Custom_STRAIGHT", 0.8),
    ("Custom_UP", 0.8),
    ("Custom_DOWN", 0.8),
];

/// Grid points per joint of the fit: 9³ = 729 PSM Si poses, 9⁴ = 6561 ECM poses.
pub const POINTS: usize = 9;

/// One arm the controller has a kinematic gravity compensation for.
struct Arm {
    /// The built-in descriptions of the arm: the arm alone, then the arm with its
    /// instrument (whose extra coordinates the controller's file ignores).
    robots: &'static [&'static str],
    /// The file's links, in order: `setup` (the links an arm shares with others), then
    /// `links`.
    setup: &'static [GcFrame],
    links: &'static [GcFrame],
    /// Each arm joint's effort as `(link, coefficient)` pairs (the effort map; empty: the
    /// controller sends 0).
    effort: &'static [&'static [(usize, f64)]],
    /// The link whose mass the controller sets from the endoscope type.
    endoscope_link: Option<usize>,
    /// The file the dVRK ships for the arm.
    shipped: &'static str,
}

impl Arm {
    fn links(&self) -> impl Iterator<Item = &GcFrame> {
        self.setup.iter().chain(self.links)
    }
}

/// A link of the file: the description's frame, the name the dVRK's file gives it, and
/// its joint value as `(coordinate, coefficient)` pairs (the controller's position map;
/// empty: 0, a passive link).
struct GcFrame(&'static str, &'static str, &'static [(usize, f64)]);

/// The Si arms' yaw and their pitch parallelogram, moved by the yaw (coordinate 0) and
/// the pitch (coordinate 1): the first five links of the PSM Si's file and the ECM Si's.
const SI_SETUP: [GcFrame; 5] = [
    GcFrame("yaw", "yaw", &[(0, 1.0)]),
    GcFrame("intermediate_yaw", "intermediate yaw", &[]),
    GcFrame("pitch1", "pitch1", &[(1, 1.0)]),
    GcFrame("pitch2", "pitch2", &[(1, -1.0)]),
    GcFrame("pitch3", "pitch3", &[(1, 1.0)]),
];

/// The Si arms' yaw and pitch efforts: the pitch's is the parallelogram's three links'.
const SI_YAW_EFFORT: &[(usize, f64)] = &[(0, 1.0)];
const SI_PITCH_EFFORT: &[(usize, f64)] = &[(2, 1.0), (3, -1.0), (4, 1.0)];

const ARMS: [Arm; 3] = [
    Arm {
        robots: &["psm_si", "psm_si_tool"],
        setup: &SI_SETUP,
        links: &[
            GcFrame("insertion1", "insertion1", &[(2, 0.5)]),
            GcFrame("insertion2", "insertion2", &[(2, 0.5)]),
        ],
        effort: &[SI_YAW_EFFORT, SI_PITCH_EFFORT, &[(6, 1.0)]],
        endoscope_link: None,
        shipped: "kinematic/PSM_Si_physical.json",
    },
    Arm {
        robots: &["ecm_si"],
        setup: &SI_SETUP,
        links: &[GcFrame("insertion", "insertion", &[(2, 1.0)])],
        effort: &[SI_YAW_EFFORT, SI_PITCH_EFFORT, &[(5, 1.0)], &[]],
        endoscope_link: Some(5),
        shipped: "kinematic/ECM_Si_physical.json",
    },
    Arm {
        robots: &["ecm"],
        setup: &[],
        links: &[
            GcFrame("yaw", "yaw", &[(0, 1.0)]),
            GcFrame("pitch", "pitch", &[(1, 1.0)]),
            GcFrame("insertion", "insertion", &[(2, 1.0)]),
            GcFrame("roll", "roll", &[(3, 1.0)]),
        ],
        effort: &[&[(0, 1.0)], &[(1, 1.0)], &[(2, 1.0)], &[(3, 1.0)]],
        endoscope_link: Some(2),
        shipped: "kinematic/ECM.json",
    },
];

/// One link of the file: modified DH (rad, m) and a point mass.
#[derive(Clone, Debug, PartialEq)]
pub struct GcLink {
    /// The name the dVRK's own file gives the link.
    pub name: String,
    /// `alpha` (rad).
    pub alpha: f64,
    /// `A` (m).
    pub a: f64,
    /// `theta` (rad): the link's angle at joint value 0.
    pub theta: f64,
    /// `D` (m).
    pub d: f64,
    /// A prismatic link (else revolute).
    pub prismatic: bool,
    /// Passive: a link the controller always sets to 0.
    pub passive: bool,
    /// `mass` (kg).
    pub mass: f64,
    /// `cx cy cz` (m, link frame).
    pub com: [f64; 3],
}

/// A kinematic gravity-compensation file and how well it represents the model.
#[derive(Clone, Debug)]
pub struct KinematicGc {
    /// The robot the model was loaded as (`psm_si`, `ecm_si`, `ecm`).
    pub robot: String,
    /// The file's links, in order.
    pub links: Vec<GcLink>,
    /// The endoscope type and its mass (kg), for the ECMs.
    pub endoscope: Option<(String, f64)>,
    /// Gravity of the fit in the base frame (m/s²): the result's.
    pub gravity: [f64; 3],
    /// The arm's measured joints (the controller's joints).
    pub joints: Vec<String>,
    /// Largest difference over the grid between the controller's effort from the file
    /// and the model's gravity torque, per joint (N·m or N).
    pub residual_max: Vec<f64>,
    /// Its RMS over the grid, per joint.
    pub residual_rms: Vec<f64>,
    /// Largest gravity torque of the model over the grid, per joint (the scale).
    pub torque_max: Vec<f64>,
    /// Poses of the grid.
    pub configurations: usize,
    /// The file the dVRK ships for the arm, which this one replaces.
    pub shipped: String,
}

impl KinematicGc {
    /// The controller's mounting pitch (rad) of this file's gravity, as its configuration
    /// writes it (`atan2(−g_y, −g_z)`).
    pub fn mounting_pitch_rad(&self) -> f64 {
        (-self.gravity[1]).atan2(-self.gravity[2])
    }

    /// The file: `DH` as `LoadRobot` reads it, our provenance and residuals under
    /// `dvrk_ident` (ignored by the controller).
    pub fn to_json(&self) -> serde_json::Value {
        let joints: Vec<serde_json::Value> = self
            .links
            .iter()
            .map(|l| {
                serde_json::json!({
                    "name": l.name,
                    "alpha": l.alpha, "A": l.a, "theta": l.theta, "D": l.d,
                    "type": if l.prismatic { "prismatic" } else { "revolute" },
                    "mode": if l.passive { "passive" } else { "active" },
                    "mass": l.mass, "cx": l.com[0], "cy": l.com[1], "cz": l.com[2],
                })
            })
            .collect();
        serde_json::json!({
            "DH": { "convention": "modified", "joints": joints },
            "dvrk_ident": {
                "robot": self.robot,
                "replaces": self.shipped,
                "endoscope": self.endoscope.as_ref().map(|(t, m)| serde_json::json!({"type": t, "mass_kg": m})),
                "gravity_m_s2": self.gravity,
                "mounting_pitch_rad": self.mounting_pitch_rad(),
                "joints": self.joints,
                "grid_configurations": self.configurations,
                "residual_max": self.residual_max,
                "residual_rms": self.residual_rms,
                "torque_max": self.torque_max,
                "install": self.install(),
            }
        })
    }

    /// How to install the file in the controller.
    pub fn install(&self) -> String {
        let mut s = format!(
            "copy the file beside the arm's configuration and set in that configuration \
             \"kinematic_gc\": \"<this file's name>\" (it replaces {}) and \"mounting_pitch\": {:.6} \
             (rad, the pitch the model was fitted at)",
            self.shipped,
            self.mounting_pitch_rad()
        );
        if let Some((t, _)) = &self.endoscope {
            s += &format!(", with \"endoscope\": \"{t}\" (its mass is the one fitted around)");
        }
        s
    }

    /// A per-joint residual table and the installation, for the command line.
    pub fn summary(&self) -> String {
        let mut out = format!(
            "dVRK kinematic gravity compensation ({} links): {} poses\n\
             joint          residual max      rms   (model's largest torque)\n",
            self.links.len(),
            self.configurations
        );
        for (j, name) in self.joints.iter().enumerate() {
            out += &format!(
                "  {:<12} {:>12.2e} {:>10.2e}   ({:.3})\n",
                name, self.residual_max[j], self.residual_rms[j], self.torque_max[j]
            );
        }
        let negative: Vec<&str> = self
            .links
            .iter()
            .filter(|l| l.mass < 0.0)
            .map(|l| l.name.as_str())
            .collect();
        if !negative.is_empty() {
            out += &format!(
                "note: link(s) {} have a negative mass: the controller's computation is \
                 linear in the masses, so its efforts are the ones above\n",
                negative.join(", ")
            );
        }
        out += &format!("install: {}\n", self.install());
        out
    }
}

fn mismatch(model: &Model, message: String) -> IdentError {
    IdentError::Mismatch {
        source_name: format!("robot `{}`", model.name),
        message,
    }
}

/// Why the file cannot be made, where the message suggests a setting
/// ([`IdentError::Unsuited`], spelled by each front end).
#[derive(Debug, thiserror::Error)]
enum Unsuited {
    /// A robot the file is not for.
    #[error("the dVRK's kinematic gravity-compensation file is for psm_si (psm_si_tool), ecm_si and ecm{}", instead(name))]
    Robot { name: String },
    /// A link with a first moment and no mass (kg·m).
    #[error("link {link}: a first moment ({first:.3e} kg·m) without mass, which a point mass cannot hold (a least-squares fit's representative parameters? fit with {})", Hint::MethodSdp)]
    Massless { link: String, first: f64 },
    /// A link whose centre of mass (m) is far off the arm, for its mass (kg).
    #[error("link {link}: centre of mass {com:?} m for a mass of {mass:.3e} kg, not a place on the arm (fit with {} for physically consistent links)", Hint::MethodSdp)]
    FarCom {
        link: String,
        com: [f64; 3],
        mass: f64,
    },
}

/// What serves the robot `name` instead of the file, after `; ` (empty: nothing).
fn instead(name: &str) -> String {
    match name {
        "mtm" => format!(
            "; the MTM's gravity compensation is its own file: {}",
            Hint::DvrkGc
        ),
        "psm" | "psm_simplified" => format!(
            "; the dVRK has no kinematic gravity compensation for the Classic PSM (its \
             controller loads none; only the PSM Si's): {} for other controllers",
            Hint::OtherExports
        ),
        _ => String::new(),
    }
}

fn unsuited(model: &Model, reason: Unsuited) -> IdentError {
    IdentError::Unsuited {
        source_name: format!("robot `{}`", model.name),
        reason: Box::new(reason),
    }
}

/// The file for `model` (with its gravity: the result's mounting pitch) and parameters
/// `params`; `endoscope`: the ECM's endoscope type (required for the ECMs, refused for
/// the PSM).
pub fn dvrk_kinematic_gc(
    model: &Model,
    params: &[f64],
    endoscope: Option<&str>,
) -> Result<KinematicGc, IdentError> {
    let arm = ARMS
        .iter()
        .find(|a| a.robots.contains(&model.name.as_str()))
        .ok_or_else(|| {
            unsuited(
                model,
                Unsuited::Robot {
                    name: model.name.clone(),
                },
            )
        })?;
    if params.len() != model.n_params() || params.iter().any(|p| !p.is_finite()) {
        return Err(mismatch(
            model,
            format!(
                "expected {} finite parameters, got {}",
                model.n_params(),
                params.len()
            ),
        ));
    }
    let endoscope =
        match (arm.endoscope_link, endoscope) {
            (Some(_), None) => {
                return Err(IdentError::Setting {
                    name: crate::error::SettingName::Argument("endoscope"),
                    message: format!(
                        "the ECM's controller sets its insertion link's mass from the endoscope \
                     type: give the one the arm carries ({})",
                        endoscope_names()
                    ),
                })
            }
            (Some(_), Some(t)) => {
                let (name, mass) = ENDOSCOPES.iter().find(|(n, _)| *n == t).ok_or_else(|| {
                    IdentError::Setting {
                        name: crate::error::SettingName::Argument("endoscope"),
                        message: format!(
                            "unknown endoscope type {t:?}: expected {}",
                            endoscope_names()
                        ),
                    }
                })?;
                Some((name.to_string(), *mass))
            }
            (None, Some(_)) => {
                return Err(IdentError::Setting {
                    name: crate::error::SettingName::Argument("endoscope"),
                    message: format!("robot {} carries no endoscope", model.name),
                })
            }
            (None, None) => None,
        };
    // The controller's file holds the links' gravity: only rigid bodies, as the MTM's
    // gravity compensation and a URDF (a negative mass would push the arm the wrong way).
    model.check_rigid_bodies(params)?;
    let frames = check_model(model, arm)?;
    let geometry = dh_at_zero(model, &frames)?;
    let ranges: Vec<[f64; 2]> = model
        .measured
        .ranges
        .iter()
        .map(|r| r.ok_or_else(|| mismatch(model, "needs the measured joints' ranges".into())))
        .collect::<Result<_, _>>()?;
    fit(model, params, arm, &frames, geometry, &ranges, endoscope)
}

fn endoscope_names() -> String {
    ENDOSCOPES
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The model's frame of each link, after checking that the model is the controller's
/// arm: its first coordinates are the arm's measured joints, each link's joint value
/// moves as the controller's position map, and any further coordinate (an instrument's,
/// which the controller's gravity compensation leaves out) is coupled to none of them and
/// moves no link with inertia, so that the arm's gravity does not depend on it.
fn check_model(model: &Model, arm: &Arm) -> Result<Vec<usize>, IdentError> {
    let (n, na) = (model.dof(), arm.effort.len());
    let m = &model.measured.coupling;
    // Rows and columns of the arm's joints are the identity's; the instrument's block is
    // free (psm_si_tool: its actuator-to-joint coupling).
    let arm_joints_are_coordinates = n >= na
        && (0..n).all(|r| {
            (0..n).all(|c| (r >= na && c >= na) || m[(r, c)] == f64::from(u8::from(r == c)))
        });
    if !arm_joints_are_coordinates {
        return Err(mismatch(
            model,
            format!(
                "expected its first {na} coordinates to be the measured joints, as the built-in {}",
                arm.robots.join(" and ")
            ),
        ));
    }
    // Every frame whose pose depends on an extra coordinate must carry no link.
    let mut moved_by_extra = vec![false; model.frames.len() + 1];
    for i in 1..=model.frames.len() {
        let f = model.frame(i);
        moved_by_extra[i] = moved_by_extra[f.parent] || f.value.terms.iter().any(|&(k, _)| k >= na);
        if moved_by_extra[i] && f.inertia.is_some() {
            return Err(mismatch(
                model,
                format!(
                    "frame {} carries a link moved by coordinate(s) beyond the arm's {na}, \
                     whose gravity the controller's file cannot hold",
                    f.name
                ),
            ));
        }
    }
    let names = model.frame_names();
    let mut frames = Vec::new();
    for GcFrame(frame, _, map) in arm.links() {
        let i = names
            .iter()
            .position(|n| n == frame)
            .filter(|&i| i > 0)
            .ok_or_else(|| {
                mismatch(
                    model,
                    format!("no frame {frame}, which the controller's file has"),
                )
            })?;
        let f = model.frame(i);
        let mut expected: Vec<(usize, f64)> = map.to_vec();
        expected.sort_by_key(|t| t.0);
        let moving = f.kind != JointKind::Fixed;
        let same = if moving {
            f.value.terms == expected
        } else {
            expected.is_empty()
        };
        if !same {
            return Err(mismatch(
                model,
                format!(
                    "frame {frame} does not move as the controller's link (joint value {:?}, the controller's {:?})",
                    f.value.terms, expected
                ),
            ));
        }
        frames.push(i);
    }
    Ok(frames)
}

/// Each link's modified DH at joint value 0, read from the model's parent → frame
/// transform at q = 0 (`RotX(α)·TransX(a)·RotZ(θ)·TransZ(d)`), checked to rebuild it.
fn dh_at_zero(model: &Model, frames: &[usize]) -> Result<Vec<GcLink>, IdentError> {
    let zero = vec![0.0; model.dof()];
    let poses = model.frame_poses(&zero);
    let mut links = Vec::with_capacity(frames.len());
    for (k, &i) in frames.iter().enumerate() {
        // The file's links are a chain: link k's parent is link k−1 (the base for 0).
        let parent = if k == 0 { 0 } else { frames[k - 1] };
        let f = model.frame(i);
        if f.parent != parent {
            return Err(mismatch(
                model,
                format!(
                    "frame {} is not the child of the controller's previous link",
                    f.name
                ),
            ));
        }
        let (pp, pi) = (&poses[parent], &poses[i]);
        let r: Matrix3<f64> = pp.rotation.transpose() * pi.rotation;
        let t: Vector3<f64> = pp.rotation.transpose() * (pi.translation - pp.translation);
        let alpha = (-r[(1, 2)]).atan2(r[(2, 2)]);
        let theta = (-r[(0, 1)]).atan2(r[(0, 0)]);
        let d = -t.y * alpha.sin() + t.z * alpha.cos();
        let a = t.x;
        // The value at q = 0 is in theta (revolute) or d (prismatic): the file's
        // constant part, the controller adds the mapped joint value.
        let rebuilt = {
            let (ca, sa, ct, st) = (alpha.cos(), alpha.sin(), theta.cos(), theta.sin());
            let rr = Matrix3::new(ct, -st, 0.0, st * ca, ct * ca, -sa, st * sa, ct * sa, ca);
            let tt = Vector3::new(a, -sa * d, ca * d);
            (rr - r).abs().max().max((tt - t).abs().max())
        };
        if rebuilt > 1e-9 {
            return Err(mismatch(
                model,
                format!(
                    "frame {} is not one modified-DH transform from its parent",
                    f.name
                ),
            ));
        }
        // The base of the file: the first link's origin may sit on its axis away from
        // ours (the Si descriptions' base is the RCM, the file's the yaw axis' top);
        // gravity does not see a translation of the base, so the file starts at its own.
        let d = if k == 0 { 0.0 } else { d };
        links.push(GcLink {
            name: String::new(),
            alpha,
            a,
            theta,
            d,
            prismatic: f.kind == JointKind::Prismatic,
            passive: f.kind == JointKind::Fixed,
            mass: 0.0,
            com: [0.0; 3],
        });
    }
    Ok(links)
}

/// The controller's efforts per unit of each link's `(m, m·cx, m·cy, m·cz)` at pose `q`:
/// rows the arm's joints, 4 columns per link. `up`: the up vector in the base frame.
fn columns(
    model: &Model,
    arm: &Arm,
    frames: &[usize],
    q: &[f64],
    up: &Vector3<f64>,
) -> DMatrix<f64> {
    let poses = model.frame_poses(q);
    let n = frames.len();
    // Each link's effort e_k per unit of link i's numbers.
    let mut e = DMatrix::zeros(n, 4 * n);
    for (k, &fk) in frames.iter().enumerate() {
        let (pk, zk) = (
            poses[fk].translation,
            poses[fk].rotation.column(2).into_owned(),
        );
        let prismatic = model.frame(fk).kind == JointKind::Prismatic;
        for (i, &fi) in frames.iter().enumerate().skip(k) {
            if prismatic {
                e[(k, 4 * i)] = zk.dot(up);
                continue;
            }
            let pi = poses[fi].translation;
            e[(k, 4 * i)] = zk.dot(&(pi - pk).cross(up));
            for j in 0..3 {
                let axis = poses[fi].rotation.column(j).into_owned();
                e[(k, 4 * i + 1 + j)] = zk.dot(&axis.cross(up));
            }
        }
    }
    let mut y = DMatrix::zeros(arm.effort.len(), 4 * n);
    for (row, combination) in arm.effort.iter().enumerate() {
        for &(link, c) in combination.iter() {
            let r = e.row(link) * c;
            let mut target = y.row_mut(row);
            target += r;
        }
    }
    y
}

#[allow(clippy::too_many_arguments)]
fn fit(
    model: &Model,
    params: &[f64],
    arm: &Arm,
    frames: &[usize],
    mut links: Vec<GcLink>,
    ranges: &[[f64; 2]],
    endoscope: Option<(String, f64)>,
) -> Result<KinematicGc, IdentError> {
    // The controller's joints: the model's first n coordinates (check_model); the
    // instrument's, if any, at 0 (they move no link with inertia).
    let n = arm.effort.len();
    let nl = frames.len();
    let up = -model.gravity;
    // The identified links' own numbers, the solution the fit stays closest to.
    let mut w0 = DVector::zeros(4 * nl);
    for (i, &f) in frames.iter().enumerate() {
        if let Some(p0) = model.frame(f).inertia {
            w0[4 * i] = params[p0 + 9];
            for j in 0..3 {
                w0[4 * i + 1 + j] = params[p0 + 6 + j];
            }
        }
    }
    // Unknowns: every link's 4 numbers but the passive links' (no mass in the model)
    // and the endoscope link's mass (the controller's).
    let fixed_mass = arm.endoscope_link.zip(endoscope.as_ref().map(|e| e.1));
    let free: Vec<usize> = (0..4 * nl)
        .filter(|&c| {
            let link = c / 4;
            model.frame(frames[link]).inertia.is_some()
                && !(c % 4 == 0 && fixed_mass.is_some_and(|(l, _)| l == link))
        })
        .collect();
    let configurations = POINTS.pow(n as u32);
    let rows = configurations * n;
    let mut y = DMatrix::zeros(rows, free.len());
    let mut rhs = DVector::zeros(rows);
    let mut target = DVector::zeros(rows);
    let mut ws = Workspace::new(model);
    let mut tau = vec![0.0; model.dof()];
    for c in 0..configurations {
        let mut q = grid_point(&ranges[..n], c);
        q.resize(model.dof(), 0.0);
        model.gravity_torque(&mut ws, params, &q, &mut tau);
        let full = columns(model, arm, frames, &q, &up);
        for j in 0..n {
            let r = c * n + j;
            target[r] = tau[j];
            let mut fixed = 0.0;
            if let Some((l, m)) = fixed_mass {
                fixed = full[(j, 4 * l)] * m;
            }
            rhs[r] = tau[j] - fixed;
            for (k, &col) in free.iter().enumerate() {
                y[(r, k)] = full[(j, col)];
            }
        }
    }
    // Least squares closest to the identified numbers: w = w0 + pinv(Y)·(rhs − Y·w0).
    // A link whose fitted mass vanishes (the PSM Si's first insertion stage, which the
    // controller leaves out of the insertion effort) cannot hold a first moment: its
    // columns are dropped and the rest solved again (its first moment is then another
    // link's, e.g. the pitch link it slides on).
    let mut keep: Vec<usize> = (0..free.len()).collect();
    let (w_free, fitted) = loop {
        let yk = DMatrix::from_fn(rows, keep.len(), |r, k| y[(r, keep[k])]);
        let w0k = DVector::from_iterator(keep.len(), keep.iter().map(|&k| w0[free[k]]));
        let svd = yk.clone().svd(true, true);
        let tol = 1e-10 * svd.singular_values.max();
        let correction = svd
            .solve(&(&rhs - &yk * &w0k), tol)
            .map_err(|e| mismatch(model, format!("least squares: {e}")))?;
        let wk = w0k + correction;
        let mut w_free = DVector::zeros(free.len());
        for (k, &c) in keep.iter().enumerate() {
            w_free[c] = wk[k];
        }
        let massless: Vec<usize> = (0..nl)
            .filter(|&link| {
                let col = |j: usize| free.iter().position(|&c| c == 4 * link + j);
                let m = col(0).map_or(1.0, |k| w_free[k]);
                let first = (1..4)
                    .any(|j| col(j).is_some_and(|k| keep.contains(&k) && w_free[k].abs() > 1e-12));
                m.abs() < 1e-9 && first
            })
            .collect();
        if massless.is_empty() {
            break (w_free, &yk * &wk);
        }
        keep.retain(|&k| !massless.contains(&(free[k] / 4)));
    };
    let mut w = DVector::zeros(4 * nl);
    for (k, &c) in free.iter().enumerate() {
        w[c] = w_free[k];
    }
    if let Some((l, m)) = fixed_mass {
        w[4 * l] = m;
    }
    // Residuals of the controller's effort against the model's torque.
    let mut residual_max = vec![0.0f64; n];
    let mut sum2 = vec![0.0f64; n];
    let mut torque_max = vec![0.0f64; n];
    for r in 0..rows {
        let j = r % n;
        let e = (fitted[r] - rhs[r]).abs();
        residual_max[j] = residual_max[j].max(e);
        sum2[j] += e * e;
        torque_max[j] = torque_max[j].max(target[r].abs());
    }
    let residual_rms: Vec<f64> = sum2
        .iter()
        .map(|s| (s / configurations as f64).sqrt())
        .collect();
    for (i, (link, frame)) in links.iter_mut().zip(arm.links()).enumerate() {
        link.name = frame.1.to_string();
        let m = w[4 * i];
        let l = [w[4 * i + 1], w[4 * i + 2], w[4 * i + 3]];
        let first = l.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if m.abs() < 1e-12 {
            if first > 1e-9 {
                return Err(unsuited(
                    model,
                    Unsuited::Massless {
                        link: link.name.clone(),
                        first,
                    },
                ));
            }
            link.mass = 0.0;
            continue;
        }
        link.mass = m;
        link.com = [l[0] / m, l[1] / m, l[2] / m];
        if link.com.iter().any(|c| c.abs() > 10.0) {
            return Err(unsuited(
                model,
                Unsuited::FarCom {
                    link: link.name.clone(),
                    com: link.com,
                    mass: m,
                },
            ));
        }
    }
    Ok(KinematicGc {
        robot: model.name.clone(),
        links,
        endoscope,
        gravity: [model.gravity.x, model.gravity.y, model.gravity.z],
        joints: model.measured.joints[..n].to_vec(),
        residual_max,
        residual_rms,
        torque_max,
        configurations,
        shipped: arm.shipped.to_string(),
    })
}

/// Pose `index` of the regular grid of `POINTS` per joint over `ranges`.
fn grid_point(ranges: &[[f64; 2]], mut index: usize) -> Vec<f64> {
    ranges
        .iter()
        .map(|[lo, hi]| {
            let k = index % POINTS;
            index /= POINTS;
            lo + (hi - lo) * k as f64 / (POINTS - 1) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests;
