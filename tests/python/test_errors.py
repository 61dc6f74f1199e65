"""Errors become exceptions with the Rust message, in a hierarchy under DvrkError that
also derives from the built-in class a Python user expects."""

import json

import numpy as np
import pytest

import dvrk_ident as di


def test_hierarchy():
    assert issubclass(di.InputError, di.DvrkError) and issubclass(di.InputError, ValueError)
    assert issubclass(di.DvrkIOError, di.DvrkError) and issubclass(di.DvrkIOError, OSError)
    assert issubclass(di.DvrkFileNotFoundError, di.DvrkIOError)
    assert issubclass(di.DvrkFileNotFoundError, FileNotFoundError)
    assert issubclass(di.SolverError, di.DvrkError) and issubclass(di.SolverError, RuntimeError)
    assert issubclass(di.NotConvergedError, di.SolverError)
    for cls in (di.DvrkError, di.InputError, di.DvrkIOError, di.SolverError):
        assert cls.__module__ == "dvrk_ident"


def test_unknown_robot():
    with pytest.raises(di.InputError, match=r"unknown robot `nope` \(built-in robots: psm"):
        di.Model.load("nope")
    # A path that does not exist is a missing file, not an unknown robot name.
    with pytest.raises(di.DvrkFileNotFoundError, match="no/such/file.toml"):
        di.Model("no/such/file.toml")


def test_bad_description(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("this is = not [a description")
    with pytest.raises(di.InputError, match="bad.toml"):
        di.Model.load(p)
    with pytest.raises(di.InputError, match="URDF"):
        di.Model.from_urdf("<robot name='x'><link name='a'/><joint/></robot>")


@pytest.mark.parametrize(
    "shape", [(6,), (3, 6), (3, 8), (2, 3, 7), ()],
)
def test_wrong_shapes(psm, shape):
    with pytest.raises(di.InputError, match=r"q: expected shape \(7,\) for one sample or \(N, 7\)"):
        psm.regressor(np.zeros(shape))


def test_mismatched_batches(psm):
    with pytest.raises(di.InputError, match="dq has shape"):
        psm.regressor(np.zeros((3, 7)), np.zeros((4, 7)))
    with pytest.raises(di.InputError, match="ddq has shape"):
        psm.inverse_dynamics(np.zeros(115), np.zeros((3, 7)), None, np.zeros(7))
    # The torques are named as themselves (they were once called ddq).
    with pytest.raises(di.InputError, match=r"^tau: expected shape \(7,\)"):
        psm.forward_dynamics(np.zeros(115), np.zeros(7), np.zeros(7), np.zeros(6))
    with pytest.raises(di.InputError, match="^tau has shape"):
        psm.forward_dynamics(np.zeros(115), np.zeros((3, 7)), np.zeros((3, 7)), np.zeros(7))


def test_nan_and_inf(psm):
    q = np.zeros((4, 7))
    q[2, 3] = np.nan
    with pytest.raises(di.InputError, match=r"q: non-finite value NaN at sample 2, column 3 \(q4\)"):
        psm.regressor(q)
    dq = np.zeros((4, 7))
    dq[1, 0] = np.inf
    with pytest.raises(di.InputError, match="dq: non-finite value inf at sample 1"):
        psm.inverse_dynamics(np.zeros(115), np.zeros((4, 7)), dq)
    params = np.zeros(115)
    params[9] = np.nan
    with pytest.raises(di.InputError, match=r"params: non-finite value NaN at index 9 \(m1\)"):
        psm.gravity(params, np.zeros(7))


def test_not_numbers(psm):
    with pytest.raises(di.InputError, match="q: not convertible to a float64 array"):
        psm.regressor(["a"] * 7)


def test_bad_params(psm):
    with pytest.raises(di.InputError, match=r"params: expected shape \(115,\)"):
        psm.gravity(np.zeros(114), np.zeros(7))
    names = psm.parameter_names
    partial = {n: 0.0 for n in names[1:]}
    with pytest.raises(di.InputError, match="missing parameters: L1xx"):
        psm.gravity(partial, np.zeros(7))
    extra = {n: 0.0 for n in names}
    extra["m99"] = 1.0
    with pytest.raises(di.InputError, match="parameters not in model psm: m99"):
        psm.gravity(extra, np.zeros(7))
    with pytest.raises(di.InputError, match="parameter L1xx is not a number"):
        psm.gravity({**extra, "L1xx": "x"}, np.zeros(7))


def test_missing_files(psm, tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        di.read_log(tmp_path / "nope.csv", format="csv")
    with pytest.raises(di.DvrkFileNotFoundError):
        di.read_log(tmp_path / "nope.mcap")
    with pytest.raises(FileNotFoundError):
        di.FitResult.read(tmp_path / "nope.json")
    with pytest.raises(di.DvrkIOError):
        di.read_log(tmp_path, format="csv")  # a directory


def test_log_errors(psm, tmp_path):
    p = tmp_path / "wpi.csv"
    p.write_text("0.1,0.2,0.3\n0.1,x,0.3\n")
    with pytest.raises(di.InputError, match="rate") as e:
        di.read_log(p, format="wpi")
    # The command line's flag, named as the keyword.
    msg = str(e.value)
    assert "give the sampling rate with rate=HZ" in msg and "--rate" not in msg, msg
    with pytest.raises(di.InputError) as e:
        di.read_log(p, format="wpi", rate=-200)
    msg = str(e.value)
    assert "the sampling rate (rate=) must be positive" in msg and "--rate" not in msg, msg
    with pytest.raises(di.InputError, match=r"wpi.csv:2: column 2 \(dq1\): malformed number"):
        di.read_log(p, format="wpi", rate=200)
    with pytest.raises(di.InputError, match="unknown log format"):
        di.read_log(p, format="xls")
    with pytest.raises(di.InputError, match="recordings .MCAP, rosbag2, sqlite3, ROS 1 bags. only"):
        di.read_log(p, format="wpi", rate=200, topic="/x")
    with pytest.raises(di.InputError, match="time_source"):
        di.read_log(p, time_source="wall")
    # A log with 1 joint is not a PSM log.
    p.write_text("0.1,0.2,0.3\n0.1,0.2,0.3\n")
    with pytest.raises(di.InputError, match="7"):
        di.read_log(p, psm, format="wpi", rate=200)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(di.InputError, match="empty"):
        di.read_log(empty)


def test_data_errors(psm):
    t = np.arange(10) / 200.0
    q = np.zeros((10, 7))
    with pytest.raises(di.InputError, match="time is not strictly increasing"):
        di.JointLog(t[::-1].copy(), q, q)
    bad = q.copy()
    bad[4, 1] = np.nan
    with pytest.raises(di.InputError, match=r"non-finite effort value NaN for joint \"q2\" at sample 4"):
        di.JointLog(t, q, bad)
    with pytest.raises(di.InputError, match="tau has shape 10x6"):
        di.JointLog(t, q, np.zeros((10, 6)))
    with pytest.raises(di.InputError, match="joint_names are required in measured"):
        di.JointLog(t, q, q, coordinates="measured")
    with pytest.raises(di.InputError, match="coordinates"):
        di.JointLog(t, q, q, coordinates="joint")
    with pytest.raises(di.InputError, match="q: expected a 2-D array"):
        di.JointLog(t, np.zeros(10), np.zeros(10))
    measured = di.JointLog(t, q, q, joint_names=[f"j{k}" for k in range(7)], coordinates="measured")
    with pytest.raises(di.InputError, match="joint `outer_yaw` of robot psm is missing"):
        measured.to_model(psm)
    with pytest.raises(di.InputError, match="no sample left|too short|padlen|trimming"):
        di.fit(psm, di.JointLog(t, q, q), method="ols")


def test_fit_setting_errors(psm):
    t = np.arange(2000) / 200.0
    data = di.JointLog(t, np.zeros((2000, 7)), np.zeros((2000, 7)))
    with pytest.raises(di.InputError, match="method: unknown method \"lasso\": expected ols, wls, irls or sdp"):
        di.fit(psm, data, method="lasso")
    with pytest.raises(di.InputError, match="cutoff"):
        di.fit(psm, data, method="ols", cutoff="fast")
    with pytest.raises(di.InputError, match="cut-off 500 Hz") as e:
        di.fit(psm, data, method="ols", cutoff=500.0)
    # The setting the filter's message suggests, named as the keyword.
    msg = str(e.value)
    assert msg.endswith("choose a cutoff= in that range") and "--cutoff" not in msg, msg
    with pytest.raises(di.InputError, match="3 per-joint cut-offs given for 7 joints"):
        di.fit(psm, data, method="ols", cutoff=[1.0, 2.0, 3.0])
    with pytest.raises(di.InputError, match="settings: unknown field `bogus`"):
        di.fit(psm, data, settings={"bogus": 1})
    # A log without motion does not determine the parameters.
    with pytest.raises(di.InputError, match="do not determine the base parameters"):
        di.fit(psm, data, method="ols")


def test_result_json_errors(psm):
    with pytest.raises(di.InputError, match="not a dvrk-ident result"):
        di.FitResult.from_json("{}")
    with pytest.raises(di.InputError, match="not a dvrk-ident result"):
        di.FitResult.from_json("not json")


def test_result_for_another_robot(psm, mtm, psm_logs):
    result = di.fit(psm, di.read_log(psm_logs["csv"]), method="ols", cutoff=5.0)
    with pytest.raises(di.InputError, match="^FitResult was fitted for psm, not mtm$"):
        mtm.inverse_dynamics(result, np.zeros(7))
    doc = json.loads(result.to_json())
    doc["parameters"]["m1"] = None
    with pytest.raises(di.InputError):
        di.FitResult.from_json(json.dumps(doc)).parameter_array
