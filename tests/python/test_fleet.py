"""The map and reduce of a fit outside one process: di.observe gives an Observation
(bytes and pickle round trips, merge and +), di.fit of observations equals the fit of
the logs; the fit of 8 logs on a Dask LocalCluster of 2 worker processes equals the
single-process fit to 1e-10 relative, and the same on Ray where it is installed."""

import functools
import operator
import pickle
import subprocess

import numpy as np
import pytest

import dvrk_ident as di
from conftest import REPO

EXAMPLES = REPO / "examples"

N_LOGS = 8


@pytest.fixture(scope="module")
def fleet(cli, tmp_path_factory):
    """Eight logs of one arm (MCAP files written by `dvrk-ident simulate`): the bundled
    example's parameters and excitation trajectory, noise of its own in each, two
    periods (about 22 s) each."""
    d = tmp_path_factory.mktemp("fleet")
    paths = []
    for k in range(N_LOGS):
        path = d / f"arm_{k}.mcap"
        subprocess.run(
            [cli, "simulate", "psm", "--params", EXAMPLES / "psm_params.json",
             "--excitation", EXAMPLES / "psm_trajectory.json", "--periods", "2",
             "--noise", "0.002", "--seed", str(10 + k), "--out", path, "--quiet"],
            check=True,
            capture_output=True,
        )
        paths.append(str(path))
    return paths


@pytest.fixture(scope="module")
def direct(psm, fleet):
    """The single-process fit of the eight logs."""
    return di.fit(psm, [di.read_log(p, psm) for p in fleet], method="wls")


def relative(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def assert_same_fit(result, reference, tolerance=1e-10):
    beta = [b["value"] for b in result.base_parameters]
    beta_ref = [b["value"] for b in reference.base_parameters]
    assert relative(beta, beta_ref) < tolerance
    for role in ("train",):
        m, r = result.metrics[role], reference.metrics[role]
        assert m["samples"] == r["samples"]
        assert relative(m["relative_error"], r["relative_error"]) < tolerance
    # The same logs, each with its own metrics.
    ours = {i["path"]: i for i in result.inputs}
    theirs = {i["path"]: i for i in reference.inputs}
    assert ours.keys() == theirs.keys()
    for path, i in ours.items():
        assert i["sha256"] == theirs[path]["sha256"]
        assert relative(
            i["metrics"]["relative_error"], theirs[path]["metrics"]["relative_error"]
        ) < tolerance
    assert result.weights == pytest.approx(reference.weights, rel=1e-15)


def test_observation_round_trips_and_merges(psm, fleet, direct):
    a = di.observe(psm, fleet[0])
    assert isinstance(a, di.Observation)
    assert a.robot == "psm"
    assert a.logs[0]["path"] == fleet[0]
    # A path, or the Data read from it: the same state, byte for byte.
    assert bytes(di.observe(psm, di.read_log(fleet[0], psm))) == bytes(a)
    assert bytes(di.Observation.from_bytes(bytes(a))) == bytes(a)
    assert bytes(pickle.loads(pickle.dumps(a))) == bytes(a)
    parts = [a] + [di.observe(psm, p) for p in fleet[1:]]
    total = functools.reduce(operator.add, parts)
    assert total.samples == sum(p.samples for p in parts)
    assert [log["path"] for log in total.logs] == fleet
    # Merged in order: the fit of the logs to the last bit.
    reduced = di.fit(psm, total, method="wls")
    assert reduced.base_parameters == direct.base_parameters
    assert reduced.metrics == direct.metrics
    # A list of observations is merged in order.
    assert di.fit(psm, parts, method="wls").base_parameters == direct.base_parameters
    # Another grouping: equal to rounding.
    other = (parts[4] + parts[5] + parts[6] + parts[7]) + (parts[0] + parts[1] + parts[2] + parts[3])
    assert_same_fit(di.fit(psm, other, method="wls"), direct)


OBSERVE_OPTIONS = [
    ({}, []),
    ({"cutoff": 8.0}, ["--cutoff", "8"]),
    ({"cutoff": "none"}, ["--cutoff", "none"]),
    ({"filter_torque": True}, ["--filter-torque"]),
    ({"trim": 40}, ["--trim", "40"]),
    ({"decimate": 3}, ["--decimate", "3"]),
    ({"min_speed": 0.01}, ["--min-speed", "0.01"]),
    ({"stribeck": 0.05}, ["--stribeck", "0.05"]),
    ({"resample": 250.0}, ["--resample", "250"]),
]


@pytest.mark.parametrize("kwargs,flags", OBSERVE_OPTIONS,
                         ids=[" ".join(f) or "defaults" for _, f in OBSERVE_OPTIONS])
def test_observe_matches_cli(psm, fleet, cli, tmp_path, kwargs, flags):
    """observe(**kwargs) and `dvrk-ident observe FLAGS` map onto one library request:
    the same state file, byte for byte (both record the log's absolute path)."""
    out = tmp_path / "cli.obs"
    subprocess.run([cli, "observe", fleet[0], fleet[1], "--robot", "psm", *flags,
                    "--out", out, "--quiet"], check=True)
    ours = di.observe(psm, [fleet[0], fleet[1]], **kwargs)
    assert bytes(ours) == out.read_bytes()
    if kwargs:
        assert bytes(ours) != bytes(di.observe(psm, [fleet[0], fleet[1]]))


def test_observations_of_other_settings_or_robots_are_refused(psm, fleet, tmp_path):
    a = di.observe(psm, fleet[0])
    b = di.observe(psm, fleet[1], cutoff=8.0)
    with pytest.raises(di.InputError, match="processing settings"):
        a + b
    with pytest.raises(di.InputError, match="reduced for robot psm"):
        di.fit(di.Model.load("psm_simplified"), a, method="wls")
    with pytest.raises(di.InputError, match="processing .* of observation states are their own"):
        di.fit(psm, a, method="wls", cutoff=3.0)
    with pytest.raises(di.InputError, match="format version 9"):
        raw = bytearray(bytes(a))
        raw[8] = 9
        di.Observation.from_bytes(bytes(raw))
    # A state file written from Python fits with the command line's `fit --states`.
    a.write(tmp_path / "a.obs")
    assert bytes(di.Observation.read(tmp_path / "a.obs")) == bytes(a)


def test_observation_file_fits_on_the_command_line(psm, fleet, run_cli, tmp_path):
    paths = []
    for k, p in enumerate(fleet[:2]):
        paths.append(tmp_path / f"{k}.obs")
        di.observe(psm, p).write(paths[-1])
    doc = run_cli("fit", "--states", *paths, "--method", "wls", "--json")
    direct = run_cli("fit", *fleet[:2], "--robot", "psm", "--method", "wls", "--json")
    for d in (doc, direct):
        d["solver"]["seconds"] = None
    assert doc == direct


def test_dask_local_cluster_of_two_processes(psm, fleet, direct):
    distributed = pytest.importorskip("distributed")
    import dask.bag as db

    observe = functools.partial(di.observe, psm)
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
    ) as cluster, distributed.Client(cluster) as client:
        client.wait_for_workers(2)
        merged = (
            db.from_sequence(fleet, npartitions=4)
            .map(observe)
            .fold(operator.add)
            .compute(scheduler=client)
        )
        # Two worker processes (which took which log is the scheduler's choice and does
        # not change the result).
        assert len(client.scheduler_info()["workers"]) == 2
    assert isinstance(merged, di.Observation)
    assert merged.samples == direct.metrics["train"]["samples"]
    assert_same_fit(di.fit(psm, merged, method="wls"), direct)


def test_ray(psm, fleet, direct):
    ray = pytest.importorskip("ray", reason="SKIPPED: ray is not installed")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        remote = ray.remote(lambda p: di.observe(psm, p))
        parts = ray.get([remote.remote(p) for p in fleet])
    finally:
        ray.shutdown()
    merged = functools.reduce(operator.add, parts)
    assert_same_fit(di.fit(psm, merged, method="wls"), direct)
