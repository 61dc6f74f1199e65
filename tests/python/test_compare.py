"""`di.compare` against `dvrk-ident compare --json` on the same result files and logs."""

import subprocess

import pytest

import dvrk_ident as di
from conftest import excitation


def fit_file(cli, train, path, *flags):
    """`dvrk-ident fit TRAIN --robot psm FLAGS --out PATH`."""
    r = subprocess.run(
        [cli, "fit", str(train), "--robot", "psm", *flags, "--out", str(path)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    return path


@pytest.fixture(scope="module")
def two_fits(cli, psm_logs, tmp_path_factory):
    d = tmp_path_factory.mktemp("compare")
    a = fit_file(cli, psm_logs["csv"], d / "ols.json", "--method", "ols")
    b = fit_file(cli, psm_logs["csv"], d / "wls.json", "--method", "wls", "--cutoff", "8")
    return a, b


def test_compare_matches_cli(psm, psm_logs, run_cli, two_fits):
    a, b = two_fits
    ra, rb = di.FitResult.read(a), di.FitResult.read(b)
    tests = [di.read_log(psm_logs["test"], psm), di.read_log(psm_logs["mcap"], psm)]
    doc = di.compare(ra, rb, tests, names=(str(a), str(b)))
    cli = run_cli("compare", a, b, "--test", psm_logs["test"], psm_logs["mcap"], "--json")
    assert doc == cli
    assert sorted(d["path"] for d in doc["differences"]) == [
        "settings.method",
        "settings.processing.filter.cutoff_hz",
    ]
    # Each result's errors on each log are its own `validate` there.
    assert [t["log"] for t in doc["tests"]] == [str(psm_logs["test"]), str(psm_logs["mcap"])]
    for k, log in enumerate(tests):
        assert doc["tests"][k]["a"] == ra.validate(log)
        assert doc["tests"][k]["b"] == rb.validate(log)
    assert doc["tests"][0]["a"]["rms"] != doc["tests"][0]["b"]["rms"]
    # One log, the default names and a window.
    one = di.compare(ra, rb, tests[0], test_window=500)
    assert (one["a"]["name"], one["b"]["name"]) == ("a", "b")
    assert one["tests"][0]["a"] == ra.validate(tests[0], test_window=500)
    cli = run_cli("compare", a, b, "--test", psm_logs["test"], "--test-window", "500",
                  "--json")
    cli["a"]["name"], cli["b"]["name"] = "a", "b"
    assert one == cli
    # A result against itself.
    same = di.compare(ra, ra)
    assert same["differences"] == [] and same["tests"] == []
    assert all(r["sigmas"] == 0.0 for r in same["base_parameters"]["parameters"])


def test_compare_refuses_results_of_two_robots(mtm, two_fits):
    e = excitation(mtm, seconds=20.0)
    log = di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"], source="mtm excitation")
    mtm_result = di.fit(mtm, log, method="ols")
    psm_result = di.FitResult.read(two_fits[0])
    with pytest.raises(di.InputError, match="^mtm.json was fitted for mtm, psm.json for psm"):
        di.compare(mtm_result, psm_result, names=("mtm.json", "psm.json"))
    with pytest.raises(di.InputError, match="test: expected a JointLog"):
        di.compare(psm_result, psm_result, test=[1.0])
