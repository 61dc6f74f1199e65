"""Trajectory, excite and evaluate_trajectory against the closed-form Fourier series,
the command line (`dvrk-ident excite`, same seed and options), the robot's own forward
kinematics (Cartesian boxes) and the 2019 trajectories (skipped without ../shared)."""

import ast
import csv
import json
import subprocess

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO, shared_file

# The planar 2-link arm of the Rust excitation tests (a massless `tip` frame, coupled
# measured joints, joint limits); an optimization on it takes a fraction of a second.
ARM_FILE = REPO / "tests" / "fixtures" / "two_link_tip.toml"

# Small and fast; the same on both sides of each comparison.
QUICK = dict(order=3, f0=0.25, seed=3, starts=3, refine=2, iterations=25, refine_iterations=25)


@pytest.fixture(scope="module")
def arm_file():
    if not ARM_FILE.exists():
        pytest.skip(f"{ARM_FILE} not found (installed without the sources)")
    return ARM_FILE


@pytest.fixture(scope="module")
def arm(arm_file):
    return di.Model.load(arm_file)


def series(order, f0, q0, a, b, t):
    """The Fourier series of docs/book/src/identification.md §7.1, written out with numpy."""
    w = 2 * np.pi * f0 * np.arange(1, order + 1)
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    q = q0 + (s / w) @ a.T - (c / w) @ b.T
    dq = c @ a.T + s @ b.T
    ddq = (c * w) @ b.T - (s * w) @ a.T
    return q, dq, ddq


def test_trajectory_matches_the_closed_form_and_round_trips(tmp_path):
    rng = np.random.default_rng(1)
    q0, a, b = rng.normal(size=3), rng.normal(size=(3, 4)), rng.normal(size=(3, 4))
    t = di.FourierTrajectory(4, 0.2, q0, a, b, coordinates=["x", "y", "z"])
    assert (t.order, t.dof, t.base_frequency_hz, t.period) == (4, 3, 0.2, 5.0)
    assert t.coordinates == ["x", "y", "z"]
    np.testing.assert_array_equal(t.a, a)
    np.testing.assert_array_equal(t.b, b)
    np.testing.assert_array_equal(t.q0, q0)
    time = np.linspace(0.0, 7.0, 301)
    for got, want in zip(t.sample(time), series(4, 0.2, q0, a, b, time)):
        assert got.shape == (301, 3)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    # Periodic, and the derivatives are those of the positions (central differences).
    q, dq, ddq = t.sample(time)
    np.testing.assert_allclose(t.sample(time + t.period)[0], q, atol=1e-11)
    h = 1e-5
    qp, dqp, _ = t.sample(time + h)
    qm, dqm, _ = t.sample(time - h)
    np.testing.assert_allclose((qp - qm) / (2 * h), dq, atol=1e-7)
    np.testing.assert_allclose((dqp - dqm) / (2 * h), ddq, atol=1e-6)
    # JSON and files round-trip exactly.
    assert di.FourierTrajectory.from_json(t.to_json()) == t
    t.write(tmp_path / "t.json")
    assert di.FourierTrajectory.read(tmp_path / "t.json") == t
    doc = json.loads((tmp_path / "t.json").read_text())
    assert doc["order"] == 4 and doc["base_frequency_hz"] == 0.2
    assert doc["a"] == a.tolist() and doc["q0"] == q0.tolist()
    assert t.to_dict() == doc


def test_trajectory_input_errors(tmp_path):
    with pytest.raises(di.InputError, match="invalid Fourier trajectory"):
        di.FourierTrajectory(2, 0.2, [0.0, 0.0], [[1.0, 2.0]], [[0.0, 0.0]])
    with pytest.raises(di.InputError, match="base"):
        di.FourierTrajectory(1, -0.2, [0.0], [[1.0]], [[0.0]])
    with pytest.raises(di.InputError, match="non-finite"):
        di.FourierTrajectory(1, 0.2, [np.nan], [[1.0]], [[0.0]])
    with pytest.raises(di.InputError, match="2-D"):
        di.FourierTrajectory(1, 0.2, [0.0], [1.0], [[0.0]])
    with pytest.raises(di.DvrkFileNotFoundError, match="missing.json"):
        di.FourierTrajectory.read(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text('{"order": 1}')
    with pytest.raises(di.InputError, match="bad.json"):
        di.FourierTrajectory.read(tmp_path / "bad.json")


def test_excite_equals_the_command_line(arm, arm_file, run_cli, cli, tmp_path):
    ex = di.excite(arm, **QUICK)
    assert ex.feasible and ex.criterion["name"] == "condition"
    assert len(ex.starts) == QUICK["starts"]
    out, setpoints = tmp_path / "traj.json", tmp_path / "setpoints.csv"
    r = subprocess.run(
        [cli, "excite", "--robot", arm_file, "--order", "3", "--f0", "0.25", "--seed", "3",
         "--starts", "3", "--refine", "2", "--iterations", "25", "--refine-iterations", "25",
         "--out", out, "--csv", setpoints, "--rate", "100"],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stderr
    doc = json.loads(out.read_text())
    # Same seed, same options: the same trajectory to the last bit.
    assert di.FourierTrajectory.read(out) == ex.trajectory
    assert doc["criterion"] == ex.criterion
    assert ex.to_dict()["criterion"] == doc["criterion"]
    assert ex.to_dict()["feasibility"] == doc["feasibility"]
    # Setpoints in measured space: q_meas = C q, the CLI's CSV to its 9 decimals.
    time, qm = ex.trajectory.setpoints(arm, rate=100.0)
    assert time.shape == (400,) and qm.shape == (400, 2)
    q, _, _ = ex.trajectory.sample(time)
    np.testing.assert_allclose(qm, q @ arm.coupling.T, atol=1e-15)
    rows = list(csv.reader(setpoints.open()))
    assert rows[0] == ["time", "shoulder", "elbow"]
    table = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(table[:, 0], time, atol=1e-6)
    np.testing.assert_allclose(table[:, 1:], qm, atol=1e-9)
    # The Python evaluation of the written file agrees with the optimizer's.
    ev = di.evaluate_trajectory(arm, di.FourierTrajectory.read(out))
    assert ev["feasible"] is True
    assert ev["criterion"]["value"] == pytest.approx(ex.criterion["value"], rel=1e-12)
    assert ev == run_cli("excite", "--robot", arm_file, "--evaluate", out, "--json")


def test_joint_limits_hold_on_an_independent_dense_grid(arm):
    ex = di.excite(arm, rest=True, **QUICK)
    t = ex.trajectory
    time = np.arange(0.0, t.period, 1.0 / 4000.0)
    q, dq, ddq = t.sample(time)
    tol = 1e-9
    assert q[:, 0].min() >= -1.0 - tol and q[:, 0].max() <= 1.2 + tol
    assert np.abs(dq[:, 0]).max() <= 1.5 + tol and np.abs(ddq[:, 0]).max() <= 4.0 + tol
    rel = q[:, 1] - q[:, 0]
    assert rel.min() >= 0.2 - tol and rel.max() <= 1.6 + tol
    assert np.abs(dq[:, 1] - dq[:, 0]).max() <= 2.0 + tol
    # rest=True: at rest at both ends of the period.
    _, dq0, ddq0 = t.sample([0.0, t.period])
    np.testing.assert_allclose(dq0, 0.0, atol=1e-12)
    np.testing.assert_allclose(ddq0, 0.0, atol=1e-11)


def tip_y(robot, q):
    """The tip's y in the base frame, from the robot's forward kinematics."""
    poses = robot.forward_kinematics(q)
    return poses[:, robot.frame_names.index("tip"), 1, 3]


def test_cartesian_box_given_as_a_dict(arm, tmp_path):
    box = {"cartesian_limits": [{"frame": "tip", "min": [-1.0, -1.0, -float("inf")],
                                 "max": [1.0, 0.2, float("inf")]}]}
    joint = arm.limits
    free = di.excite(arm, limits=joint, **QUICK)
    # Without the box the optimum leaves it; with the box it stays in.
    time = np.arange(0.0, free.trajectory.period, 1e-3)
    assert tip_y(arm, free.trajectory.sample(time)[0]).max() > 0.2
    ev = di.evaluate_trajectory(arm, free.trajectory, limits={**joint, **box})
    assert not ev["feasible"]
    assert ev["worst_violation"]["limit"] == "frame tip y"
    assert ev["worst_violation"]["excess"] > 0
    boxed = di.excite(arm, limits={**joint, **box}, **QUICK)
    y = tip_y(arm, boxed.trajectory.sample(np.arange(0.0, boxed.trajectory.period, 2e-4))[0])
    assert y.max() <= 0.2 + 1e-9
    assert y.max() > 0.19, "the box binds"
    # The same limits from a file.
    f = tmp_path / "limits.toml"
    f.write_text(
        '[[cartesian_limits]]\nframe = "tip"\nmin = [-1, -1, -inf]\nmax = [1, 0.2, inf]\n'
        '[[limits]]\nexpr = "q1"\nposition = [-1.0, 1.2]\nvelocity = [-1.5, 1.5]\n'
        'acceleration = [-4.0, 4.0]\n'
        '[[limits]]\nexpr = "q2 - q1"\nposition = [0.2, 1.6]\nvelocity = [-2.0, 2.0]\n'
    )
    assert di.excite(arm, limits=f, **QUICK).trajectory == boxed.trajectory


def test_robot_limits_round_trip(arm):
    lim = arm.limits
    assert lim["cartesian_limits"] == []
    assert [x["expr"] for x in lim["limits"]] == ["q1", "q2 - q1"]
    assert lim["limits"][0] == {"expr": "q1", "position": [-1.0, 1.2],
                                "velocity": [-1.5, 1.5], "acceleration": [-4.0, 4.0]}
    # The dict gives the description's limits back: the same optimum.
    assert di.excite(arm, limits=lim, **QUICK).trajectory == di.excite(arm, **QUICK).trajectory
    psm = di.Model.load("psm")
    jaw = [x for x in psm.limits["limits"] if x["expr"] == "1.2177*(q7 - q6)"]
    assert len(jaw) == 1 and jaw[0]["position"][0] == pytest.approx(0.15)


def test_excite_errors(arm, tmp_path):
    with pytest.raises(di.InputError, match="criterion"):
        di.excite(arm, criterion="trace", **QUICK)
    # The same checks as a limits file or a description (one schema, one compiler).
    with pytest.raises(di.InputError, match="position`: lower bound 1 is above upper bound 0"):
        di.excite(arm, limits={"limits": [{"expr": "q1", "position": [1.0, 0.0]}]}, **QUICK)
    with pytest.raises(di.InputError, match="unknown field `speed`"):
        di.excite(arm, limits={"limits": [{"expr": "q1", "speed": [-1.0, 1.0]}]}, **QUICK)
    with pytest.raises(di.InputError, match="must be a finite number"):
        di.excite(arm, limits={"limits": [{"expr": "q1", "position": [float("nan"), 1.0]}]},
                  **QUICK)
    with pytest.raises(di.InputError, match="no frame named `hand`"):
        di.excite(arm, limits={"cartesian_limits": [
            {"frame": "hand", "min": [0, 0, 0], "max": [1, 1, 1]}]}, **QUICK)
    with pytest.raises(di.InputError, match="no static pose"):
        # The tip cannot be 1 m from the base: the links total 0.55 m.
        di.excite(arm, limits={"cartesian_limits": [
            {"frame": "tip", "min": [1.0, -1, -1], "max": [2.0, 1, 1]}]}, **QUICK)
    with pytest.raises(di.DvrkFileNotFoundError, match="nope.toml"):
        di.excite(arm, limits=tmp_path / "nope.toml", **QUICK)
    wrong = di.FourierTrajectory(1, 0.2, [0.0, 0.0, 0.0], [[1.0]] * 3, [[0.0]] * 3)
    with pytest.raises(di.InputError, match="3 coordinates"):
        di.evaluate_trajectory(arm, wrong)
    with pytest.raises(di.InputError, match="rate"):
        di.FourierTrajectory(1, 0.2, [0.0, 0.5], [[1.0]] * 2, [[0.0]] * 2).setpoints(arm, rate=0.0)


def test_2019_trajectories_evaluated_as_by_the_command_line(run_cli):
    path = shared_file("anchors", "wpi2019_excitation_trajectories.json")
    assert "psm_one" in di.FourierTrajectory.wpi_names(path)
    old = di.FourierTrajectory.read(path, pick="psm_one")
    assert (old.order, old.base_frequency_hz, old.dof) == (6, 0.18, 7)
    ev = di.evaluate_trajectory(di.Model.load("psm_simplified"), old)
    # The 2019 psm_one: condition 334.1 and four limits exceeded (q1 velocity worst).
    assert ev["criterion"]["value"] == pytest.approx(334.114, abs=1e-3)
    assert not ev["feasible"]
    assert ev["worst_violation"]["limit"] == "q1"
    assert ev["worst_violation"]["quantity"] == "velocity"
    assert len(ev["violated"]) == 4
    cli = run_cli("excite", "--robot", "psm_simplified", "--evaluate", path, "--pick",
                  "psm_one", "--json")
    assert ev == cli


def test_excite_keywords_take_numpy_values(arm):
    """The keywords go through the library's one conversion: NumPy's integers, floats
    and booleans are their values (an int is not a boolean)."""
    plain = di.excite(arm, **QUICK, rest=True)
    numpy = di.excite(arm, **{**QUICK, "order": np.int64(3), "f0": np.float64(0.25)},
                      rest=np.bool_(True))
    assert numpy.to_json() == plain.to_json()
    with pytest.raises(TypeError, match="^rest: invalid type: integer"):
        di.excite(arm, **QUICK, rest=1)


def test_excite_defaults_are_the_librarys(cli):
    """The excitation options are declared once, in the library (``ExciteOptions``):
    Python converts its keywords through the library's list (``_excite_options``: each
    function's options, in order, with the library's defaults), the command line makes
    its flags from it and prints the defaults in ``--help``, and the type stub writes
    them literally: each must be the library's, so that a default is changed in one
    place and a stub or flag left behind fails here."""
    import re
    from pathlib import Path

    table = di._excite_options
    assert list(table) == ["excite", "evaluate_trajectory"]
    assert list(table["evaluate_trajectory"]) == ["criterion", "samples_per_harmonic",
                                                  "check_rate"]
    assert table["excite"]["order"] == 6 and table["excite"]["smooth"] is True
    stub = ast.parse((Path(di.__file__).parent / "__init__.pyi").read_text())
    stubs = {n.name: n for n in stub.body if isinstance(n, ast.FunctionDef)}
    for function, defaults in table.items():
        args = stubs[function].args
        given = list(zip(args.args[len(args.args) - len(args.defaults):], args.defaults))
        given += list(zip(args.kwonlyargs, args.kw_defaults))
        listed = {a.arg: d.value for a, d in given if a.arg in defaults}
        assert list(listed) == list(defaults), function
        for name, default in defaults.items():
            # Equal and of the same type (6 is not 6.0, True is not 1).
            assert (listed[name], type(listed[name])) == (default, type(default)), \
                (function, name)
    text = subprocess.run([cli, "excite", "--help"], capture_output=True, text=True,
                          check=True).stdout
    flags = dict(re.findall(r"--([a-z0-9-]+) <[^>]+>\s+.*?\[default: ([^\]]+)\]", text))
    for name, default in table["excite"].items():
        if isinstance(default, bool):
            # The switches: `--rest` turns rest on, `--no-smooth` smoothing off.
            flag = f"--{name}" if default is False else f"--no-{name}"
            assert re.search(rf"^\s+{flag}\s", text, re.M), flag
            continue
        shown = flags[name.replace("_", "-")]
        if isinstance(default, str):
            assert shown == default, name
        else:
            assert float(shown) == float(default), name
    # The setpoints' rate: the library's constant, in the stub and the help.
    trajectory = next(n for n in stub.body
                      if isinstance(n, ast.ClassDef) and n.name == "FourierTrajectory")
    setpoints = next(n for n in trajectory.body
                     if isinstance(n, ast.FunctionDef) and n.name == "setpoints")
    assert setpoints.args.defaults[-1].value == float(flags["rate"]) == 200.0
    # Keywords are the library's, each function's own.
    with pytest.raises(TypeError, match="unexpected keyword argument 'draws'"):
        di.excite(di.Model.load("psm_simplified"), draws=2)
    with pytest.raises(TypeError, match="unexpected keyword argument 'seed'"):
        trajectory = di.FourierTrajectory(order=1, base_frequency_hz=0.5, q0=[0.0] * 7,
                                          a=[[0.1]] * 7, b=[[0.0]] * 7)
        di.evaluate_trajectory(di.Model.load("psm_simplified"), trajectory, seed=1)
    with pytest.raises(TypeError, match="^starts: invalid type"):
        di.excite(di.Model.load("psm_simplified"), starts=2.5)
    with pytest.raises(di.InputError, match="^criterion: unknown criterion"):
        di.excite(di.Model.load("psm_simplified"), criterion="trace")

