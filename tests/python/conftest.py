"""Shared fixtures: the command-line binary (the reference the module is checked
against), the shared real data (skipped when absent), a synthetic PSM excitation."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import dvrk_ident as di

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


def pytest_report_header(config):
    return f"dvrk_ident {di.__version__} from {Path(di.__file__).parent}"


@pytest.fixture(scope="session")
def cli():
    """The `dvrk-ident` binary: $DVRK_IDENT_BIN, else built with cargo (a no-op when up
    to date) at target/release/dvrk-ident."""
    env = os.environ.get("DVRK_IDENT_BIN")
    if env:
        return env
    exe = REPO / "target" / "release" / "dvrk-ident"
    cargo = shutil.which("cargo")
    if cargo and (REPO / "Cargo.toml").exists():
        r = subprocess.run(
            [cargo, "build", "--release", "-q", "-p", "dvrk-cli"],
            cwd=REPO,
            capture_output=True,
            text=True,
        )
        if r.returncode != 0:
            pytest.fail(f"cargo build --release -p dvrk-cli failed:\n{r.stderr}")
    if not exe.exists():
        pytest.skip("the dvrk-ident binary is not built and cargo is not available")
    return str(exe)


@pytest.fixture(scope="session")
def run_cli(cli):
    """Runs the binary with arguments, returns stdout parsed as JSON."""

    def run(*args, cwd=None):
        r = subprocess.run(
            [cli, *map(str, args)], capture_output=True, text=True, cwd=cwd
        )
        if r.returncode != 0:
            raise AssertionError(f"dvrk-ident {' '.join(map(str, args))}: {r.stderr}")
        return json.loads(r.stdout)

    return run


@pytest.fixture(scope="session")
def psm():
    return di.Model.load("psm")


@pytest.fixture(scope="session")
def mtm():
    return di.Model.load("mtm")


def shared_file(*parts):
    """A file of ../shared, or skip with the reason."""
    p = SHARED.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"SKIPPED: {p} not found (../shared absent)")
    return p


def excitation(robot, seconds=40.0, rate=200.0, seed=0, noise=0.01):
    """Sums of sines in model coordinates and torques from a random parameter vector
    (with noise): t, q, dq, ddq, tau_exact, tau_noisy, params."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    w = 2 * np.pi * 0.1 * np.arange(1, 6)
    rng = np.random.default_rng(seed)
    amp = rng.uniform(-0.3, 0.3, (robot.dof, w.size)) / np.arange(1, 6)
    centre = np.zeros(robot.dof)
    for j, name in enumerate(robot.coordinates):
        if robot.name.startswith("psm") and name == "q3":
            amp[j] *= 0.1
            centre[j] = 0.12
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    q = centre + s @ amp.T
    dq = c @ (amp * w).T
    ddq = -s @ (amp * w**2).T
    params = rng.uniform(-0.05, 0.05, robot.n_parameters)
    tau = robot.inverse_dynamics(params, q, dq, ddq)
    noisy = tau + rng.normal(0.0, noise, tau.shape)
    return dict(t=t, q=q, dq=dq, ddq=ddq, tau=tau, noisy=noisy, params=params)


@pytest.fixture(scope="session")
def psm_excitation(psm):
    return excitation(psm)


@pytest.fixture(scope="session")
def psm_logs(psm, psm_excitation, tmp_path_factory):
    """The PSM excitation written as a headered CSV (model coordinates) and as an MCAP
    in measured joints; a second, different excitation as a test log."""
    d = tmp_path_factory.mktemp("logs")
    e = psm_excitation
    model = di.JointLog(e["t"], e["q"], e["noisy"], dq=e["dq"], source="synthetic")
    model.write(d / "train.csv")
    C = psm.coupling
    measured = di.JointLog(
        e["t"],
        e["q"] @ C.T,
        e["noisy"] @ np.linalg.inv(C),
        dq=e["dq"] @ C.T,
        joint_names=psm.measured_joints,
        coordinates="measured",
    )
    measured.write(d / "train.mcap")
    e2 = excitation(psm, seconds=20.0, seed=1)
    # Same parameters as the training log, another trajectory.
    tau2 = psm.inverse_dynamics(e["params"], e2["q"], e2["dq"], e2["ddq"])
    di.JointLog(e2["t"], e2["q"], tau2, dq=e2["dq"]).write(d / "test.csv")
    return dict(dir=d, csv=d / "train.csv", mcap=d / "train.mcap", test=d / "test.csv")
