"""`external_torque` against `dvrk-ident residual` on the same log (one library function
behind both), and `MomentumObserver` against its closed-form response to a torque step."""

import json

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO


def read_csv(path):
    """The `residual --out` layout: a `time,<joints>` header, then numbers."""
    lines = path.read_text().splitlines()
    names = lines[0].split(",")[1:]
    values = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    return names, values[:, 0], values[:, 1:]


@pytest.fixture(scope="module")
def pushed(psm, tmp_path_factory):
    """An OLS fit (with Stribeck terms) of the bundled example, written as a result
    document, and the bundled log in model coordinates with a push of 0.05 N·m on q1
    from its middle on (the plain log and the pushed one)."""
    log = REPO / "examples" / "psm_excitation.mcap"
    if not log.exists():
        pytest.skip(f"{log} not found")
    d = tmp_path_factory.mktemp("residual")
    data = di.read_log(log, psm).to_model(psm)
    result = di.fit(psm, data, method="ols", stribeck=0.3)
    result.write(d / "fit.json")
    tau = data.tau.copy()
    half = len(data) // 2
    tau[half:, 0] += 0.05
    push = di.JointLog(data.time, data.q, tau, dq=data.dq, joint_names=data.joint_names,
                       coordinates="model")
    push.write(d / "pushed.csv")
    return dict(dir=d, result=result, plain=data, pushed=push,
                t_push=data.time[half])


@pytest.mark.parametrize("joints", ["model", "measured"])
def test_external_torque_is_the_cli_residual(pushed, cli, joints):
    import subprocess

    d = pushed["dir"]
    out, obs = d / f"residual_{joints}.csv", d / f"observer_{joints}.csv"
    args = [cli, "residual", d / "fit.json", d / "pushed.csv", "--observer-gain", "30",
            "--trim", "50", "--joints", joints, "--out", out, "--observer-out", obs, "--json"]
    run = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)["residuals"][0]
    r = di.external_torque(pushed["result"], di.read_log(d / "pushed.csv"),
                           observer_gain=30, trim=50, joints=joints)
    names, t, residual = read_csv(out)
    _, t_obs, observer = read_csv(obs)
    assert names == r["joints"] == summary["joints"]
    assert r["residual"].shape == residual.shape and len(r["time"]) == summary["samples"]
    np.testing.assert_allclose(r["time"], t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["time"], t_obs, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["residual"], residual, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["observer"], observer, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["rms"], summary["rms"], rtol=1e-12)
    if joints == "model":  # the fit's own joints: its training error is the floor
        np.testing.assert_allclose(r["noise_floor"], summary["noise_floor"], rtol=1e-12)
        np.testing.assert_allclose(
            r["noise_floor"], pushed["result"].metrics["train"]["rms"], rtol=1e-12)
    assert r["observer_gain"] == 30

    df = di.external_torque(pushed["result"], di.read_log(d / "pushed.csv"),
                            observer_gain=30, trim=50, joints=joints, as_dataframe=True)
    assert list(df.columns) == (["time"] + [f"residual.{n}" for n in names]
                                + [f"observer.{n}" for n in names])
    np.testing.assert_array_equal(df[f"residual.{names[0]}"].to_numpy(), r["residual"][:, 0])
    np.testing.assert_array_equal(df.attrs["rms"], r["rms"])


def test_the_push_is_what_the_residual_adds(pushed):
    """The model's prediction does not depend on the measured torque (unfiltered here),
    so the pushed log's residual is the plain log's plus the push exactly, and the
    observer's settles on the push."""
    result = pushed["result"]
    plain = di.external_torque(result, pushed["plain"], trim=50)
    push = di.external_torque(result, pushed["pushed"], trim=50)
    np.testing.assert_array_equal(plain["time"], push["time"])
    step = np.where(push["time"] >= pushed["t_push"], 0.05, 0.0)
    np.testing.assert_allclose(push["residual"][:, 0] - plain["residual"][:, 0], step,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(push["residual"][:, 1:], plain["residual"][:, 1:],
                               rtol=0, atol=1e-12)
    # 20 /s: five time constants (0.25 s) after the push, the observers differ by it
    # to within e^-5 of it.
    late = push["time"] >= pushed["t_push"] + 0.25
    gap = push["observer"][late, 0] - plain["observer"][late, 0]
    assert np.all(np.abs(gap - 0.05) < 0.05 * np.exp(-5) * 1.05), np.abs(gap - 0.05).max()


def test_external_torque_refuses_a_bad_gain(pushed):
    with pytest.raises(di.InputError, match="observer_gain"):
        di.external_torque(pushed["result"], pushed["plain"], observer_gain=0.0)


def test_observer_step_response_is_the_closed_form(psm, pushed):
    """A PSM whose torque is its inverse dynamics (Newton–Euler) plus a step at t_step,
    observed at 1 kHz with gains 20–80 /s: each estimate is the exact discrete response
    of a first-order lag, s·(1 − α^(k−k0)·(1 + α)/2) with α = e^(−K·dt) (the trapezoid
    sees half the step over its first interval), to the integration error of the motion,
    and within 1 % of s·(1 − e^(−K·(t − t_step))) after three time constants."""
    result = pushed["result"]
    dt, k0 = 1e-3, 300
    t = np.arange(900) * dt
    w = 2.0 + 0.4 * np.arange(psm.dof)
    amp = np.where(np.arange(psm.dof) == 2, 0.02, 0.3)
    centre = np.where(np.arange(psm.dof) == 2, 0.12, 0.0)
    q = centre + amp * np.sin(np.outer(t, w))
    dq = amp * w * np.cos(np.outer(t, w))
    ddq = -amp * w**2 * np.sin(np.outer(t, w))
    s = 0.1 * (1 + np.arange(psm.dof))
    tau = psm.inverse_dynamics(result, q, dq, ddq) + psm.known_forces(q)
    tau[k0:] += s
    gains = 20.0 + 10.0 * np.arange(psm.dof)
    obs = di.MomentumObserver(psm, result, gains)
    r = obs.update(q, dq, tau, dt)
    assert r.shape == q.shape
    np.testing.assert_array_equal(obs.gains, gains)
    np.testing.assert_array_equal(obs.estimate, r[-1])

    alpha = np.exp(-gains * dt)
    k = np.arange(len(t))[:, None]
    discrete = np.where(k >= k0, s * (1 - alpha ** np.maximum(k - k0, 0) * (1 + alpha) / 2), 0.0)
    assert np.all(r[0] == 0.0)
    assert np.abs(r - discrete).max() < 2e-3 * s.max(), np.abs(r - discrete).max()
    t_step = (k0 - 0.5) * dt
    continuous = s * (1 - np.exp(-gains * (t[:, None] - t_step)))
    settled = t[:, None] - t_step >= 3.0 / gains
    err = np.abs(r - continuous) / s
    assert err[settled].max() < 0.01, err[settled].max()

    # One sample at a time is the batch, bit for bit; reset starts again at zero.
    again = di.MomentumObserver(psm, result, gains)
    one = np.array([again.update(q[i], dq[i], tau[i], dt) for i in range(len(t))])
    np.testing.assert_array_equal(one, r)
    again.reset()
    assert np.all(again.update(q[5], dq[5], tau[5], dt) == 0.0)
    assert np.all(again.estimate == 0.0)
    # Steps per sample: the same steps give the same estimates.
    third = di.MomentumObserver(psm, result, gains)
    np.testing.assert_array_equal(third.update(q, dq, tau, np.full(len(t), dt)), r)


def test_observer_refuses_bad_input(psm, pushed):
    result = pushed["result"]
    with pytest.raises(di.InputError, match="gains"):
        di.MomentumObserver(psm, result, [20.0] * 3)
    with pytest.raises(di.InputError, match="positive and finite"):
        di.MomentumObserver(psm, result, -1.0)
    obs = di.MomentumObserver(psm, result)
    np.testing.assert_array_equal(obs.gains, np.full(psm.dof, 20.0))
    z = np.zeros(psm.dof)
    with pytest.raises(di.InputError, match="dt"):
        obs.update(z, z, z, 0.0)
    with pytest.raises(di.InputError, match="non-finite"):
        obs.update(z, z + np.nan, z, 1e-3)
    with pytest.raises(di.InputError, match="shape"):
        obs.update(np.zeros((3, psm.dof)), z, z, 1e-3)


def test_wrench_is_the_cli_wrench(pushed, cli):
    """`external_torque(..., wrench=)` and `residual --wrench --wrench-out` on the same
    log: one library function, the same numbers; an unknown frame is refused naming the
    robot's frames."""
    import subprocess

    d = pushed["dir"]
    out = d / "wrench.csv"
    args = [cli, "residual", d / "fit.json", d / "pushed.csv", "--trim", "50",
            "--wrench", "tool_tip", "--wrench-out", out, "--json"]
    run = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)["residuals"][0]["wrench"]
    r = di.external_torque(pushed["result"], di.read_log(d / "pushed.csv"), trim=50,
                           wrench="tool_tip")
    w = r["wrench"]
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    values = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    assert header[1:7] == [f"{c}_base" for c in w["components"]]
    assert header[7:13] == [f"{c}_tip" for c in w["components"]] and header[13] == "rank"
    assert w["frame"] == "tool_tip" and w["rcond"] == 1e-6
    np.testing.assert_allclose(values[:, 0], r["time"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(values[:, 1:7], w["base"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(values[:, 7:13], w["tip"], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(values[:, 13], w["rank"])
    assert summary["min_rank"] == w["rank"].min() == 6
    np.testing.assert_allclose(np.sqrt(np.mean(w["base"] ** 2, axis=0)), summary["rms_base"],
                               rtol=1e-12)
    assert all(u.shape == (6 - k, 6) for u, k in zip(w["unsensed_base"], w["rank"]))
    # The tip's axes turn the force and the moment alike: their norms are the base's.
    for a, b in ((0, 3), (3, 6)):
        np.testing.assert_allclose(np.linalg.norm(w["tip"][:, a:b], axis=1),
                                   np.linalg.norm(w["base"][:, a:b], axis=1), rtol=1e-9)
    df = di.external_torque(pushed["result"], di.read_log(d / "pushed.csv"), trim=50,
                            wrench="tool_tip", as_dataframe=True)
    np.testing.assert_array_equal(df["wrench_tip.fz"].to_numpy(), w["tip"][:, 2])
    assert df.attrs["wrench_frame"] == "tool_tip"
    assert di.external_torque(pushed["result"], pushed["plain"])["wrench"] is None
    with pytest.raises(di.InputError, match=r"no frame `nowhere`.*tool_tip"):
        di.external_torque(pushed["result"], pushed["plain"], wrench="nowhere")
