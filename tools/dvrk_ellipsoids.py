#!/usr/bin/env python3
"""Bounding ellipsoids of the built-in dVRK arms' links from the dVRK's own meshes.

Recomputes the `ellipsoid = {...}` entries of robots/mtm.toml, robots/psm.toml
(pitch_front only: the others' reasons are in psm.toml) and robots/ecm.toml. Not run
in CI:

    fetch jhu-dvrk/dvrk_model (any checkout with urdf/ and meshes/), then
    python tools/dvrk_ellipsoids.py /path/to/dvrk_model [--commit SHA] --arm mtm|psm|ecm

(the ECM's STL meshes are Git LFS pointers from dvrk_model 70998aa on: give
--commit 736b90fc3e5fd5e170170425687a3ec22c715838, the commit before, or an LFS
checkout). Needs numpy, pinocchio (`pin`) and the dvrk_ident Python module (for our
frames).

Method:
1. The URDF: the xacro macros of urdf/Classic/MTM.urdf.xacro (`mtm` and both
   platforms, right and left), urdf/Classic/PSM_base.urdf.xacro (`base`) or
   urdf/Classic/ECM_base.urdf.xacro (`ecm_base`, with the default endoscope of
   urdf/common/endoscopes/Classic_SD_straight.urdf.xacro), expanded here (only `${...}`
   expressions of PI and the macro parameters occur), loaded with Pinocchio.
2. Each link's mesh (the MTM's and the ECM's <collision>, the PSM's <visual>; Collada
   positions or binary STL, metres; the instanced node's transform is the identity in
   every file used) placed by its origin in the URDF link frame.
3. The URDF link frame in our (modified DH) frame: the constant transform
   X = T_ours(q)^-1 * T_b^-1 * T_urdf(q), with T_b (our base in the URDF world) from
   a point registration of corresponding joint points over random configurations
   (MTM), the identity (PSM: both at the remote centre of motion) or a given rotation
   (ECM); the URDF joints are the dVRK's measured joints (coupling * q; the ECM's with
   the signs of its entry), mimic joints follow theirs. X must be the same at every
   configuration: the script checks it (the FK verification, printed per link) and
   stops if not.
4. The ellipsoid: Khachiyan's minimum-volume enclosing ellipsoid of the mesh vertices
   in our frame (tolerance 1e-4), of the right- and left-arm meshes together (the
   platforms differ by a visual rotation), then grown by MARGIN (m) on every semi-axis
   for the meshes' simplification.
"""

import argparse
import math
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np

MARGIN = 0.01
# Largest change (m, and rotation-matrix entries) of a URDF link frame in our frame
# over the configurations: the URDF's and the 2019 model's lengths differ (the MTM's
# wrist platform offset: 0.1506 m in the URDF, 0.151 m in the 2019 model; the PSM's
# parallelogram: up to 2.3 mm).
TOLERANCE = 3e-3


def read_bytes(root, commit, path):
    if commit is None:
        with open(f"{root}/{path}", "rb") as f:
            return f.read()
    return subprocess.run(
        ["git", "--git-dir", root, "show", f"{commit}:{path}"],
        check=True,
        capture_output=True,
    ).stdout


def read(root, commit, path):
    return read_bytes(root, commit, path).decode()


def expand_macro(xacro_text, macro, params):
    """The body of `macro`, its ${...} evaluated with PI and `params`."""
    tree = ET.fromstring(xacro_text)
    ns = "{http://www.ros.org/wiki/xacro}"
    for m in tree.iter(f"{ns}macro"):
        if m.get("name") == macro:
            body = "".join(ET.tostring(c, encoding="unicode") for c in m)
            break
    else:
        raise SystemExit(f"macro {macro} not found")
    env = {"PI": math.pi, "PI_2": math.pi / 2, **params}

    def sub(match):
        v = eval(match.group(1), {}, env)
        return str(v)

    body = re.sub(r"\$\{([^}]*)\}", sub, body)
    body = re.sub(r"xmlns:ns0=\"[^\"]*\"", "", body)
    # Sub-macro calls (xacro:...) and plugins are not geometry.
    body = re.sub(r"<ns0:[^>]*/>", "", body)
    return body


def stl_vertices(data):
    """Vertices (N, 3) of a binary STL document (the dVRK's STL meshes are in metres)."""
    if data.startswith(b"version https://git-lfs"):
        raise SystemExit(
            "the mesh is a Git LFS pointer: give --commit 736b90f (the last dvrk_model commit "
            "before 70998aa converted the meshes to LFS pointers) or an LFS checkout"
        )
    n = int.from_bytes(data[80:84], "little")
    if len(data) != 84 + 50 * n:
        raise SystemExit("only binary STL meshes are handled")
    rec = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(data[84:], dtype=rec)["v"].reshape(-1, 3).astype(float)


def collada_vertices(text, any_up_axis=False):
    """Vertices (N, 3) of the instanced geometries of a Collada document, metres, in the
    document's own coordinates (`any_up_axis`: whatever its <up_axis> says)."""
    root = ET.fromstring(text)
    ns = {"c": root.tag.split("}")[0].strip("{")}
    unit = root.find("c:asset/c:unit", ns)
    scale = float(unit.get("meter")) if unit is not None else 1.0
    up = root.find("c:asset/c:up_axis", ns)
    if up is not None and up.text.strip() != "Z_UP" and not any_up_axis:
        raise SystemExit(f"up axis {up.text}: only Z_UP meshes are handled")
    out = []
    for inst in root.iter(f"{{{ns['c']}}}instance_geometry"):
        gid = inst.get("url").lstrip("#")
        geom = root.find(f".//c:geometry[@id='{gid}']", ns)
        mesh = geom.find("c:mesh", ns)
        vid = mesh.find("c:vertices/c:input[@semantic='POSITION']", ns).get("source").lstrip("#")
        src = mesh.find(f"c:source[@id='{vid}']", ns)
        arr = src.find("c:float_array", ns)
        v = np.array(arr.text.split(), dtype=float).reshape(-1, 3) * scale
        out.append(v)
    return np.vstack(out)


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = map(float, (math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def origin(el):
    o = el.find("origin") if el is not None else None
    xyz = [0.0] * 3 if o is None or o.get("xyz") is None else [float(x) for x in o.get("xyz").split()]
    rpy = [0.0] * 3 if o is None or o.get("rpy") is None else [float(x) for x in o.get("rpy").split()]
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(*rpy)
    t[:3, 3] = xyz
    return t


def mvee(points, tol=1e-4):
    """Khachiyan's minimum-volume enclosing ellipsoid: (c, A) with (x-c)^T A (x-c) <= 1."""
    p = np.asarray(points).T
    d, n = p.shape
    q = np.vstack([p, np.ones(n)])
    u = np.full(n, 1.0 / n)
    err = 1.0
    while err > tol:
        x = (q * u) @ q.T
        m = np.einsum("ij,ij->j", q, np.linalg.solve(x, q))
        j = np.argmax(m)
        step = (m[j] - d - 1.0) / ((d + 1.0) * (m[j] - 1.0))
        new_u = (1.0 - step) * u
        new_u[j] += step
        err = np.linalg.norm(new_u - u)
        u = new_u
    c = p @ u
    a = np.linalg.inv((p * u) @ p.T - np.outer(c, c)) / d
    # Khachiyan stops at a tolerance: scale so that every point is inside.
    r = np.max(np.einsum("ij,jk,ik->i", points - c, a, points - c))
    return c, a / r


def rpy_of(r):
    """URDF roll, pitch, yaw of a rotation matrix."""
    pitch = math.asin(-max(-1.0, min(1.0, r[2, 0])))
    roll = math.atan2(r[2, 1], r[2, 2])
    yaw = math.atan2(r[1, 0], r[0, 0])
    return roll, pitch, yaw


def ellipsoid_fields(c, a, margin):
    w, v = np.linalg.eigh(a)
    if np.linalg.det(v) < 0:
        v[:, 2] *= -1
    semi = 1.0 / np.sqrt(w) + margin
    roll, pitch, yaw = rpy_of(v)
    assert np.allclose(rpy_matrix(roll, pitch, yaw), v, atol=1e-9)
    return c, semi, (roll, pitch, yaw)


def kabsch(a, b):
    """T with b ~ T a (rigid), a and b (N, 3)."""
    ca, cb = a.mean(0), b.mean(0)
    h = (a - ca).T @ (b - cb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1, 1, d]) @ u.T
    t = np.eye(4)
    t[:3, :3] = r
    t[:3, 3] = cb - r @ ca
    return t


MTM = {
    "xacro": "urdf/Classic/MTM.urdf.xacro",
    "robot": "mtm",
    "macros": ["mtm"],
    # Variants whose meshes are enclosed together (the right and left platforms).
    "variants": ["mtm_platform_right", "mtm_platform_left"],
    # URDF link -> our frame (robots/mtm.toml).
    "links": {
        "outer_yaw_link": "top_panel",
        "back_parallel_link": "upper_arm",
        "bottom_parallel_link": "forearm",
        "wrist_platform_link": "wrist_platform",
        "wrist_pitch_link": "wrist_pitch",
        "wrist_yaw_link": "wrist_yaw",
        "wrist_roll_link": "wrist_roll",
    },
    # URDF joints in the order of our measured joints (mimic joints follow theirs).
    "joints": ["outer_yaw", "shoulder_pitch", "elbow_pitch", "wrist_platform",
               "wrist_pitch", "wrist_yaw", "wrist_roll"],
    # Our base in the URDF world: registered on the joint origins of the links, which
    # coincide in both (to 0.14 mm).
    "base": "register",
    "geometry": "collision",
    "any_up_axis": False,
}

PSM = {
    "xacro": "urdf/Classic/PSM_base.urdf.xacro",
    "robot": "psm",
    "macros": [],
    "variants": ["base"],
    # Only the links whose URDF frame is fixed in one of our frames: the 2019 model's
    # parallelogram (pitch_bottom, pitch_top), insertion stage and counterweight
    # (pitch_end, main_insertion) move differently from every URDF link.
    "links": {
        "yaw_link": "yaw",
        "insertion_link": "pitch_intermediate",
        "pitch_4_link": "pitch_front",
        "pitch_5_link": "pitch_front_ext",
    },
    "joints": ["yaw", "pitch", "insertion"],
    # Both bases are the remote centre of motion with the dVRK's axes (checked by the
    # fixed-frame test below).
    "base": "identity",
    # The PSM's URDF has visuals only.
    "geometry": "visual",
    # Its meshes say Y_UP, but the URDF places them in their own coordinates (RViz
    # ignores the up axis): so placed, pitch_4's mesh spans the 0.52 m from its joint
    # to the insertion carrier's along its x axis, and pitch_2's its 0.156 m and 0.192 m
    # to pitch_4 and pitch_5.
    "any_up_axis": True,
}


ECM = {
    "xacro": "urdf/Classic/ECM_base.urdf.xacro",
    "robot": "ecm",
    "macros": [],
    "variants": ["ecm_base"],
    # The endoscope (ECM.urdf.xacro's default, Classic_SD_straight) on the adaptor link.
    "more": [("urdf/common/endoscopes/Classic_SD_straight.urdf.xacro", "endoscope",
              {"parent_link": "adaptor_link"})],
    # Only the links whose URDF frame is fixed in one of our frames: our pitch link lumps
    # the parallelogram (the URDF's pitch_link, pitch_2..5), whose links turn about other
    # axes or only translate, into one link turning about the remote centre of motion.
    "links": {
        "yaw_link": "yaw",
        "insertion_link": "insertion",
        "endoscope_link": "roll",
    },
    # The insertion frame carries the endoscope's mass in our description (as in the
    # dVRK's controller: robots/ecm.toml), so its ellipsoid encloses the endoscope over
    # the roll range of ECM.json (q4 in [-1.552, 1.552] rad) too.
    "carries": {"insertion": {"endoscope_link": (3, -1.552, 1.552)}},
    "joints": ["yaw", "pitch", "insertion", "roll"],
    # The URDF's yaw and roll joints turn opposite to ECM.json's (robots/ecm.toml): with
    # the URDF joints equal to the measured ones no base rotation keeps its links fixed
    # in our frames. Searched over the 24 axis-aligned base rotations and the 16 joint
    # sign patterns, four keep all three fixed (to 6e-5 m), in two pairs that differ only
    # by the insertion axis's direction in the world (up or down); of the two that move
    # the endoscope down toward the remote centre of motion as the URDF does, this one
    # (yaw and roll reversed, our base turned -90 degrees about the URDF's z) puts the yaw
    # link's body on the same side of the remote centre of motion along the yaw axis
    # (z 0.27-0.54 m in our yaw frame) as the PSM's mesh in the same DH frame (the PSM
    # and the ECM share their first two DH rows); the other (pitch reversed, +90
    # degrees) would put it at z -0.54 to -0.27 m. Its insertion and endoscope
    # ellipsoids are the same up to a half turn about the insertion axis.
    "signs": [-1, 1, 1, -1],
    "base": [[0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
    "geometry": "collision",
    "any_up_axis": False,
}


def urdf_document(root, commit, arm, variant):
    text = read(root, commit, arm["xacro"])
    params = {"prefix": "", "parent_link": "world", "xyz": "0 0 0", "rpy": "0 0 0"}
    body = "".join(expand_macro(text, m, params) for m in arm["macros"] + [variant])
    for path, macro, extra in arm.get("more", []):
        body += expand_macro(read(root, commit, path), macro, {**params, **extra})
    return f'<robot name="{arm["robot"]}"><link name="world"/>{body}</robot>'


def urdf_poses(pin, model, data, xml, arm, qm):
    """World poses of the URDF's links with the measured joints `qm` (mimic joints
    from their <mimic>)."""
    value = dict(zip(arm["joints"], qm))
    mimic = {}
    for j in xml.iter("joint"):
        m = j.find("mimic")
        if m is not None:
            mimic[j.get("name")] = (m.get("joint"), float(m.get("multiplier", "1")))

    def joint_value(name):
        if name in value:
            return value[name]
        of, multiplier = mimic[name]
        return multiplier * joint_value(of)

    q = pin.neutral(model)
    for i in range(1, model.njoints):
        j = model.joints[i]
        v = joint_value(model.names[i])
        if j.nq == 1:
            q[j.idx_q] = v
        else:  # continuous: cos, sin
            q[j.idx_q], q[j.idx_q + 1] = math.cos(v), math.sin(v)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    return {l: data.oMf[model.getFrameId(l)].homogeneous.copy() for l in arm["links"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dvrk_model", help="dvrk_model checkout, or bare git dir with --commit")
    ap.add_argument("--commit")
    ap.add_argument("--arm", choices=["mtm", "psm", "ecm"], default="mtm")
    args = ap.parse_args()
    import pinocchio as pin
    import dvrk_ident as di

    arm = {"mtm": MTM, "psm": PSM, "ecm": ECM}[args.arm]
    ours = di.Model.load(arm["robot"])
    names = ours.frame_names
    meas = np.asarray(ours.coupling)
    rng = np.random.default_rng(1)
    dof = meas.shape[0]
    configs = [np.zeros(dof)] + [rng.uniform(-0.5, 0.5, dof) for _ in range(5)]
    if args.arm in ("psm", "ecm"):
        # The insertion is a length within [0, 0.24] m (PSM), [0, 0.255] m (ECM).
        for q in configs[1:]:
            q[2] = rng.uniform(0.02, 0.2)
    points = {}
    for variant in arm["variants"]:
        doc = urdf_document(args.dvrk_model, args.commit, arm, variant)
        model = pin.buildModelFromXML(doc)
        data = model.createData()
        xml = ET.fromstring(doc)
        signs = np.asarray(arm.get("signs", np.ones(dof)))
        poses = [urdf_poses(pin, model, data, xml, arm, signs * (meas @ q)) for q in configs]
        ours_poses = [ours.forward_kinematics(q) for q in configs]
        if arm["base"] == "register":
            a = np.array([o[names.index(f)][:3, 3] for o in ours_poses for f in arm["links"].values()])
            b = np.array([u[l][:3, 3] for u in poses for l in arm["links"]])
            t_b = kabsch(a, b)
            res = np.abs((t_b @ np.c_[a, np.ones(len(a))].T).T[:, :3] - b).max()
            print(f"# base registration: largest joint-origin mismatch {res:.2e} m", file=sys.stderr)
        elif arm["base"] == "identity":
            t_b = np.eye(4)
        else:
            t_b = np.asarray(arm["base"], dtype=float)
        for link, frame in arm["links"].items():
            xs = [np.linalg.inv(o[names.index(frame)]) @ np.linalg.inv(t_b) @ u[link]
                  for o, u in zip(ours_poses, poses)]
            dev = max(np.abs(x - xs[0]).max() for x in xs)
            if dev > TOLERANCE:
                raise SystemExit(
                    f"{link}: URDF frame not fixed in our {frame} frame (moves by {dev:.2e})"
                )
            print(f"# {variant} {link} in {frame}: fixed to {dev:.1e}", file=sys.stderr)
            el = [l for l in xml.iter("link") if l.get("name") == link][0]
            geo = el.find(arm["geometry"])
            mesh = geo.find("geometry/mesh").get("filename").replace("package://dvrk_model/", "")
            if mesh.lower().endswith(".stl"):
                v = stl_vertices(read_bytes(args.dvrk_model, args.commit, mesh))
            else:
                v = collada_vertices(read(args.dvrk_model, args.commit, mesh), arm["any_up_axis"])
            v = (origin(geo) @ np.c_[v, np.ones(len(v))].T).T
            points[(variant, link)] = ((xs[0] @ v.T).T[:, :3], mesh)
    for link, frame in arm["links"].items():
        v = np.vstack([points[(p, link)][0] for p in arm["variants"]])
        meshes = sorted({points[(p, link)][1] for p in arm["variants"]})
        for carried, (k, lo, hi) in arm.get("carries", {}).get(frame, {}).items():
            # A link this frame carries through our joint k (ECM: the endoscope, which
            # rolls): its mesh in our carried frame, placed at 25 values of q_k over
            # [lo, hi] (the joint's range).
            fi, fc = names.index(frame), names.index(arm["links"][carried])
            for qk in np.linspace(lo, hi, 25):
                q = np.zeros(dof)
                q[k] = qk
                t = ours.forward_kinematics(q)
                t = np.linalg.inv(t[fi]) @ t[fc]
                w = np.vstack([points[(p, carried)][0] for p in arm["variants"]])
                v = np.vstack([v, (t[:3, :3] @ w.T).T + t[:3, 3]])
            meshes += [f"{m} (over q{k + 1} in [{lo}, {hi}])" for p in arm["variants"]
                       for m in [points[(p, carried)][1]]]
        c, a = mvee(v)
        c, semi, rpy = ellipsoid_fields(c, a, MARGIN)
        print(f"# {frame}: {', '.join(meshes)}")
        print(
            f"ellipsoid = {{ center = [{c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f}], "
            f"semi_axes = [{semi[0]:.4f}, {semi[1]:.4f}, {semi[2]:.4f}], "
            f"rpy = [{rpy[0]:.4f}, {rpy[1]:.4f}, {rpy[2]:.4f}] }}"
        )


if __name__ == "__main__":
    main()
