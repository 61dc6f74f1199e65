"""Data that behaves: DataFrames in and out (columns matched by joint name, model or
measured coordinates inferred), exact times, slicing and concatenation, pickling of
Robot, Data, Result and Trajectory, through multiprocessing too."""

import copy
import multiprocessing
import pickle

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO, excitation

pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def logs(psm):
    e = excitation(psm, seconds=20.0)
    model = di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"])
    C = psm.coupling
    meas = di.JointLog(e["t"], e["q"] @ C.T, e["noisy"] @ np.linalg.inv(C), dq=e["dq"] @ C.T,
                   joint_names=psm.measured_joints)
    return model, meas


def same(a, b):
    assert a.joint_names == b.joint_names and a.coordinates == b.coordinates
    for x, y in [(a.time, b.time), (a.q, b.q), (a.tau, b.tau)]:
        np.testing.assert_array_equal(x, y)
    if a.dq is None:
        assert b.dq is None
    else:
        np.testing.assert_array_equal(a.dq, b.dq)


def test_dataframe_round_trip_and_coordinates(psm, logs):
    model, meas = logs
    for d in (model, meas):
        df = d.to_dataframe()
        assert list(df.columns[:2]) == ["time", f"position.{d.joint_names[0]}"]
        same(di.JointLog.from_dataframe(df, psm), d)
        same(di.JointLog.from_dataframe(df), d)
    assert meas.coordinates == "measured" and model.coordinates == "model"
    # A MultiIndex (signal, joint) with the time as a timedelta index, columns shuffled.
    df = meas.to_dataframe()
    t = df.pop("time")
    df.columns = pd.MultiIndex.from_tuples([tuple(c.split(".", 1)) for c in df.columns])
    df.index = pd.to_timedelta(np.round(t.to_numpy() * 1e9).astype(np.int64), unit="ns")
    back = di.JointLog.from_dataframe(df[df.columns[::-1]], psm)
    assert back.joint_names == list(reversed(psm.measured_joints))
    np.testing.assert_array_equal(back.time, df.index.to_numpy().astype(np.int64) / 1e9)
    np.testing.assert_array_equal(back.to_model(psm).q, meas.to_model(psm).q)
    # Names that are neither the robot's coordinates nor its measured joints.
    bad = model.to_dataframe().rename(columns=lambda c: c.replace(".q3", ".outer_insertion"))
    with pytest.raises(di.InputError, match="neither coordinates of robot"):
        di.JointLog.from_dataframe(bad, psm)
    with pytest.raises(di.InputError, match='missing effort column for joint "q2"'):
        di.JointLog.from_dataframe(model.to_dataframe().drop(columns="effort.q2"))
    with pytest.raises(di.InputError, match="no sample times"):
        di.JointLog.from_dataframe(model.to_dataframe().drop(columns="time"))


def test_dataframe_columns_are_joint_names(psm, logs):
    """Data(t, q_df, tau_df): the column names are the joints (not q1..qn), tau's
    columns matched to q's by name."""
    _, meas = logs
    q = pd.DataFrame(meas.q, columns=meas.joint_names)
    tau = pd.DataFrame(meas.tau, columns=meas.joint_names)[meas.joint_names[::-1]]
    d = di.JointLog(meas.time, q, tau)
    assert d.coordinates == "measured" and d.joint_names == psm.measured_joints
    np.testing.assert_array_equal(d.tau, meas.tau)
    with pytest.raises(di.InputError, match="differ from q's columns"):
        di.JointLog(meas.time, q, tau, joint_names=psm.coordinates)


def test_times(psm, logs):
    model, _ = logs
    n = len(model)
    ns = 1_700_000_000_123_456_789 + np.arange(n, dtype=np.int64) * 5_000_000
    want = (np.arange(n) * 5_000_000) / 1e9
    for t in (ns, ns.astype("datetime64[ns]"), pd.to_datetime(ns).tz_localize("UTC"),
              pd.Series(pd.to_datetime(ns)), (ns - ns[0]).astype("timedelta64[ns]")):
        d = di.JointLog(t, model.q, model.tau)
        np.testing.assert_array_equal(d.time, want)
        assert abs(d.rate - 200.0) < 1e-9
    with pytest.raises(di.InputError, match="NaT"):
        di.JointLog(np.array(["NaT"] * n, dtype="datetime64[ns]"), model.q, model.tau)
    # Exact times give the same fit as the float times they equal.
    a = di.fit(psm, di.JointLog(ns, model.q, model.tau, dq=model.dq), method="ols")
    b = di.fit(psm, di.JointLog(want, model.q, model.tau, dq=model.dq), method="ols")
    assert a.parameters == b.parameters


def test_slicing_and_concat(psm, logs):
    model, _ = logs
    part = model[100:400]
    assert len(part) == 300
    np.testing.assert_array_equal(part.q, model.q[100:400])
    np.testing.assert_array_equal(part.time, model.time[100:400])
    assert len(model[::2]) == (len(model) + 1) // 2
    with pytest.raises(di.InputError):
        model[::-1]
    with pytest.raises(di.InputError):
        model[3]
    joined = di.JointLog.concat([model[:1000], model[1000:]])
    same(joined, model)
    with pytest.raises(di.InputError, match="not after"):
        di.JointLog.concat([model[1000:], model[:1000]])
    with pytest.raises(di.InputError, match="joints"):
        di.JointLog.concat([model, logs[1]])


def test_prepared_and_predictions_as_dataframes(psm, logs):
    model, _ = logs
    r = di.fit(psm, model, method="ols")
    p = r.prepare(model)
    df = p.to_dataframe()
    np.testing.assert_array_equal(df["time"], p.time)
    np.testing.assert_array_equal(df["acceleration.q2"], p.ddq[:, 1])
    pred = r.predict(model, as_dataframe=True)
    np.testing.assert_array_equal(pred["time"], p.time)
    np.testing.assert_array_equal(pred[[f"effort.{c}" for c in psm.coordinates]].to_numpy(),
                                  r.predict(model))


def test_pickle_and_deepcopy(psm, logs, tmp_path):
    model, meas = logs
    r = di.fit(psm, [model[:2000], model[2000:]], method="ols")
    traj = di.FourierTrajectory(2, 0.2, np.zeros(7), np.full((7, 2), 0.01), np.zeros((7, 2)))
    # A description from a file: pickled by its text, independent of the file after.
    text = (REPO / "robots" / "psm.toml").read_text()
    desc = tmp_path / "psm.toml"
    desc.write_text(text)
    from_file = di.Model.load(str(desc))
    for obj in (psm, from_file, di.Model.from_toml(text, "inline"), model, meas, r, traj):
        for copied in (pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj)):
            assert type(copied) is type(obj)
            if isinstance(obj, di.Model):
                assert copied.parameter_names == obj.parameter_names
                x = np.full(7, 0.1)
                np.testing.assert_array_equal(copied.regressor(x), obj.regressor(x))
            elif isinstance(obj, di.JointLog):
                same(copied, obj)
                assert copied.path == obj.path
            elif isinstance(obj, di.FitResult):
                assert copied.to_json() == obj.to_json()
                np.testing.assert_array_equal(copied.predict(model), obj.predict(model))
            else:
                assert copied == obj
    desc.unlink()
    restored = pickle.loads(pickle.dumps(from_file))
    assert restored.n_parameters == psm.n_parameters
    # A result with Stribeck terms pickles with its extended robot.
    rs = di.fit(psm, model, method="ols", settings={"stribeck_velocity": 0.3})
    extended = di.FitResult.from_json(rs.to_json()).load_robot()
    back = pickle.loads(pickle.dumps(extended))
    assert back.n_parameters == extended.n_parameters > psm.n_parameters


def test_multiprocessing_round_trip(psm, logs):
    import mp_worker

    model, _ = logs
    test = model[3000:]
    train = [model[:1500], model[1500:3000]]
    local = di.fit(psm, train, method="ols", test=test)
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        robot, data, remote = pool.map(mp_worker.fit_in_child, [(psm, train, test)])[0]
    assert remote.to_json().replace(
        str(remote.solver["seconds"]), "") == local.to_json().replace(str(local.solver["seconds"]), "")
    assert robot.parameter_names == psm.parameter_names
    same(data[1], train[1])


@pytest.mark.parametrize("columns", [
    ["time", "position.a", "q.a", "effort.a"],
    ["time", "position.a", "effort.a", "speed.a"],
    ["time", "position.a", "effort.a", "effort.b"],
    ["time", "position.a", "position.b", "effort.a"],
    ["time", "position.a", "position.b", "effort.a", "effort.b", "velocity.b"],
    ["time", "effort.a"],
])
def test_a_dataframe_and_a_csv_share_one_column_grammar(tmp_path, columns):
    """The same columns give the same verdict, word for word, from a DataFrame and from
    the headered CSV (dvrk_logs::columns, one grammar for both)."""
    df = pd.DataFrame([[0.01 * (k + 1) for k in range(len(columns))]], columns=columns)
    path = tmp_path / "log.csv"
    df.to_csv(path, index=False)
    with pytest.raises(di.InputError) as from_df:
        di.JointLog.from_dataframe(df)
    with pytest.raises(di.InputError) as from_csv:
        di.read_log(path)
    assert str(from_df.value).startswith("df: ")
    assert str(from_csv.value).startswith(f"{path}:1: ")
    assert str(from_df.value)[len("df: "):] == str(from_csv.value)[len(f"{path}:1: "):]


def test_aliases_read_alike_from_a_dataframe_and_a_csv(tmp_path):
    columns = ["time", "q.q1", "tau.q1", "position.q2", "torque.q2", "dq.q1", "velocity.q2"]
    df = pd.DataFrame([[0.0, 1, 2, 3, 4, 5, 6], [0.01, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5]], columns=columns)
    path = tmp_path / "log.csv"
    df.to_csv(path, index=False)
    a, b = di.JointLog.from_dataframe(df), di.read_log(path)
    assert a.joint_names == b.joint_names == ["q1", "q2"]
    assert a.coordinates == b.coordinates == "model"
    for signal in ("q", "dq", "tau"):
        np.testing.assert_array_equal(getattr(a, signal), getattr(b, signal))
    np.testing.assert_array_equal(a.q, [[1, 3], [1.5, 3.5]])
