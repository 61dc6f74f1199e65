"""Exports other tools load as they are.

- The dVRK controller's MTM gravity-compensation file (`export --dvrk-gc`,
  `Result.dvrk_gc()`), from the real 2019 MTM fit (../shared, skipped when absent):
  evaluated here with an implementation of the controller's formula written from its
  loader (sawIntuitiveResearchKit `robGravityCompensationMTM.cpp`: `AssignRegressor`
  with its sums of products as written there, the version-2 velocity blend and the
  clamp) and compared with the model's own torques at random configurations.
- The generated URDF of the PSM, the MTM and DH robots in Pinocchio with
  `mimic=True` (skipped when `pin` is not installed): its RNEA, the mimic joints driven
  by the coordinates, against our rigid-body inverse dynamics; `check_urdf`
  (liburdfdom-tools) when installed; our importer reads the coordinates back in order.
"""

import json
import pickle
import shutil
import subprocess
import warnings

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO, shared_file

G = 9.81
# The keys robGravityCompensationMTM::Create reads for version 2, and their lengths.
GC_KEYS = {
    "gc_dynamic_params_pos": 40,
    "gc_dynamic_params_neg": 40,
    "safe_upper_torque_limit": 7,
    "safe_lower_torque_limit": 7,
    "db_vel_vec": 7,
    "sat_vec_vec": 7,
    "fric_comp_ratio_vec": 7,
}


def controller_regressor(q):
    """AssignRegressor(q): 7x40, written out term by term as in the controller."""
    q1, q2, q3, q4, q5, q6 = q[:6]
    sq2, cq2, sq3, cq3 = np.sin(q2), np.cos(q2), np.sin(q3), np.cos(q3)
    sq4, cq4, sq5, cq5 = np.sin(q4), np.cos(q4), np.sin(q5), np.cos(q5)
    sq6, cq6 = np.sin(q6), np.cos(q6)
    sq2pq3 = np.sin(q2 + q3)
    Y = np.zeros((7, 40))
    Y[0, 10:15] = [1.0, q1, q1**2, q1**3, q1**4]
    Y[1, 0] = G * sq2
    Y[1, 1] = G * cq2
    for r in (1, 2):
        Y[r, 2] = G * cq2 * cq3 - G * sq2 * sq3
        Y[r, 3] = -G * cq2 * sq3 - G * cq3 * sq2
        Y[r, 4] = G * cq2 * cq3 * cq4 - G * cq4 * sq2 * sq3
        Y[r, 5] = G * sq2 * sq3 * sq4 - G * cq2 * cq3 * sq4
        Y[r, 6] = (G * cq4 * sq2 * sq3 * sq5 - G * cq3 * cq5 * sq2
                   - G * cq2 * cq3 * cq4 * sq5 - G * cq2 * cq5 * sq3)
        Y[r, 7] = (G * cq2 * cq3 * cq4 * cq5 - G * cq3 * sq2 * sq5
                   - G * cq2 * sq3 * sq5 - G * cq4 * cq5 * sq2 * sq3)
        Y[r, 8] = (G * cq2 * cq3 * sq4 * sq6 + G * cq2 * cq6 * sq3 * sq5
                   + G * cq3 * cq6 * sq2 * sq5 - G * sq2 * sq3 * sq4 * sq6
                   + G * cq4 * cq5 * cq6 * sq2 * sq3 - G * cq2 * cq3 * cq4 * cq5 * cq6)
        Y[r, 9] = (G * cq2 * cq3 * cq6 * sq4 - G * cq6 * sq2 * sq3 * sq4
                   - G * cq2 * sq3 * sq5 * sq6 - G * cq3 * sq2 * sq5 * sq6
                   - G * cq4 * cq5 * sq2 * sq3 * sq6 + G * cq2 * cq3 * cq4 * cq5 * sq6)
    Y[1, 15:20] = [1.0, q2, q2**2, q2**3, q2**4]
    Y[2, 20:25] = [1.0, q3, q3**2, q3**3, q3**4]
    Y[3, 4] = -G * sq2pq3 * sq4
    Y[3, 5] = -G * sq2pq3 * cq4
    Y[3, 6] = G * sq2pq3 * sq4 * sq5
    Y[3, 7] = -G * sq2pq3 * cq5 * sq4
    Y[3, 8] = G * sq2pq3 * (cq4 * sq6 + cq5 * cq6 * sq4)
    Y[3, 9] = G * sq2pq3 * (cq4 * cq6 - cq5 * sq4 * sq6)
    Y[3, 25:30] = [1.0, q4, q4**2, q4**3, q4**4]
    Y[4, 6] = -G * (cq2 * cq3 * sq5 - sq2 * sq3 * sq5 + cq2 * cq4 * cq5 * sq3
                    + cq3 * cq4 * cq5 * sq2)
    Y[4, 7] = -G * (cq5 * sq2 * sq3 - cq2 * cq3 * cq5 + cq2 * cq4 * sq3 * sq5
                    + cq3 * cq4 * sq2 * sq5)
    Y[4, 8] = G * (cq5 * cq6 * sq2 * sq3 - cq2 * cq3 * cq5 * cq6
                   + cq2 * cq4 * cq6 * sq3 * sq5 + cq3 * cq4 * cq6 * sq2 * sq5)
    Y[4, 9] = -G * (cq5 * sq2 * sq3 * sq6 - cq2 * cq3 * cq5 * sq6
                    + cq2 * cq4 * sq3 * sq5 * sq6 + cq3 * cq4 * sq2 * sq5 * sq6)
    Y[4, 30:35] = [1.0, q5, q5**2, q5**3, q5**4]
    Y[5, 8] = G * (cq2 * cq6 * sq3 * sq4 + cq3 * cq6 * sq2 * sq4 + cq2 * cq3 * sq5 * sq6
                   - sq2 * sq3 * sq5 * sq6 + cq2 * cq4 * cq5 * sq3 * sq6
                   + cq3 * cq4 * cq5 * sq2 * sq6)
    Y[5, 9] = G * (cq2 * cq3 * cq6 * sq5 - cq2 * sq3 * sq4 * sq6 - cq3 * sq2 * sq4 * sq6
                   - cq6 * sq2 * sq3 * sq5 + cq2 * cq4 * cq5 * cq6 * sq3
                   + cq3 * cq4 * cq5 * cq6 * sq2)
    Y[5, 35:40] = [1.0, q6, q6**2, q6**3, q6**4]
    return Y


def controller_effort(gc, q, qd):
    """robGravityCompensationMTM::compute, version 2: blend by velocity, then clamp."""
    c = gc["GC_controller"]
    Y = controller_regressor(q)
    pos = Y @ np.array(c["gc_dynamic_params_pos"])
    neg = Y @ np.array(c["gc_dynamic_params_neg"])
    tau = np.zeros(7)
    for j in range(7):
        db, sat, r = c["db_vel_vec"][j], c["sat_vec_vec"][j], c["fric_comp_ratio_vec"][j]
        if qd[j] >= sat:
            a = 0.5 + 0.5 * r
        elif qd[j] <= -sat:
            a = 0.5 - 0.5 * r
        elif -db <= qd[j] <= db:
            a = 0.5
        elif db < qd[j] < sat:
            a = 0.5 * r * (qd[j] - db) / (sat - db) + 0.5
        else:
            a = -0.5 * r * (-qd[j] - db) / (sat - db) + 0.5
        tau[j] = a * pos[j] + (1 - a) * neg[j]
    return np.clip(tau, c["safe_lower_torque_limit"], c["safe_upper_torque_limit"])


@pytest.fixture(scope="module")
def mtm_fit(mtm):
    one = shared_file("data", "dvrk", "mtm", "one_results.csv")
    train = di.read_log(one, mtm, format="wpi-csv", rate=200)
    # The 2019 bounds: the fit these checks were calibrated on. With the physical
    # default bounds, joint 5's worst error at rest over the 200 random points below is
    # 1.00035 times the 1.5 x grid-residual margin (0.0056772 vs 0.0056752 N·m).
    result = di.fit(mtm, train, method="sdp", cutoff=5.655, bounds="2019",
                    settings={"processing": {"filter_torque": True}})
    assert result.solver["converged"] and result.physically_consistent
    return result


def model_torques(robot, result, qm, direction):
    """The model's static torque in measured joints at measured positions `qm`, the
    friction of a motion `direction` (measured joint rates, only signs count): inverse
    dynamics at a vanishing speed plus the known forces (the cable)."""
    C = robot.coupling
    q = np.linalg.solve(C, qm)
    # Rounded so that a frame the motion leaves still gets a rate of exactly zero
    # (the MTM's wrist platform, 0.6697 q2 - 0.6697 q3 + q4, under elbow pitch).
    dq = 1e-12 * np.round(np.linalg.solve(C, direction), 12)
    tau = robot.inverse_dynamics(result, q, dq, np.zeros(7)) + robot.known_forces(q)
    return np.linalg.solve(C.T, tau)


def test_dvrk_gc_file_matches_the_real_mtm_fit(mtm, mtm_fit, cli, tmp_path):
    result = mtm_fit
    path = tmp_path / "result.json"
    result.write(path)
    out = tmp_path / "gc-MTML.json"
    r = subprocess.run([cli, "export", path, "--dvrk-gc", out], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    # The residual table is on the command line.
    assert "wrist_platform" in r.stdout and "not compensated" in r.stdout
    gc = json.loads(out.read_text())
    assert gc == json.loads(json.dumps(result.dvrk_gc()))
    # What the loader needs: version "2.0" as a string, every key, the right lengths.
    assert gc["version"] == "2.0" and int(float(gc["version"])) == 2
    for key, n in GC_KEYS.items():
        assert len(gc["GC_controller"][key]) == n, key
    c = gc["GC_controller"]
    pos, neg = np.array(c["gc_dynamic_params_pos"]), np.array(c["gc_dynamic_params_neg"])
    # Gravity parameters shared by both directions (as the CUHK generator has them).
    np.testing.assert_array_equal(pos[:10], neg[:10])
    res = gc["dvrk_ident"]["residual_N_m"]
    ranges = np.array(gc["dvrk_ident"]["grid"]["ranges_rad"])
    assert ranges.shape == (6, 2)

    rng = np.random.default_rng(7)
    C = mtm.coupling
    worst = {"gravity": 0.0, "pos": np.zeros(7), "neg": np.zeros(7), "rest": np.zeros(7)}
    for _ in range(200):
        qm = np.append(rng.uniform(ranges[:, 0], ranges[:, 1]), rng.uniform(-3, 3))
        Y = controller_regressor(qm)
        # Gravity: the links' gravity torque, in measured joints, from the ten columns.
        # The controller does not read the wrist roll: the file holds the average over
        # a turn of it (a rigid body turning with it: the mean of q7 and q7 + pi).
        def gravity(roll):
            q = np.linalg.solve(C, np.append(qm[:6], roll))
            return np.linalg.solve(C.T, mtm.gravity(result, q))
        average = 0.5 * (gravity(qm[6]) + gravity(qm[6] + np.pi))
        worst["gravity"] = max(worst["gravity"],
                               np.abs(Y[:6, :10] @ pos[:10] - average[:6]).max())
        worst["roll"] = np.maximum(worst.get("roll", 0), np.abs(gravity(qm[6]) - average))
        for j in range(6):
            e = np.eye(7)[j]
            worst["pos"][j] = max(worst["pos"][j],
                                  abs(Y[j] @ pos - model_torques(mtm, result, qm, e)[j]))
            worst["neg"][j] = max(worst["neg"][j],
                                  abs(Y[j] @ neg - model_torques(mtm, result, qm, -e)[j]))
        # At rest (inside the dead band) the controller feeds the mean of both
        # directions: the model's torque at rest (offset friction, no Coulomb).
        rest = model_torques(mtm, result, qm, np.zeros(7))
        effort = controller_effort(gc, qm, np.zeros(7))
        worst["rest"] = np.maximum(worst["rest"], np.abs(effort - rest))
        # One joint moving beyond the saturation speed: the controller adds the share
        # fric_comp_ratio of that joint's Coulomb friction to its torque at rest. (It
        # blends each joint by its own speed: friction that the parallelogram and the
        # cable couple into other joints is not in the file.)
        j = rng.integers(6)
        qd = np.zeros(7)
        qd[j] = rng.choice([-1.0, 1.0])
        effort = controller_effort(gc, qm, qd)[j]
        moving = model_torques(mtm, result, qm, qd)[j]
        ratio = c["fric_comp_ratio_vec"][j]
        expected = rest[j] + ratio * (moving - rest[j])
        bound = max(res["pos_max"][j], res["neg_max"][j])
        assert abs(effort - expected) < 1.5 * bound + 1e-9, (j, effort, expected)
    # The MTM's gravity, averaged over the wrist roll, is in the span of the
    # controller's ten gravity columns; the roll's own part is in the reported residual.
    assert worst["gravity"] < 1e-9, worst["gravity"]
    np.testing.assert_array_less(worst["roll"], np.array(res["gravity_max"]) + 1e-12)
    # Springs, cable and friction: within the reported residual (it is the worst case
    # on the fitted grid; random points between grid points may exceed it a little).
    for side in ("pos", "neg"):
        np.testing.assert_array_less(worst[side][:6],
                                     1.5 * np.array(res[f"{side}_max"][:6]) + 1e-9)
    np.testing.assert_array_less(worst["rest"][:6],
                                 1.5 * np.maximum(res["pos_max"], res["neg_max"])[:6] + 1e-9)
    # Joint 7 is not compensated: its row is zero and its limits are 0.
    assert not controller_regressor(np.ones(7))[6].any()
    assert c["safe_upper_torque_limit"][6] == c["safe_lower_torque_limit"][6] == 0
    # The reported residuals: the wrist roll's centre of mass off its axis (joints 2-6,
    # a few mN·m on this fit), the cable (joint 4) and the spring (joint 5) approximated
    # by quartics; joint 1 (vertical axis) exact.
    print("residual max (N·m): gravity", res["gravity_max"], "pos", res["pos_max"],
          "random worst: pos", worst["pos"], "neg", worst["neg"])
    assert res["pos_max"][0] < 1e-9 and res["neg_max"][0] < 1e-9
    assert max(res["pos_max"][:6]) < 0.02 and max(res["neg_max"][:6]) < 0.02
    # The kinematic gravity compensation is not the MTM's: the message names the export
    # that is, as Python's method (the command line: `export --dvrk-gc`).
    with pytest.raises(di.InputError) as e:
        result.dvrk_kinematic_gc()
    msg = str(e.value)
    assert msg.endswith("the MTM's gravity compensation is its own file: FitResult.dvrk_gc()") \
        and "--" not in msg, msg


def test_result_says_what_the_data_determined_and_exports_warn(psm, psm_logs):
    # The semidefinite fit of the synthetic PSM: a status for every parameter, the
    # per-link summary equal to its parameters' statuses, and the 2019 layout warning
    # about each link whose mass the data did not determine (most of them: a revolute
    # joint folds the masses of what it carries into its parents' moments).
    result = di.fit(psm, di.read_log(psm_logs["csv"], psm))
    status = result.parameter_status
    assert list(status) == result.parameter_order
    assert set(status.values()) <= {
        "identified", "at_lower_bound", "at_upper_bound", "unidentified"}
    for link in result.links:
        frame = link["frame"]
        names = [f"L{frame}{s}" for s in ("xx", "xy", "xz", "yy", "yz", "zz")]
        d = link["determined"]
        assert d["mass"] == (status[f"m{frame}"] == "identified")
        assert d["first_moment"] == all(
            status[f"l{frame}{a}"] == "identified" for a in "xyz")
        assert d["inertia"] == all(status[n] == "identified" for n in names)
    undetermined = [link for link in result.links if not link["determined"]["mass"]]
    assert undetermined
    with pytest.warns(UserWarning) as caught:
        result.wpi_params()
    text = [str(w.message) for w in caught]
    for link in undetermined:
        assert any(t.startswith(f"link {link['link']}: mass") for t in text), text


def test_dvrk_gc_refuses_other_robots(psm, psm_logs):
    result = di.fit(psm, di.read_log(psm_logs["csv"], psm), method="ols")
    with pytest.raises(di.InputError, match="for the MTM"):
        result.dvrk_gc()
    # The Classic PSM has no kinematic gravity compensation either: told which it has.
    with pytest.raises(di.InputError, match="Classic PSM") as e:
        result.dvrk_kinematic_gc()
    # The exports it suggests, as Python's methods (the command line's flags).
    msg = str(e.value)
    assert msg.endswith("Model.to_urdf() or FitResult.wpi_params() for other controllers") \
        and "--" not in msg, msg


def test_dvrk_kinematic_gc_matches_cli(run_cli, cli, tmp_path):
    """result.dvrk_kinematic_gc() is `export --dvrk-kinematic-gc` of the same result: a
    PSM Si mounted at -45 degrees, simulated from its nominal parameters and fitted."""
    robot = di.Model("psm_si")
    traj = di.FourierTrajectory(order=2, base_frequency_hz=0.1, q0=[0.0, 0.0, 0.12],
                                a=[[0.3, 0.1], [0.2, 0.1], [0.03, 0.01]],
                                b=[[0.1, 0.05], [0.1, 0.0], [0.01, 0.0]])
    excitation = tmp_path / "excitation.json"
    traj.write(excitation)
    log = tmp_path / "log.csv"
    subprocess.run([cli, "simulate", "psm_si", "--params", "nominal", "--excitation",
                    excitation, "--mounting-pitch", "-45", "--noise", "0.001", "--out", log,
                    "--quiet"], check=True, capture_output=True)
    result = di.fit(robot, di.read_log(log, robot), mounting_pitch=-45.0)
    path = tmp_path / "psm_si.json"
    result.write(path)
    # The result's model carries the fit's gravity, as `model psm_si --json
    # --mounting-pitch -45` prints it: fitted in memory, read back, pickled.
    level = subprocess.run([cli, "model", "psm_si", "--json"], check=True,
                           capture_output=True, text=True)
    mounted = subprocess.run([cli, "model", "psm_si", "--json", "--mounting-pitch", "-45"],
                             check=True, capture_output=True, text=True)
    gravity = json.loads(mounted.stdout)["gravity"]
    assert gravity != json.loads(level.stdout)["gravity"]
    assert list(robot.gravity_vector) == json.loads(level.stdout)["gravity"]
    fitted = result.load_robot()
    for model in (fitted, di.FitResult.from_json(path.read_text()).load_robot(),
                  pickle.loads(pickle.dumps(fitted))):
        assert list(model.gravity_vector) == gravity
        assert model.summary()["gravity"] == gravity
    # A `--preset dvrk` result's model has its Stribeck and Dahl terms too.
    preset = di.fit(robot, di.read_log(log, robot), preset="dvrk", mounting_pitch=-45.0)
    for model in (preset.load_robot(), di.FitResult.from_json(preset.to_json()).load_robot()):
        assert model.parameter_names == list(preset.parameters)
        assert list(model.gravity_vector) == gravity
    out = tmp_path / "gc.json"
    subprocess.run([cli, "export", path, "--dvrk-kinematic-gc", out, "--quiet"], check=True,
                   capture_output=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours = result.dvrk_kinematic_gc()
    assert ours == json.loads(out.read_text())
    with pytest.raises(di.InputError, match="carries no endoscope"):
        result.dvrk_kinematic_gc(endoscope="Si_HD_UP")


# A standard-DH robot with gravity along -y (the URDF gets a rotated root), a reversed
# coordinate, a prismatic joint, a joint turning by 2w and one by u + w; the Rust export
# test reads the same file.
DH = (REPO / "tests" / "fixtures" / "dh_odd.toml").read_text()


def physical_params(robot, rng):
    """Random rigid bodies on every link (mass, centre of mass, the inertia of a box
    about it), as barycentric parameters; friction and the rest zero."""
    names = robot.parameter_names
    p = dict.fromkeys(names, 0.0)
    for i in range(1, len(robot.frame_names)):
        if f"m{i}" not in p:
            continue
        m = rng.uniform(0.1, 2.0)
        c = rng.uniform(-0.1, 0.1, 3)
        # A box of random sides, turned by a random rotation.
        a, b, h = rng.uniform(0.02, 0.3, 3)
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        Ic = R @ np.diag([b * b + h * h, a * a + h * h, a * a + b * b]) @ R.T * m / 12
        L = Ic + m * (c @ c * np.eye(3) - np.outer(c, c))
        for k, (r, s) in zip(("xx", "xy", "xz", "yy", "yz", "zz"),
                             ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
            p[f"L{i}{k}"] = L[r, s]
        for k, x in zip("xyz", m * c):
            p[f"l{i}{k}"] = x
        p[f"m{i}"] = m
    return p


ROBOTS = {
    "psm": lambda: di.Model.load("psm"),
    "mtm": lambda: di.Model.load("mtm"),
    # The PSM Si's parallelogram and two-stage insertion, its instrument's coupled joints.
    "psm_si_tool": lambda: di.Model.load("psm_si_tool"),
    "dh_2w": lambda: di.Model.from_toml(DH, "dh_odd.toml"),
    "dh_chain": lambda: di.Model.from_toml(DH.replace('theta = "2*w"', 'theta = "w"'),
                                           "dh_odd.toml"),
}


@pytest.mark.parametrize("name", ROBOTS)
def test_exported_urdf_loads_everywhere_with_its_mimics(name, tmp_path, capsys):
    robot = ROBOTS[name]()
    rng = np.random.default_rng(len(name))
    params = physical_params(robot, rng)
    text = robot.to_urdf(params)
    path = tmp_path / f"{name}.urdf"
    path.write_text(text)
    # Our importer: the same coordinates, in the same order.
    back = di.Model.from_urdf(text, str(path))
    assert back.coordinates == robot.coordinates
    if shutil.which("check_urdf"):
        r = subprocess.run(["check_urdf", path], capture_output=True, text=True)
        assert r.returncode == 0 and "Successfully Parsed" in r.stdout, r.stdout + r.stderr
    else:
        with capsys.disabled():
            print("SKIPPED: check_urdf not installed (apt-get install liburdfdom-tools)")
    try:
        import pinocchio as pin
    except ImportError:
        pytest.skip("SKIPPED: Pinocchio not installed (pip install pin)")
    model = pin.buildModelFromUrdf(str(path), mimic=True)
    data = model.createData()
    # One degree of freedom per coordinate; every other moving joint mimics one.
    assert model.nv == robot.dof
    joints = [model.joints[model.getJointId(c)] for c in robot.coordinates]
    assert sorted(j.idx_v for j in joints) == list(range(robot.dof))
    worst = pose_worst = 0.0
    posed = set()
    for _ in range(20):
        q, dq, ddq = (rng.uniform(-1, 1, robot.dof) for _ in range(3))
        ours = robot.inverse_dynamics(params, q, dq, ddq)
        qp, vp, ap = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        for k, j in enumerate(joints):
            if j.nq == 2:  # a continuous joint: cos, sin
                qp[j.idx_q:j.idx_q + 2] = np.cos(q[k]), np.sin(q[k])
            else:
                qp[j.idx_q] = q[k]
            vp[j.idx_v], ap[j.idx_v] = dq[k], ddq[k]
        tau = pin.rnea(model, data, qp, vp, ap)
        theirs = np.array([tau[j.idx_v] for j in joints])
        worst = max(worst, np.abs(ours - theirs).max())
        # Every frame's pose in the base frame: the generated URDF's link of the same
        # name, from its link "base" (below which a rotated root may turn gravity).
        pin.framesForwardKinematics(model, data, qp)
        poses = robot.forward_kinematics(q)
        base = data.oMf[model.getFrameId("base")].inverse()
        for k, frame in enumerate(robot.frame_names[1:], start=1):
            if model.existFrame(frame):
                theirs = (base * data.oMf[model.getFrameId(frame)]).homogeneous
                pose_worst = max(pose_worst, np.abs(poses[k] - theirs).max())
                posed.add(frame)
    print(f"{name}: max |ours - Pinocchio RNEA| = {worst:.2e} N·m, frame poses "
          f"{pose_worst:.2e} over {len(posed)} frames")
    assert worst < 1e-9
    assert pose_worst < 1e-9 and len(posed) >= 3, (pose_worst, posed)
