"""Robot: properties, regressor, base parameters, dynamics and kinematics, checked
against the command line (`dvrk-ident model`), identities and Pinocchio's numbers."""

import json

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO, shared_file

ROBOTS = ["psm", "psm_simplified", "mtm"]


def csv(v):
    return ",".join(repr(float(x)) for x in v)


def state(robot, n, seed=3):
    rng = np.random.default_rng(seed)
    return (
        rng.uniform(-1, 1, (n, robot.dof)),
        rng.uniform(-2, 2, (n, robot.dof)),
        rng.uniform(-2, 2, (n, robot.dof)),
    )


def test_builtin_names_and_properties(psm):
    assert di.Model.builtin_names() == ["psm", "psm_simplified", "mtm", "ecm", "psm_si", "ecm_si"]
    assert psm.name == "psm"
    assert psm.source == "builtin:psm"
    assert psm.dof == 7
    assert psm.coordinates == [f"q{j}" for j in range(1, 8)]
    assert psm.measured_joints[:3] == ["outer_yaw", "outer_pitch", "outer_insertion"]
    assert len(psm.parameter_names) == psm.n_parameters == 115
    assert psm.parameter_names[:10] == [
        "L1xx", "L1xy", "L1xz", "L1yy", "L1yz", "L1zz", "l1x", "l1y", "l1z", "m1",
    ]
    assert psm.coupling.shape == (7, 7) and psm.coupling.dtype == np.float64
    assert psm.frame_names[0] == "base"
    np.testing.assert_array_equal(psm.gravity_vector, [0.0, 0.0, -9.81])
    assert psm.nominal_parameters is None
    assert "Model('psm'" in repr(psm)
    # Same object either way.
    assert di.Model("psm").parameter_names == psm.parameter_names


@pytest.mark.parametrize("name", ROBOTS)
def test_summary_matches_cli(run_cli, name):
    robot = di.Model.load(name)
    assert robot.summary() == run_cli("model", name, "--json")


@pytest.mark.parametrize("name", ROBOTS)
def test_regressor_matches_cli(run_cli, name):
    robot = di.Model.load(name)
    q, dq, ddq = state(robot, 3)
    H = robot.regressor(q, dq, ddq)
    assert H.shape == (3 * robot.dof, robot.n_parameters) and H.dtype == np.float64
    Hb = robot.base_regressor(q, dq, ddq)
    base = robot.base()
    assert Hb.shape == (3 * robot.dof, base.rank)
    for k in range(3):
        args = ["model", name, "--regressor", "--q", csv(q[k]), "--dq", csv(dq[k]),
                "--ddq", csv(ddq[k])]
        doc = run_cli(*args)
        assert doc["parameters"] == robot.parameter_names
        block = H[k * robot.dof:(k + 1) * robot.dof]
        np.testing.assert_allclose(block, np.array(doc["rows"]), rtol=1e-12, atol=1e-12)
        doc = run_cli(*args, "--base")
        assert doc["parameters"] == base.expressions
        np.testing.assert_allclose(
            Hb[k * robot.dof:(k + 1) * robot.dof], np.array(doc["rows"]),
            rtol=1e-12, atol=1e-12,
        )


def test_regressor_single_sample_and_defaults(psm):
    q, dq, ddq = state(psm, 2)
    H1 = psm.regressor(q[0], dq[0], ddq[0])
    assert H1.shape == (7, 115)
    np.testing.assert_array_equal(H1, psm.regressor(q, dq, ddq)[:7])
    # dq, ddq default to zeros; lists and ints are accepted.
    np.testing.assert_array_equal(psm.regressor(q), psm.regressor(q, 0 * q, 0 * q))
    np.testing.assert_array_equal(
        psm.regressor([0, 0, 0.1, 0, 0, 0, 0]),
        psm.regressor(np.array([0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0])),
    )
    # Non-contiguous and float32 inputs are converted.
    qt = np.asfortranarray(q)
    np.testing.assert_array_equal(psm.regressor(qt[:, :]), psm.regressor(q))
    np.testing.assert_allclose(
        psm.regressor(q.astype(np.float32)), psm.regressor(q.astype(np.float32).astype(np.float64))
    )
    assert psm.regressor(np.zeros((0, 7))).shape == (0, 115)


@pytest.mark.parametrize("name", ROBOTS)
def test_torque_matches_cli(run_cli, tmp_path, name):
    robot = di.Model.load(name)
    rng = np.random.default_rng(7)
    params = rng.uniform(-0.1, 0.1, robot.n_parameters)
    path = tmp_path / "params.json"
    path.write_text(json.dumps(dict(zip(robot.parameter_names, params.tolist()))))
    q, dq, ddq = state(robot, 2)
    tau = robot.inverse_dynamics(params, q, dq, ddq)
    assert tau.shape == (2, robot.dof) and tau.dtype == np.float64
    for k in range(2):
        doc = run_cli("model", name, "--torque", "--q", csv(q[k]), "--dq", csv(dq[k]),
                      "--ddq", csv(ddq[k]), "--params", path)
        np.testing.assert_allclose(tau[k], doc["tau"], rtol=1e-12, atol=1e-12)
    # params as a dict gives the same numbers; one sample drops the batch axis.
    by_name = dict(zip(robot.parameter_names, params))
    np.testing.assert_array_equal(robot.inverse_dynamics(by_name, q, dq, ddq), tau)
    np.testing.assert_array_equal(robot.inverse_dynamics(params, q[1], dq[1], ddq[1]), tau[1])


@pytest.mark.parametrize("name", ROBOTS)
def test_regressor_times_params_is_inverse_dynamics(name):
    robot = di.Model.load(name)
    q, dq, ddq = state(robot, 50)
    params = np.random.default_rng(1).uniform(-0.1, 0.1, robot.n_parameters)
    H = robot.regressor(q, dq, ddq)
    tau = robot.inverse_dynamics(params, q, dq, ddq)
    np.testing.assert_allclose((H @ params).reshape(-1, robot.dof), tau, atol=1e-12)
    base = robot.base()
    beta = base.project(params)
    assert beta.shape == (base.rank,)
    np.testing.assert_allclose(base.combination @ params, beta, atol=1e-12)
    np.testing.assert_allclose(robot.base_regressor(q, dq, ddq) @ beta, H @ params, atol=1e-10)
    np.testing.assert_array_equal(base.regressor(q, dq, ddq), H[:, base.independent])


def test_base_parameters(psm, mtm):
    for robot, rank in [(psm, 49), (mtm, 73), (di.Model.load("psm_simplified"), 48)]:
        base = robot.base()
        assert base.rank == len(base) == rank
        assert len(base.names) == len(base.expressions) == len(base.independent) == rank
        assert base.combination.shape == (rank, robot.n_parameters)
        assert base.independent == sorted(base.independent)
        assert [robot.parameter_names[i] for i in base.independent] == base.names
        d = base.to_dict()
        assert d["names"] == base.names
        np.testing.assert_array_equal(np.array(d["combination"]), base.combination)
        summary = robot.summary()
        assert summary["base_parameters"] == base.expressions


def test_gravity_and_mass_matrix_identities(mtm):
    q, dq, ddq = state(mtm, 20)
    params = np.random.default_rng(2).uniform(-0.1, 0.1, mtm.n_parameters)
    zero = np.zeros_like(q)
    # Gravity: the inverse dynamics at rest without friction and springs.
    links_only = params.copy()
    for i, name in enumerate(mtm.parameter_names):
        if name[:2] in ("Fc", "Fv", "Fo") or name.startswith("K"):
            links_only[i] = 0.0
    g = mtm.gravity(params, q)
    assert g.shape == (20, 7)
    np.testing.assert_allclose(g, mtm.inverse_dynamics(links_only, q, zero, zero), atol=1e-12)
    # Mass matrix: column k is ID(q, 0, e_k) - ID(q, 0, 0).
    M = mtm.mass_matrix(params, q)
    assert M.shape == (20, 7, 7)
    rest = mtm.inverse_dynamics(params, q, zero, zero)
    for k in range(7):
        e = np.zeros_like(q)
        e[:, k] = 1.0
        np.testing.assert_allclose(
            M[:, :, k], mtm.inverse_dynamics(params, q, zero, e) - rest, atol=1e-12
        )
    np.testing.assert_allclose(M, M.transpose(0, 2, 1), atol=1e-12)
    assert mtm.mass_matrix(params, q[0]).shape == (7, 7)
    np.testing.assert_array_equal(mtm.mass_matrix(params, q[0]), M[0])


def test_known_forces(psm, mtm):
    q, _, _ = state(mtm, 4)
    assert np.all(psm.known_forces(q) == 0.0)
    k = mtm.known_forces(q)
    assert k.shape == (4, 7) and np.any(k != 0.0)
    assert mtm.known_forces(q[0]).shape == (7,)


def test_forward_kinematics():
    mtm = di.Model.load("mtm")
    poses = mtm.forward_kinematics(np.zeros((2, 7)))
    frames = len(mtm.frame_names)
    assert poses.shape == (2, frames, 4, 4)
    np.testing.assert_array_equal(poses[:, 0], np.broadcast_to(np.eye(4), (2, 4, 4)))
    # Frame 1 (top panel) sits l_b2p = 0.2154 m below the base origin (dvrk-model doc).
    assert abs(poses[0, 1, 2, 3] + 0.2154) < 1e-12
    np.testing.assert_array_equal(poses[:, :, 3], np.broadcast_to([0, 0, 0, 1.0], (2, frames, 4)))
    R = poses[0, :, :3, :3]
    np.testing.assert_allclose(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    assert mtm.forward_kinematics(np.zeros(7)).shape == (frames, 4, 4)


# One link of 2 kg, its centre of mass 0.5 m from a hinge about y (I_yy = 0.02 kg·m²).
PENDULUM = (REPO / "tests" / "fixtures" / "pendulum.urdf").read_text()


def test_urdf_pendulum_nominal_dynamics():
    robot = di.Model.from_urdf(PENDULUM, "pendulum.urdf")
    assert robot.dof == 1
    nominal = robot.nominal_parameters
    assert nominal is not None and nominal.shape == (robot.n_parameters,)
    # |g(0)| = m g l with the arm horizontal, 0 with it hanging.
    assert abs(abs(robot.gravity(nominal, [0.0])[0]) - 2.0 * 9.81 * 0.5) < 1e-12
    assert abs(robot.gravity(nominal, [np.pi / 2])[0]) < 1e-12 or abs(
        robot.gravity(nominal, [-np.pi / 2])[0]
    ) < 1e-12
    # M = I_yy + m l² about the hinge.
    assert abs(robot.mass_matrix(nominal, [0.3])[0, 0] - (0.02 + 2.0 * 0.25)) < 1e-12
    # Forward dynamics inverts the inverse dynamics.
    q, dq, ddq = np.array([[0.3], [1.0]]), np.array([[0.5], [-1.0]]), np.array([[2.0], [0.1]])
    tau = robot.inverse_dynamics(nominal, q, dq, ddq)
    np.testing.assert_allclose(robot.forward_dynamics(nominal, q, dq, tau), ddq, atol=1e-12)


def test_urdf_file_matches_cli(run_cli, tmp_path):
    path = tmp_path / "pendulum.urdf"
    path.write_text(PENDULUM)
    robot = di.Model.load(path)  # a pathlib.Path is accepted
    assert robot.source == str(path)
    doc = run_cli("model", path, "--torque", "--q", "0.7", "--dq", "0.2", "--ddq", "-1.5")
    np.testing.assert_allclose(
        robot.inverse_dynamics(robot.nominal_parameters, [0.7], [0.2], [-1.5]),
        doc["tau"], rtol=1e-12, atol=1e-12,
    )


def test_toml_text_equals_builtin(psm):
    robot = di.Model.from_toml((REPO / "robots" / "psm.toml").read_text(), "psm.toml")
    q, dq, ddq = state(psm, 5)
    np.testing.assert_array_equal(robot.regressor(q, dq, ddq), psm.regressor(q, dq, ddq))


def test_panda_against_pinocchio():
    ref = json.loads(shared_file("anchors", "pinocchio_reference.json").read_text())
    panda = di.Model.load(shared_file("anchors", "panda_arm_7dof.urdf"))
    params = panda.nominal_parameters
    assert params is not None
    s = ref["samples"]
    q = np.array([x["q"] for x in s])
    dq = np.array([x["dq"] for x in s])
    ddq = np.array([x["ddq"] for x in s])
    np.testing.assert_allclose(
        panda.inverse_dynamics(params, q, dq, ddq), [x["tau_rnea"] for x in s], atol=1e-9
    )
    np.testing.assert_allclose(panda.mass_matrix(params, q), [x["M"] for x in s], atol=1e-9)
    np.testing.assert_allclose(panda.gravity(params, q), [x["gravity_torque"] for x in s], atol=1e-9)
