"""Logs: Data from numpy, the three file layouts (headered CSV, 2019 CSV, ROS 2 MCAP)
written and read back, measured ↔ model coordinates, MCAP options."""

import json
import subprocess

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO, shared_file


def small(psm, n=50, velocities=True):
    t = np.arange(n) / 200.0
    rng = np.random.default_rng(4)
    q = rng.uniform(-1, 1, (n, 7))
    # Within the PSM's insertion range (0 to 0.24 m), so that the logs read as a PSM's.
    q[:, 2] = rng.uniform(0.05, 0.2, n)
    dq = rng.uniform(-1, 1, (n, 7)) if velocities else None
    tau = rng.uniform(-1, 1, (n, 7))
    return t, q, dq, tau


def test_data_from_numpy(psm):
    t, q, dq, tau = small(psm)
    d = di.JointLog(t, q, tau, dq=dq)
    assert len(d) == 50 and d.dof == 7
    assert d.coordinates == "model" and d.joint_names == psm.coordinates
    assert d.source == "numpy" and d.path is None
    assert abs(d.rate - 200.0) < 1e-9
    for got, want in [(d.time, t), (d.q, q), (d.dq, dq), (d.tau, tau)]:
        assert got.dtype == np.float64
        np.testing.assert_array_equal(got, want)
    # Attributes are copies.
    d.q[0, 0] = 99.0
    assert d.q[0, 0] == q[0, 0]
    assert di.JointLog(t, q, tau).dq is None
    assert "50 samples, 7 joints, model coordinates" in repr(d)


@pytest.mark.parametrize("fmt,suffix", [("csv", ".csv"), ("wpi", ".csv"), ("mcap", ".mcap")])
def test_round_trip(psm, tmp_path, fmt, suffix):
    t, q, dq, tau = small(psm)
    if fmt == "mcap":  # JointState messages hold measured joints
        d = di.JointLog(t, q, tau, dq=dq, joint_names=psm.measured_joints, coordinates="measured")
    else:
        d = di.JointLog(t, q, tau, dq=dq)
    path = tmp_path / f"log{suffix}"
    d.write(path, format=fmt)
    # The rate only for the layout without time stamps: the others refuse it.
    rate = 200 if fmt == "wpi" else None
    back = di.read_log(path, psm, format=fmt if fmt != "wpi" else "wpi-csv", rate=rate)
    assert back.path == path.resolve()
    assert len(back) == 50
    np.testing.assert_array_equal(back.q, q)
    np.testing.assert_array_equal(back.dq, dq)
    np.testing.assert_array_equal(back.tau, tau)
    np.testing.assert_allclose(back.time, t, atol=1e-9)
    assert back.coordinates == d.coordinates
    assert back.joint_names == d.joint_names
    # Detected from the file when format is None.
    np.testing.assert_array_equal(di.read_log(path, rate=rate).q, q)
    if fmt != "wpi":
        with pytest.raises(di.InputError, match=r"the sampling rate \(rate=\) applies to the 2019 layout only"):
            di.read_log(path, rate=200)


def test_measured_to_model(psm, tmp_path):
    t, q, dq, tau = small(psm)
    C = psm.coupling
    measured = di.JointLog(
        t, q @ C.T, tau @ np.linalg.inv(C), dq=dq @ C.T,
        joint_names=psm.measured_joints, coordinates="measured", source="sim",
    )
    model = measured.to_model(psm)
    assert model.coordinates == "model" and model.joint_names == psm.coordinates
    np.testing.assert_allclose(model.q, q, atol=1e-12)
    np.testing.assert_allclose(model.dq, dq, atol=1e-12)
    np.testing.assert_allclose(model.tau, tau, atol=1e-12)
    # Columns are matched by name: any order, extra joints ignored.
    order = [3, 0, 6, 1, 5, 2, 4]
    shuffled = di.JointLog(
        t,
        np.hstack([(q @ C.T)[:, order], np.ones((50, 1))]),
        np.hstack([(tau @ np.linalg.inv(C))[:, order], np.ones((50, 1))]),
        joint_names=[psm.measured_joints[k] for k in order] + ["extra"],
        coordinates="measured",
    )
    np.testing.assert_allclose(shuffled.to_model(psm).q, q, atol=1e-12)
    # Model data are returned as they are.
    np.testing.assert_array_equal(model.to_model(psm).q, model.q)
    # An MCAP of measured joints, read back with the robot's check.
    measured.write(tmp_path / "m.mcap", topic="/PSM1/measured_js")
    back = di.read_log(tmp_path / "m.mcap", psm)
    assert back.coordinates == "measured" and back.joint_names == psm.measured_joints
    np.testing.assert_allclose(back.to_model(psm).q, q, atol=1e-12)
    topics = di.list_topics(tmp_path / "m.mcap")
    assert topics == [{
        "topic": "/PSM1/measured_js", "schema_name": "sensor_msgs/msg/JointState",
        "message_encoding": "cdr", "messages": 50,
    }]
    assert len(di.read_log(tmp_path / "m.mcap", topic="/PSM1/measured_js")) == 50
    assert len(di.read_log(tmp_path / "m.mcap", topic=["/PSM1/measured_js"],
                           time_source="log")) == 50
    with pytest.raises(di.InputError, match="/nope"):
        di.read_log(tmp_path / "m.mcap", topic="/nope")
    # The MTM's joints are not in this log.
    with pytest.raises(di.InputError, match="robot mtm is missing"):
        di.read_log(tmp_path / "m.mcap", di.Model.load("mtm"))


def test_mcap_without_velocities_and_resampling(psm, tmp_path):
    t, q, _, tau = small(psm, velocities=False)
    t = t.copy()
    t[30:] += 0.5 * (t[1] - t[0])  # a jittered step
    d = di.JointLog(t, q, tau, joint_names=psm.measured_joints, coordinates="measured")
    d.write(tmp_path / "j.mcap")
    with pytest.raises(di.InputError, match="resample"):
        di.read_log(tmp_path / "j.mcap")
    r = di.read_log(tmp_path / "j.mcap", resample=200.0)
    assert r.dq is None
    assert abs(r.rate - 200.0) < 1e-6
    # observe reads the file itself: its resample keyword, a processing setting, reads
    # the recording at that rate too (as `dvrk-ident observe --resample` does).
    with pytest.raises(di.InputError, match="resample"):
        di.observe(psm, tmp_path / "j.mcap", cutoff="none", trim=0)
    obs = di.observe(psm, tmp_path / "j.mcap", resample=200.0, cutoff="none", trim=0)
    assert obs.samples == len(r)
    assert obs.processing["resample_hz"] == 200.0


def test_wpi_write_needs_model_coordinates(psm, tmp_path):
    t, q, dq, tau = small(psm)
    d = di.JointLog(t, q, tau, dq=dq, joint_names=psm.measured_joints, coordinates="measured")
    with pytest.raises(di.InputError, match="model coordinates"):
        d.write(tmp_path / "x.csv", format="wpi")
    with pytest.raises(di.InputError, match="topic"):
        d.write(tmp_path / "x.csv", topic="/x")


def test_prepare(psm, psm_excitation):
    e = psm_excitation
    data = di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"])
    p = di.prepare(psm, data, cutoff=5.0)
    n = len(e["t"]) - 400  # 200 trimmed at each end by default
    assert len(p) == n
    for a in (p.q, p.dq, p.ddq, p.tau):
        assert a.shape == (n, 7) and a.dtype == np.float64
    assert p.time.shape == (n,)
    np.testing.assert_allclose(p.time, e["t"][200:-200])
    assert p.joint_names == psm.coordinates
    # Filtering at 5 Hz barely touches 0.1-0.5 Hz motion: q and ddq stay close.
    np.testing.assert_allclose(p.q, e["q"][200:-200], atol=1e-5)
    np.testing.assert_allclose(p.ddq, e["ddq"][200:-200], atol=1e-3)
    assert len(di.prepare(psm, data, cutoff=5.0, trim=10, decimate=2)) == (len(e["t"]) - 20 + 1) // 2
    unfiltered = di.prepare(psm, data, settings={"processing": {"filter": None}}, trim=0)
    np.testing.assert_array_equal(unfiltered.q, e["q"])
    # filter_torque is fit's keyword too: the torques get the motion's low-pass, as with
    # the settings' processing.filter_torque; unfiltered, they are the logged ones.
    np.testing.assert_array_equal(p.tau, e["noisy"][200:-200])
    smooth = di.prepare(psm, data, cutoff=5.0, filter_torque=True)
    same = di.prepare(psm, data, cutoff=5.0, settings={"processing": {"filter_torque": True}})
    np.testing.assert_array_equal(smooth.tau, same.tau)
    np.testing.assert_array_equal(smooth.q, p.q)
    # The low-pass takes out part of the white noise added to the simulated torques (the
    # error's spread drops to 0.65 of the logged torques'; the Coulomb steps it smooths
    # keep it from dropping further).
    assert np.std(smooth.tau - e["tau"][200:-200]) < 0.75 * np.std(p.tau - e["tau"][200:-200])


def test_shared_mcap_anchor(psm):
    """The MCAP written by the official ROS 2 Python writer (../shared/anchors)."""
    path = shared_file("anchors", "psm_joint_states_sample.mcap")
    ref = json.loads(shared_file("anchors", "psm_joint_states_sample.json").read_text())
    data = di.read_log(path, psm, topic="/PSM1/measured_js")
    assert len(data) == 2000 and data.joint_names == ref["joint_names"]
    for k in (0, 1, 1000, 1999):
        spot = ref["spot_values"][f"k={k}"]
        np.testing.assert_allclose(data.q[k], spot["position"], rtol=0, atol=1e-15)
        np.testing.assert_allclose(data.dq[k], spot["velocity"], rtol=0, atol=1e-15)
    names = [t["topic"] for t in di.list_topics(path)]
    assert "/PSM1/measured_js" in names and "/PSM1/setpoint_js" in names


def test_csv_written_by_convert_reads_in_pandas_and_numpy(psm, cli, tmp_path):
    # The header is the first line: no options needed in any CSV reader.
    pandas = pytest.importorskip("pandas")

    def run_cli(*args):
        subprocess.run([cli, *args], check=True, capture_output=True)

    out = tmp_path / "log.csv"
    run_cli("convert", str(REPO / "examples" / "psm_excitation.mcap"), str(out))
    df = pandas.read_csv(out)
    joints = psm.measured_joints
    assert list(df.columns) == (["time"] + [f"position.{j}" for j in joints]
                                + [f"velocity.{j}" for j in joints]
                                + [f"effort.{j}" for j in joints])
    back = di.read_log(out, psm)
    assert len(df) == len(back)
    np.testing.assert_array_equal(df[[f"effort.{j}" for j in joints]].to_numpy(),
                                  di.read_log(out).tau)
    table = np.genfromtxt(out, names=True, delimiter=",")
    assert table.dtype.names[0] == "time" and len(table) == len(df)
    np.testing.assert_array_equal(table["time"], df["time"].to_numpy())
    # Model coordinates are written as q1..qn and read back as such.
    model = tmp_path / "model.csv"
    run_cli("convert", str(out), str(model), "--robot", "psm", "--coordinates", "model")
    dm = pandas.read_csv(model)
    assert list(dm.columns[:8]) == ["time"] + [f"position.q{k}" for k in range(1, 8)]
    assert di.read_log(model).coordinates == "model"
