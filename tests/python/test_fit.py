"""fit and Result against `dvrk-ident fit --json` / `--out` / `validate` on the same
files, the Result API, and Ctrl-C during long calls."""

import json
import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import dvrk_ident as di

TOL = 1e-12


def close(a, b, tol=TOL):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = max(1.0, float(np.max(np.abs(b)))) if b.size else 1.0
    np.testing.assert_allclose(a, b, rtol=tol, atol=tol * scale)


def same_document(py, cli, tol=TOL):
    """Every number of the two result documents to `tol` (relative to the largest
    value of each field); file paths and timings aside."""
    assert py["method"] == cli["method"] and py["robot"] == cli["robot"]
    assert py["robot_source"] == cli["robot_source"]
    assert py["settings"] == cli["settings"]
    assert py["parameter_order"] == cli["parameter_order"]
    assert list(py["parameters"]) == list(cli["parameters"])
    close(list(py["parameters"].values()), list(cli["parameters"].values()), tol)
    for a, b in zip(py["base_parameters"], cli["base_parameters"]):
        assert (a["name"], a["expression"]) == (b["name"], b["expression"])
    for key in ("value", "std"):
        close([b[key] for b in py["base_parameters"]], [b[key] for b in cli["base_parameters"]], tol)
    close([c["min_eigenvalue"] for c in py["consistency"]],
          [c["min_eigenvalue"] for c in cli["consistency"]], tol)
    assert py["physically_consistent"] == cli["physically_consistent"]
    for key in ("mass", "com", "inertia_com"):
        close([l[key] for l in py["links"]], [l[key] for l in cli["links"]], tol)
    for key in ("name", "status", "converged", "iterations"):
        assert py["solver"][key] == cli["solver"][key]
    close(py["weights"], cli["weights"], tol)
    assert py["rows"] == cli["rows"]
    close(py["condition_number"], cli["condition_number"], tol)
    close(py["sigma2"], cli["sigma2"], tol)
    for part in ("train", "test"):
        a, b = py["metrics"][part], cli["metrics"][part]
        assert (a is None) == (b is None)
        if a is not None:
            assert a["joints"] == b["joints"] and a["samples"] == b["samples"]
            close(a["relative_error"], b["relative_error"], tol)
            close(a["rms"], b["rms"], tol)
    assert [(i["role"], i["sha256"], i["bytes"]) for i in py["inputs"]] == [
        (i["role"], i["sha256"], i["bytes"]) for i in cli["inputs"]
    ]


@pytest.mark.parametrize("method", ["ols", "wls", "irls", "sdp"])
def test_fit_matches_cli(psm, psm_logs, run_cli, method):
    train = di.read_log(psm_logs["csv"], psm)
    test = di.read_log(psm_logs["test"], psm)
    result = di.fit(psm, train, method=method, cutoff=5.0, test=test, test_window=2000)
    assert result.solver["converged"]
    cli = run_cli("fit", psm_logs["csv"], "--robot", "psm", "--method", method,
                  "--cutoff", "5", "--test", psm_logs["test"], "--test-window", "2000",
                  "--json")
    same_document(result.to_dict(), cli)
    if method == "sdp":
        assert result.physically_consistent


# Every option of `dvrk-ident fit` against its keyword of `di.fit`: both map onto one
# library request (dvrk_ident::FitRequest), so the documents must agree to
# rounding. Each case: (keywords, flags); the test log and its window are added to all.
OPTIONS = [
    ({"method": "ols", "cutoff": 4.0}, ["--method", "ols", "--cutoff", "4"]),
    ({"method": "ols", "cutoff": [4.0, 5.0, 6.0, 4.0, 5.0, 6.0, 4.0]},
     ["--method", "ols", "--cutoff", "4,5,6,4,5,6,4"]),
    ({"method": "ols", "cutoff": "none"}, ["--method", "ols", "--cutoff", "none"]),
    ({"method": "ols", "filter_torque": True}, ["--method", "ols", "--filter-torque"]),
    ({"method": "ols", "trim": 50}, ["--method", "ols", "--trim", "50"]),
    ({"method": "ols", "decimate": 3}, ["--method", "ols", "--decimate", "3"]),
    ({"method": "ols", "min_speed": 0.01}, ["--method", "ols", "--min-speed", "0.01"]),
    ({"method": "wls", "stribeck": 0.3}, ["--method", "wls", "--stribeck", "0.3"]),
    ({"method": "irls", "irls_iterations": 2},
     ["--method", "irls", "--irls-iterations", "2"]),
    ({"method": "sdp", "sdp_regularization": 1e-6},
     ["--method", "sdp", "--sdp-regularization", "1e-6"]),
    ({"method": "sdp", "bounds": "2019"}, ["--method", "sdp", "--bounds", "2019"]),
    ({"method": "sdp", "ellipsoids": False}, ["--method", "sdp", "--no-ellipsoids"]),
    ({"method": "ols", "mounting_pitch": -45.0}, ["--method", "ols", "--mounting-pitch", "-45"]),
    ({"method": "ols", "delay": 0.01}, ["--method", "ols", "--delay", "0.01"]),
    ({"method": "ols", "delay": [0.01, 0.02, 0.0, 0.0, 0.0, 0.0, 0.005]},
     ["--method", "ols", "--delay", "0.01,0.02,0,0,0,0,0.005"]),
    ({"method": "ols", "resample": 250.0}, ["--method", "ols", "--resample", "250"]),
    ({"method": "ols", "filter_order": 2}, ["--method", "ols", "--filter-order", "2"]),
    ({"method": "ols", "position_torque": 1}, ["--method", "ols", "--position-torque", "1"]),
    ({"method": "ols", "position_torque": 1, "position_torque_frames": ["yaw", "tool_roll"]},
     ["--method", "ols", "--position-torque", "1", "--position-torque-frames", "yaw,tool_roll"]),
    ({"method": "ols", "load_friction": True}, ["--method", "ols", "--load-friction"]),
    ({"preset": "dvrk", "prior": "none"}, ["--preset", "dvrk", "--prior", "none"]),
    ({"method": "ols", "select": ["coulomb", "dahl"]},
     ["--method", "ols", "--select", "coulomb,dahl"]),
    ({"method": "ols", "log_offsets": True}, ["--method", "ols", "--log-offsets"]),
]


@pytest.mark.parametrize("kwargs,flags", OPTIONS, ids=[" ".join(f) for _, f in OPTIONS])
def test_every_option_matches_cli(psm, psm_logs, run_cli, kwargs, flags):
    train = di.read_log(psm_logs["csv"], psm)
    test = di.read_log(psm_logs["test"], psm)
    result = di.fit(psm, train, test=test, test_window=1000, **kwargs)
    cli = run_cli("fit", psm_logs["csv"], "--robot", "psm", *flags, "--test",
                  psm_logs["test"], "--test-window", "1000", "--json")
    same_document(result.to_dict(), cli)
    # The option took effect (it is in the recorded settings).
    settings = result.settings
    for key, value in kwargs.items():
        recorded = {
            "method": settings["method"],
            "filter_torque": settings["processing"]["filter_torque"],
            "filter_order": (settings["processing"]["filter"] or {}).get("order"),
            "trim": settings["processing"]["trim"],
            "decimate": settings["processing"]["decimate"],
            "min_speed": settings["processing"]["min_speed"],
            "stribeck": settings["stribeck_velocity"],
            "irls_iterations": settings["irls_iterations"],
            "sdp_regularization": settings["sdp_regularization"],
            "ellipsoids": settings.get("ellipsoids", True),
            "mounting_pitch": settings.get("mounting_pitch_deg"),
            "position_torque": settings.get("position_torque_order"),
            "position_torque_frames": settings.get("position_torque_frames"),
            "load_friction": settings.get("load_friction"),
            "log_offsets": settings.get("log_offsets"),
        }.get(key)
        if recorded is not None:
            assert recorded == value, key
    if "select" in kwargs:
        # The table, as the command line's document holds it, and the winner's terms.
        assert result.selection == cli["selection"]
        chosen = result.selection["chosen"]
        names = [c["candidate"] for c in result.selection["candidates"]]
        assert chosen in names and settings["select"] == ",".join(names)
        assert result.selection["folds"] == {"kind": "blocked", "folds": 4,
                                             "guard_s": result.selection["folds"]["guard_s"]}
    if "log_offsets" in kwargs:
        assert result.inputs[0]["offset"] == [0.0] * 7


@pytest.mark.parametrize("metric", ["entropic", "euclidean"])
def test_prior_matches_cli(psm, psm_logs, run_cli, tmp_path, metric):
    """prior=, prior_weight=, prior_metric= against --prior, --prior-weight,
    --prior-metric; a Result in memory is the same prior as its file."""
    train = di.read_log(psm_logs["csv"], psm)
    first = di.fit(psm, train, cutoff=4.0)
    path = tmp_path / "first.json"
    first.write(path)
    result = di.fit(psm, train, cutoff=4.0, prior=path, prior_weight=0.01,
                    prior_metric=metric)
    prior = result.settings["prior"]
    assert (prior["source"], prior["metric"], prior["weight"]) == (str(path), metric, 0.01)
    assert prior["parameters"] == first.parameters
    assert any(i["role"] == "prior" for i in result.inputs)
    assert (result.prior_divergence is not None) == (metric == "entropic")
    assert result.prior_divergence == result.to_dict().get("prior_divergence")
    cli = run_cli("fit", psm_logs["csv"], "--robot", "psm", "--cutoff", "4", "--prior",
                  path, "--prior-weight", "0.01", "--prior-metric", metric, "--json")
    same_document(result.to_dict(), cli)
    in_memory = di.fit(psm, train, cutoff=4.0, prior=first, prior_weight=0.01,
                       prior_metric=metric)
    assert in_memory.settings["prior"]["parameters"] == first.parameters
    close(list(in_memory.parameters.values()), list(result.parameters.values()), 1e-12)
    with pytest.raises(di.InputError, match="prior_weight: needs a prior"):
        di.fit(psm, train, prior_weight=0.1)
    with pytest.raises(di.InputError, match="prior_metric"):
        di.fit(psm, train, prior=path, prior_metric="cosine")


@pytest.mark.parametrize("kwargs,flags,name", [
    (dict(method="ols", irls_iterations=3), ["--method", "ols", "--irls-iterations", "3"],
     ("--irls-iterations", "irls_iterations")),
    (dict(method="ols", ellipsoids=False), ["--method", "ols", "--no-ellipsoids"],
     ("--no-ellipsoids", "ellipsoids")),
    (dict(prior_weight=0.1), ["--prior-weight", "0.1"], ("--prior-weight", "prior_weight")),
])
def test_refused_setting_is_spelled_by_each_front_end(psm, psm_logs, cli, kwargs, flags,
                                                       name):
    """The library refuses the setting once, naming it by identity; the command line
    spells it as its flag, Python as its keyword, in front of the same message."""
    import subprocess

    flag, keyword = name
    r = subprocess.run([cli, "fit", psm_logs["csv"], "--robot", "psm", *flags],
                       capture_output=True, text=True)
    assert r.returncode == 1, r.stderr
    prefix = f"dvrk-ident: error: {flag}: "
    assert r.stderr.startswith(prefix), r.stderr
    message = r.stderr[len(prefix):].strip()
    with pytest.raises(di.InputError) as e:
        di.fit(psm, di.read_log(psm_logs["csv"], psm), **kwargs)
    assert str(e.value) == f"{keyword}: {message}"


def test_excitation_window_matches_cli(psm, psm_logs, run_cli, tmp_path):
    """--excitation with a test log and no --test-window: the metrics cover one period
    of the excitation (the 2019 rule), in both front ends."""
    traj = di.FourierTrajectory(order=1, base_frequency_hz=0.125, q0=[0.0] * 7,
                         a=[[0.1]] * 7, b=[[0.0]] * 7)
    path = tmp_path / "excitation.json"
    traj.write(path)
    train = di.read_log(psm_logs["csv"], psm)
    test = di.read_log(psm_logs["test"], psm)
    for excitation in (traj, path):
        result = di.fit(psm, train, method="ols", test=test, excitation=excitation)
        # 8 s at 200 Hz.
        assert result.settings["test_window"] == 1600
        assert result.metrics["test"]["samples"] == 1600
    cli = run_cli("fit", psm_logs["csv"], "--robot", "psm", "--method", "ols", "--test",
                  psm_logs["test"], "--excitation", path, "--json")
    same_document(result.to_dict(), cli)


def test_fit_mcap_matches_cli(psm, psm_logs, run_cli):
    data = di.read_log(psm_logs["mcap"], psm)
    assert data.coordinates == "measured"
    result = di.fit(psm, data, method="wls", cutoff=[5.0] * 7, trim=100)
    cli = run_cli("fit", psm_logs["mcap"], "--robot", "psm", "--method", "wls",
                  "--cutoff", ",".join(["5"] * 7), "--trim", "100", "--json")
    same_document(result.to_dict(), cli)


def test_bundled_example_matches_cli(psm, run_cli):
    """examples/psm_excitation.mcap: simulated from examples/psm_params.json."""
    from conftest import REPO

    log = REPO / "examples" / "psm_excitation.mcap"
    if not log.exists():
        pytest.skip(f"{log} not found")
    data = di.read_log(log, psm)
    assert data.coordinates == "measured" and len(data) == 2222
    for method in ("ols", "sdp"):
        result = di.fit(psm, data, method=method, cutoff="none")
        cli = run_cli("fit", log, "--robot", "psm", "--method", method, "--cutoff", "none",
                      "--json")
        same_document(result.to_dict(), cli)
        assert result.settings["processing"]["filter"] is None
    # The least-squares fit finds the generating base parameters.
    true = json.loads((REPO / "examples" / "psm_params.json").read_text())["parameters"]
    ols = di.fit(psm, data, method="ols", cutoff=False)
    beta_true = psm.base().project(true)
    beta = np.array([b["value"] for b in ols.base_parameters])
    std = np.array([b["std"] for b in ols.base_parameters])
    assert np.all(np.abs(beta - beta_true) < 6 * std + 1e-9)


def test_resampled_csv_matches_cli(psm, psm_excitation, run_cli, tmp_path):
    e = psm_excitation
    t = e["t"].copy()
    t[3000:] += 0.3 / 200.0  # one jittered step: refused unless resampled
    path = tmp_path / "jitter.csv"
    di.JointLog(t, e["q"], e["noisy"], dq=e["dq"]).write(path)
    with pytest.raises(di.InputError, match="resample"):
        di.fit(psm, di.read_log(path), method="ols", cutoff=5.0)
    # `--resample` is fit's keyword: a processing setting the result records.
    result = di.fit(psm, di.read_log(path), method="ols", cutoff=5.0, resample=200.0)
    assert result.settings["processing"]["resample_hz"] == 200.0
    cli = run_cli("fit", path, "--robot", "psm", "--method", "ols", "--cutoff", "5",
                  "--resample", "200", "--json")
    same_document(result.to_dict(), cli)
    # Resampled while reading instead: the same samples to rounding, so the same base
    # parameters, but the result does not know the log was resampled.
    data = di.read_log(path, resample=200.0)
    assert abs(data.rate - 200.0) < 1e-9
    read_resampled = di.fit(psm, data, method="ols", cutoff=5.0)
    close([b["value"] for b in read_resampled.base_parameters],
          [b["value"] for b in result.base_parameters], 1e-9)
    assert read_resampled.settings["processing"]["resample_hz"] is None


def test_result_files_interoperate_with_cli(psm, psm_logs, run_cli, tmp_path):
    out = tmp_path / "cli.json"
    wpi = tmp_path / "params.json"
    run_cli("fit", psm_logs["csv"], "--robot", "psm", "--method", "ols", "--cutoff", "5",
            "--out", out, "--wpi-json", wpi, "--json")
    from_cli = di.FitResult.read(out)
    assert from_cli.to_json() == out.read_text()
    assert di.FitResult.from_json(out.read_text()).parameters == from_cli.parameters
    # The result without a robot loads it from robot_source for predictions.
    assert from_cli.load_robot().name == "psm"
    assert from_cli.wpi_params() == json.loads(wpi.read_text())
    # A Python result file is read by `dvrk-ident validate`, with the same metrics.
    ours = di.fit(psm, di.read_log(psm_logs["csv"]), method="ols", cutoff=5.0)
    ours.write(tmp_path / "py.json")
    doc = run_cli("validate", tmp_path / "py.json", psm_logs["test"], "--test-window", "1500",
                  "--json")
    metrics = ours.validate(di.read_log(psm_logs["test"]), test_window=1500)
    cli_metrics = doc["validations"][0]["metrics"]
    assert metrics["samples"] == cli_metrics["samples"] == 1500
    close(metrics["relative_error"], cli_metrics["relative_error"])
    close(metrics["rms"], cli_metrics["rms"])
    # Parameters of a result are accepted by `model --torque --params`.
    q = np.full(7, 0.1)
    tau = run_cli("model", "psm", "--torque", "--q", ",".join(["0.1"] * 7), "--params",
                  tmp_path / "py.json")["tau"]
    close(psm.inverse_dynamics(ours, q), tau)


def test_result_api(psm, psm_logs, psm_excitation):
    train = di.read_log(psm_logs["csv"], psm)
    test = di.read_log(psm_logs["test"], psm)
    r = di.fit(psm, train, method="ols", cutoff=5.0, test=test, test_window=1000)
    doc = json.loads(r.to_json())
    # Attributes are the document's keys.
    assert r.parameters == doc["parameters"]
    assert list(r.parameters) == psm.parameter_names == r.parameter_order
    np.testing.assert_array_equal(r.parameter_array, list(doc["parameters"].values()))
    assert r.base_parameters == doc["base_parameters"]
    assert len(r.base_parameters) == 49
    assert set(r.base_parameters[0]) == {"name", "expression", "value", "std"}
    assert r.consistency == doc["consistency"]
    assert set(r.consistency[0]) == {"frame", "link", "min_eigenvalue", "consistent"}
    assert r.links == doc["links"]
    assert r.physically_consistent == doc["physically_consistent"]
    assert r.solver == doc["solver"] and r.solver["name"] == "qr"
    assert r.metrics == doc["metrics"]
    assert set(r.metrics["train"]) == {"joints", "samples", "relative_error", "rms"}
    assert r.metrics["test"]["samples"] == 1000
    assert r.settings == doc["settings"] and r.inputs == doc["inputs"]
    assert [i["role"] for i in r.inputs] == ["train", "test"]
    assert r.method == "ols" and r.robot == "psm" and r.robot_source == "builtin:psm"
    assert r.rows == doc["rows"] and r.condition_number == doc["condition_number"]
    assert r.sigma2 == doc["sigma2"] and r.tool == doc["tool"]
    np.testing.assert_array_equal(r.weights, doc["weights"])
    assert r.to_dict() == doc
    assert repr(r) == (
        "FitResult(robot='psm', method='ols', converged=True, physically_consistent=False)"
    )
    # JSON round trip: the same document, the same numbers.
    again = di.FitResult.from_json(r.to_json())
    assert again.to_json() == r.to_json()
    # Fitting again with the result's settings gives the same parameters.
    again = di.fit(psm, train, settings=r.settings)
    assert again.parameters == r.parameters

    # predict: H(q, dq, ddq) @ params on the processed samples.
    prepared = r.prepare(train)
    predicted = r.predict(train)
    assert predicted.shape == (len(prepared), 7) and predicted.dtype == np.float64
    np.testing.assert_array_equal(predicted, r.predict(prepared))
    expected = psm.inverse_dynamics(r.parameter_array, prepared.q, prepared.dq, prepared.ddq)
    np.testing.assert_allclose(predicted, expected, atol=1e-12)
    # The metrics are those of these predictions.
    err = np.linalg.norm(prepared.tau - predicted, axis=0) / np.linalg.norm(prepared.tau, axis=0)
    close(err, r.metrics["train"]["relative_error"], 1e-10)
    # The identified model predicts the noise-free torques closely.
    e = psm_excitation
    exact = e["tau"][200:-200]
    assert np.linalg.norm(predicted - exact) / np.linalg.norm(exact) < 0.02
    # validate(test) reproduces the test metrics.
    v = r.validate(test, test_window=1000)
    assert v == r.metrics["test"]
    # Parameters from a result feed the model functions.
    np.testing.assert_array_equal(
        psm.inverse_dynamics(r, prepared.q[:5], prepared.dq[:5], prepared.ddq[:5]),
        predicted[:5],
    )


def test_sdp_result_is_consistent(psm, psm_logs):
    r = di.fit(psm, di.read_log(psm_logs["csv"]), cutoff=5.0)
    assert r.method == "sdp" and r.solver["name"] == "clarabel" and r.solver["converged"]
    assert r.physically_consistent
    assert all(c["consistent"] and c["min_eigenvalue"] > 0 for c in r.consistency)
    p = r.parameters
    # The robot's default bounds are physical, met exactly (projected after the solve);
    # bounds="2019" puts back Fc, Fv, Ia >= 0.001.
    assert all(p[n] >= 0.0 for n in p if n[:2] in ("Fc", "Fv", "Ia"))
    p2019 = di.fit(psm, di.read_log(psm_logs["csv"]), cutoff=5.0, bounds="2019").parameters
    assert all(p2019[n] >= 0.001 for n in p2019 if n[:2] in ("Fc", "Fv", "Ia"))
    assert any(p[n] < 0.001 for n in p if n[:2] in ("Fc", "Fv", "Ia"))
    # A consistent result has a positive definite mass matrix: forward dynamics works.
    q = np.zeros((3, 7))
    q[:, 2] = 0.12
    ddq = np.full((3, 7), 0.3)
    tau = psm.inverse_dynamics(r, q, q * 0, ddq)
    np.testing.assert_allclose(psm.forward_dynamics(r, q, q * 0, tau), ddq, atol=1e-6)


def test_allow_unconverged_flag_is_accepted(psm, psm_logs):
    r = di.fit(psm, di.read_log(psm_logs["csv"]), method="ols", cutoff=5.0,
               allow_unconverged=True)
    assert r.solver["converged"]


@pytest.fixture
def held():
    """Long computations held (they cannot finish) until the test ends: whether the
    interrupt lands does not depend on how fast the machine is. Python's own SIGINT
    handler is installed for the test: a process that starts with SIGINT ignored (a
    background job of a shell without job control, `nohup`) has none, and the held call
    would wait for an interrupt that never comes (a CI run started that way hung here)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    di._hold_computations(True)
    try:
        yield
    finally:
        di._hold_computations(False)
        signal.signal(signal.SIGINT, previous)


def interrupt_when_held():
    """SIGINT from another thread once the call has reached the hold: the interrupt
    lands inside the long call, never before it."""
    def send():
        while di._held_computations() == 0:
            time.sleep(0.001)
        os.kill(os.getpid(), signal.SIGINT)
    thread = threading.Thread(target=send, daemon=True)
    thread.start()
    return thread


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals are delivered to the main thread")
def test_ctrl_c_stops_a_long_per_sample_call(psm, held):
    q = np.zeros((400_000, 7))
    sender = interrupt_when_held()
    with pytest.raises(KeyboardInterrupt):
        psm.mass_matrix(np.full(115, 0.01), q)
    sender.join()


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals are delivered to the main thread")
def test_ctrl_c_stops_waiting_for_a_fit(psm, psm_excitation, held):
    e = psm_excitation
    data = di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"])
    sender = interrupt_when_held()
    with pytest.raises(KeyboardInterrupt):
        di.fit(psm, data, method="irls", irls_iterations=12, cutoff=5.0)
    sender.join()


def test_a_held_computation_finishes_once_released(psm):
    # The hook itself: released, the same calls complete normally.
    di._hold_computations(True)
    di._hold_computations(False)
    m = psm.mass_matrix(np.full(115, 0.01), np.zeros((3, 7)))
    assert m.shape == (3, 7, 7)


def test_delay_auto_matches_cli(psm, cli, run_cli, tmp_path):
    """`delay="auto"` is `fit --delay auto`: a log simulated with torque delays of 0, 10
    and 50 ms (`simulate --delay`) gives the same document, delays included, and they
    are within 1 ms of the simulated ones."""
    import subprocess
    from conftest import REPO

    truth = [0.0, 0.01, 0.05, 0.01, 0.05, 0.0, 0.01]
    log = tmp_path / "delayed.mcap"
    subprocess.run(
        [cli, "simulate", "psm", "--params", REPO / "examples" / "psm_params.json",
         "--excitation", REPO / "examples" / "psm_trajectory.json", "--periods", "3",
         "--noise", "0.002", "--seed", "1", "--delay", ",".join(map(str, truth)),
         "--out", log],
        check=True,
        capture_output=True,
    )
    result = di.fit(psm, di.read_log(log, psm), method="ols", delay="auto")
    cli_doc = run_cli("fit", log, "--robot", "psm", "--method", "ols", "--delay", "auto",
                      "--json")
    py = result.to_dict()
    same_document(py, cli_doc)
    close(py["delay"]["delay_s"], cli_doc["delay"]["delay_s"])
    close(py["delay"]["std_s"], cli_doc["delay"]["std_s"])
    assert result.delay == py["delay"]
    assert np.all(np.abs(np.array(result.delay["delay_s"]) - truth) < 1e-3)
    # Fixed delays and the 2019 bounds by name, as on the command line.
    fixed = di.fit(psm, di.read_log(log, psm), method="ols", delay=truth)
    assert fixed.settings["processing"]["delay_s"] == truth and fixed.delay is None
    with pytest.raises(di.InputError, match="delay"):
        di.fit(psm, di.read_log(log, psm), delay=[0.01, 0.02])
    with pytest.raises(di.InputError, match="bounds"):
        di.fit(psm, di.read_log(log, psm), bounds="2018")
    assert di.fit(psm, di.read_log(log, psm), method="sdp", bounds="2019").settings[
        "bounds"] == "2019"
    # Bounds that a least-squares fit would not use are refused, as on the command line.
    with pytest.raises(di.InputError, match="method ols has none"):
        di.fit(psm, di.read_log(log, psm), method="ols", bounds="2019")


def test_the_same_data_twice_is_warned(psm, tmp_path):
    """A training log given twice, or a test log equal to a training log, is fitted
    with a ``UserWarning`` naming both (the command line prints the same on stderr)."""
    import warnings

    log = di.read_log(Path(__file__).resolve().parents[2] / "examples" / "psm_excitation.mcap")
    with pytest.warns(UserWarning, match="same data") as seen:
        di.fit(psm, [log, log], method="ols", test=log)
    messages = [str(w.message) for w in seen if "same data" in str(w.message)]
    assert len(messages) == 2
    assert "√2" in messages[0] and "not a test of generalization" in messages[1]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        di.fit(psm, log, method="ols")


def test_identify_payload_matches_cli(psm, cli, run_cli, tmp_path):
    """`identify_payload` is `dvrk-ident payload`: on a log simulated with 0.2 kg at
    [0, 0.02, 0.165] m on the insertion stage, under the fit of the payload-free bundled
    example, the same payload (mass within 2 %, com within 3 mm) and the result it
    returns validates at the noise; an unknown frame is refused, naming the frames."""
    import subprocess
    from conftest import REPO

    example = REPO / "examples" / "psm_excitation.mcap"
    if not example.exists():
        pytest.skip(f"{example} not found")
    (tmp_path / "payload.toml").write_text(
        'frame = "main_insertion"\nmass = 0.2\ncom = [0.0, 0.02, 0.165]\n'
    )
    log = tmp_path / "loaded.mcap"
    subprocess.run(
        [cli, "simulate", "psm", "--params", REPO / "examples" / "psm_params.json",
         "--excitation", REPO / "examples" / "psm_trajectory.json", "--noise", "0.002",
         "--seed", "7", "--payload", tmp_path / "payload.toml", "--out", log],
        check=True,
        capture_output=True,
    )
    result = di.fit(psm, di.read_log(example, psm))
    result.write(tmp_path / "fit.json")
    data = di.read_log(log, psm)
    loaded = di.identify_payload(result, data, frame="main_insertion")
    doc = run_cli("payload", tmp_path / "fit.json", log, "--frame", "main_insertion", "--json")
    p = loaded.payload
    assert p["frame"] == "main_insertion" and result.payload is None
    close(p["mass"], doc["payload"]["mass"], 1e-9)
    close(p["com"], doc["payload"]["com"], 1e-9)
    assert p["identification"]["determined"] == doc["identification"]["determined"]
    assert abs(p["mass"] - 0.2) < 0.004
    assert np.max(np.abs(np.array(p["com"]) - [0.0, 0.02, 0.165])) < 3e-3
    assert loaded.parameters == result.parameters
    assert max(loaded.validate(data)["rms"][:3]) < 0.0025
    assert min(result.validate(data)["rms"][:3]) > 0.1
    with pytest.raises(di.InputError, match="no frame `nowhere`.*main_insertion") as e:
        di.identify_payload(result, data, frame="nowhere")
    # The argument refused, named as the keyword (the command line's `--frame: ...`).
    assert str(e.value).startswith("frame: robot psm has no frame `nowhere`"), str(e.value)
