"""No Rust panic reaches Python: every public function and method, given wrong lengths,
shapes, types, results of another robot or model, and NaN, raises an ``Exception``
(a ``DvrkError`` for what the module checks), never pyo3's ``PanicException`` (a
``BaseException``, which ``except Exception`` does not catch).

The first defect of the front-door issue: a result fitted with Stribeck terms (125
parameters) given to ``Model.inverse_dynamics`` of the plain PSM (115) panicked."""

import inspect
import json
import subprocess

import numpy as np
import pytest

import dvrk_ident as di

# The complex arrays among the bad values are cast by numpy, which warns.
pytestmark = pytest.mark.filterwarnings("ignore:Casting complex values")


@pytest.fixture(scope="module")
def results(psm, mtm, psm_logs):
    """A plain and a Stribeck result of the PSM, and an MTM result."""
    train = di.read_log(psm_logs["csv"])
    plain = di.fit(psm, train, method="ols", cutoff=5.0)
    # Physically consistent, so that forward dynamics has a positive definite mass matrix.
    stribeck = di.fit(psm, train, method="sdp", cutoff=5.0, stribeck=0.3)
    e = _mtm_log(mtm)
    other = di.fit(mtm, e, method="ols", cutoff=5.0)
    return dict(plain=plain, stribeck=stribeck, mtm=other)


def _mtm_log(mtm):
    from conftest import excitation

    e = excitation(mtm, seconds=30.0)
    return di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"], source="synthetic mtm")


def test_stribeck_result_evaluates_with_its_own_model(psm, results, psm_logs, tmp_path, cli):
    """The README's pattern with a Stribeck result: the plain robot's methods evaluate
    it with the result's model, as the command line does."""
    r = results["stribeck"]
    fitted = r.load_robot()
    assert fitted.n_parameters == psm.n_parameters + 10
    rng = np.random.default_rng(3)
    q = rng.uniform(-0.3, 0.3, (5, 7))
    q[:, 2] = 0.12
    dq = rng.uniform(-0.5, 0.5, (5, 7))
    ddq = rng.uniform(-1.0, 1.0, (5, 7))
    tau = psm.inverse_dynamics(r, q, dq, ddq)
    # The identity H(q, dq, ddq) @ params of the result's own model.
    H = fitted.regressor(q, dq, ddq)
    expected = (H @ r.parameter_array).reshape(-1, 7)
    np.testing.assert_allclose(tau, expected, rtol=1e-12, atol=1e-12)
    # The Stribeck terms are in it: the plain result's friction law differs.
    assert np.abs(tau - psm.inverse_dynamics(r.parameter_array[:115], q, dq, ddq)).max() > 1e-6
    np.testing.assert_allclose(psm.gravity(r, q), fitted.gravity(r, q), rtol=0, atol=0)
    np.testing.assert_allclose(psm.mass_matrix(r, q), fitted.mass_matrix(r, q), rtol=0, atol=0)
    acc = psm.forward_dynamics(r, q, dq, tau)
    np.testing.assert_allclose(acc, ddq, rtol=1e-6, atol=1e-6)
    # The command line evaluates the same result file to the same torque.
    path = tmp_path / "stribeck.json"
    r.write(path)
    out = subprocess.run(
        [cli, "model", "psm", "--torque", "--params", str(path),
         "--q", ",".join(map(repr, q[0].tolist())), "--dq", ",".join(map(repr, dq[0].tolist())),
         "--ddq", ",".join(map(repr, ddq[0].tolist()))],
        capture_output=True, text=True, check=True,
    )
    np.testing.assert_allclose(json.loads(out.stdout)["tau"], tau[0], rtol=1e-12, atol=1e-12)


def test_result_of_another_robot_in_one_line(psm, results, tmp_path, cli):
    with pytest.raises(di.InputError) as e:
        psm.inverse_dynamics(results["mtm"], np.zeros(7))
    assert str(e.value) == "FitResult was fitted for mtm, not psm"
    with pytest.raises(di.InputError, match="^FitResult was fitted for psm, not mtm$"):
        results["plain"].predict(_mtm_log(di.Model.load("mtm")), robot=di.Model.load("mtm"))
    path = tmp_path / "mtm.json"
    results["mtm"].write(path)
    r = subprocess.run(
        [cli, "model", "psm", "--torque", "--params", str(path), "--q", "0,0,0.1,0,0,0,0"],
        capture_output=True, text=True,
    )
    assert r.returncode == 1
    assert r.stderr.strip() == f"dvrk-ident: error: {path} was fitted for mtm, not psm"
    with pytest.raises(di.InputError, match="BaseParameters|base\\(\\)"):
        psm.base().project(results["stribeck"])


BAD = [
    None,
    "x",
    1.5,
    [],
    [[1.0, 2.0], [3.0]],
    np.zeros(0),
    np.zeros(6),
    np.zeros(8),
    np.zeros((3, 6)),
    np.zeros((2, 7, 1)),
    np.zeros(116),
    np.full(7, np.nan),
    np.full((3, 7), np.inf),
    np.full(115, np.nan),
    np.full(115, 1e308),
    np.zeros(7, dtype=complex),
    {"m1": 1.0},
    {"bogus": np.nan},
    object(),
]


def _call(f, *args, **kwargs):
    """Calls `f`; any `Exception` is fine, anything else (a `PanicException`) fails."""
    try:
        f(*args, **kwargs)
    except Exception:
        pass
    except BaseException as e:  # noqa: BLE001 - the point of the test
        pytest.fail(f"{getattr(f, '__qualname__', f)}{args}: {type(e).__module__}.{type(e).__name__}: {e}")


def _positional(f):
    """Names of the parameters `f` takes positionally (its text signature)."""
    sig = inspect.signature(f)
    return [
        p.name
        for p in sig.parameters.values()
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name != "self"
    ]


def test_walk_model_methods(psm, results):
    """Every array method of Model and BaseParameters with each bad value in each
    position, the others valid; and every result (plain, Stribeck, another robot's)."""
    good = dict(
        q=np.full((2, 7), 0.1), dq=np.zeros((2, 7)), ddq=np.zeros((2, 7)),
        tau=np.zeros((2, 7)), params=results["plain"],
    )
    base = psm.base()
    methods = [
        getattr(psm, name)
        for name in (
            "regressor", "base_regressor", "inverse_dynamics", "gravity", "mass_matrix",
            "forward_dynamics", "known_forces", "forward_kinematics", "to_urdf",
        )
    ] + [base.project, base.regressor]
    called = 0
    for f in methods:
        names = _positional(f)
        assert names, f
        for i, name in enumerate(names):
            for bad in BAD + list(results.values()):
                args = [good[n] for n in names]
                args[i] = bad
                _call(f, *args)
                called += 1
        # Every result as the parameters, with valid states.
        if "params" in names:
            for r in results.values():
                _call(f, *[r if n == "params" else good[n] for n in names])
    assert called > 300


def test_walk_result_methods(psm, mtm, results, psm_logs):
    data = di.read_log(psm_logs["csv"])
    mtm_data = _mtm_log(mtm)
    for r in results.values():
        for robot in (None, psm, mtm):
            for d in (data, mtm_data):
                _call(r.predict, d, robot)
                _call(r.validate, d, None, robot)
                _call(r.prepare, d, robot)
            _call(r.wpi_params, robot)
            _call(r.dvrk_gc, robot)
            for bad in BAD:
                _call(r.predict, bad, robot)
                _call(r.validate, data, bad, robot)
                _call(r.dvrk_gc, robot, bad)
        _call(r.validate, data, 0)
        _call(r.validate, data, -1)
        _call(r.dvrk_gc, None, 0)
        _call(r.dvrk_gc, None, 10**9)


def test_walk_logs_and_fits(psm, mtm, psm_logs, tmp_path):
    data = di.read_log(psm_logs["csv"])
    t = np.arange(100) / 100.0
    for bad in BAD:
        _call(di.JointLog, bad, np.zeros((100, 7)), np.zeros((100, 7)))
        _call(di.JointLog, t, bad, np.zeros((100, 7)))
        _call(di.JointLog, t, np.zeros((100, 7)), bad)
        _call(di.JointLog, t, np.zeros((100, 7)), np.zeros((100, 7)), dq=bad)
        _call(di.read_log, bad)
        _call(di.fit, psm, bad)
        _call(di.fit, bad, data)
        _call(di.prepare, psm, bad)
        _call(di.observe, psm, bad)
    _call(di.JointLog, t[::-1], np.zeros((100, 7)), np.zeros((100, 7)))
    _call(di.JointLog.concat, [])
    # A log of the MTM fitted as the PSM, and the keyword arguments at absurd values.
    _call(di.fit, psm, _mtm_log(mtm), method="ols")
    for kw in [
        dict(cutoff=np.nan), dict(cutoff=-1.0), dict(cutoff=1e300), dict(trim=-1.0),
        dict(trim=1e300), dict(method="x"), dict(delay="bogus"), dict(delay=[np.nan] * 7),
        dict(stribeck=0.0), dict(stribeck=-1.0), dict(stribeck=np.nan), dict(decimate=0),
        dict(min_speed=np.inf), dict(resample=-5.0), dict(test_window=0),
        dict(sdp_regularization=-1.0), dict(prior="nominal", method="ols"),
        dict(bounds="x"), dict(excitation="x"), dict(settings={"method": 3}),
    ]:
        _call(di.fit, psm, data, **kw)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    _call(di.read_log, empty)
    _call(di.FitResult.read, empty)
    _call(di.FitResult.from_json, "[]")
    _call(di.Observation.from_bytes, b"\x00" * 64)
