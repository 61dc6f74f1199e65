"""The 2019 dVRK PSM measurements (../shared/data/dvrk/psm): the published
least-squares test errors and the command line's numbers. Skipped when ../shared is
absent."""

import numpy as np
import pytest

import dvrk_ident as di
from conftest import shared_file
from test_fit import same_document

# Published 2019 test errors (trajectory "two", first period), joints 1..7.
PSM_OLS = [0.1027, 0.1839, 0.1983, 0.1344, 0.2402, 0.2119, 0.2638]


@pytest.fixture(scope="module")
def psm_logs():
    return (
        shared_file("data", "dvrk", "psm", "one_results.csv"),
        shared_file("data", "dvrk", "psm", "two_results.csv"),
    )


def test_psm_ols_reproduces_2019(psm, psm_logs, run_cli):
    one, two = psm_logs
    train = di.read_log(one, psm, format="wpi-csv", rate=200)
    test = di.read_log(two, psm, format="wpi-csv", rate=200)
    assert train.coordinates == "model" and train.q.shape == (5999, 7)
    # The 2019 protocol filters the torques too (not the default, see docs/book/src/fit.md).
    result = di.fit(psm, train, method="ols", cutoff=16.965, test=test, test_window=1111,
                    settings={"processing": {"filter_torque": True}})
    errors = result.metrics["test"]["relative_error"]
    assert result.metrics["test"]["samples"] == 1111
    np.testing.assert_array_equal(np.round(errors, 4), PSM_OLS)
    cli = run_cli("fit", one, "--robot", "psm", "--format", "wpi-csv", "--rate", "200",
                  "--method", "ols", "--cutoff", "16.965", "--filter-torque", "--test", two,
                  "--test-window", "1111", "--json")
    same_document(result.to_dict(), cli)
    # validate() on the test log gives the test metrics.
    assert result.validate(test, test_window=1111) == result.metrics["test"]


def test_psm_sdp_matches_cli(psm, psm_logs, run_cli):
    one, two = psm_logs
    train = di.read_log(one, psm, format="wpi-csv", rate=200)
    test = di.read_log(two, psm, format="wpi-csv", rate=200)
    result = di.fit(psm, train, cutoff=16.965, test=test, test_window=1111)
    assert result.solver["converged"] and result.physically_consistent
    cli = run_cli("fit", one, "--robot", "psm", "--format", "wpi-csv", "--rate", "200",
                  "--cutoff", "16.965", "--test", two, "--test-window", "1111", "--json")
    same_document(result.to_dict(), cli)
