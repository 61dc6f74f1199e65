"""Measured joints (``joints="measured"``): a fit's errors, predictions and processed
samples shown in the arm's measured joints by name, checked against the PSM coupling
transcribed here from robots/psm.toml (the dVRK's wrist coupling) and applied with
numpy: ``q_measured = M·q``, ``tau_measured = M⁻ᵀ·tau``."""

from pathlib import Path

import numpy as np
import pytest

import dvrk_ident as di

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "psm_excitation.mcap"

# robots/psm.toml [measured]: the first four joints are the coordinates; the wrist maps
# the motor angles q5..q7 to wrist pitch, wrist yaw and the jaw.
M = np.eye(7)
M[4:, 4:] = [[1.0186, 0.0, 0.0], [-0.8306, 0.6089, 0.6089], [0.0, -1.2177, 1.2177]]
NAMES = [
    "outer_yaw",
    "outer_pitch",
    "outer_insertion",
    "outer_roll",
    "outer_wrist_pitch",
    "outer_wrist_yaw",
    "jaw",
]


@pytest.fixture(scope="module")
def fitted(psm):
    log = di.read_log(EXAMPLE)
    model = di.fit(psm, log, method="sdp")
    measured = di.fit(psm, log, method="sdp", joints="measured")
    return log, model, measured


def metrics(tau, predicted):
    e = tau - predicted
    return np.linalg.norm(e, axis=0) / np.linalg.norm(tau, axis=0), np.sqrt(
        np.mean(e**2, axis=0)
    )


def test_the_fit_is_the_same_and_its_metrics_are_the_couplings(fitted):
    log, model, measured = fitted
    assert measured.parameters == model.parameters
    assert measured.settings["joints"] == "measured"
    train = measured.metrics["train"]
    assert train["joints"] == NAMES
    # Independent of the library's map: model-coordinate torques and predictions mapped
    # here with the transcribed coupling.
    p = model.prepare(log)
    assert p.joints == "model" and p.joint_names[4] == "q5"
    W = np.linalg.inv(M).T
    tau, pred = p.tau @ W.T, model.predict(p) @ W.T
    rel, rms = metrics(tau, pred)
    np.testing.assert_allclose(train["relative_error"], rel, rtol=1e-9)
    np.testing.assert_allclose(train["rms"], rms, rtol=1e-9)
    # The wrist's numbers are not the model coordinates'.
    own = model.metrics["train"]
    assert np.all(np.abs(np.array(own["rms"][4:]) - rms[4:]) > 1e-3 * rms[4:])
    np.testing.assert_allclose(own["rms"][:4], rms[:4], rtol=1e-9)


def test_prepare_predict_and_validate_show_the_measured_joints(fitted):
    log, model, measured = fitted
    p_model = model.prepare(log)
    p = measured.prepare(log)
    assert p.joints == "measured" and p.joint_names == NAMES
    np.testing.assert_allclose(p.q, p_model.q @ M.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.dq, p_model.dq @ M.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.ddq, p_model.ddq @ M.T, rtol=0, atol=1e-9)
    W = np.linalg.inv(M).T
    np.testing.assert_allclose(p.tau, p_model.tau @ W.T, rtol=0, atol=1e-12)
    # Power is the same in either joints.
    np.testing.assert_allclose(
        np.sum(p.tau * p.dq, axis=1), np.sum(p_model.tau * p_model.dq, axis=1), atol=1e-12
    )
    # predict: a Prepared's own joints, a log's the fit's, or as asked.
    pred = measured.predict(p)
    np.testing.assert_allclose(pred, model.predict(p_model) @ W.T, atol=1e-12)
    np.testing.assert_allclose(measured.predict(log), pred, atol=1e-12)
    np.testing.assert_allclose(model.predict(log, joints="measured"), pred, atol=1e-12)
    np.testing.assert_allclose(measured.predict(p, joints="model"), model.predict(p_model), atol=1e-12)
    frame = measured.predict(log, as_dataframe=True)
    assert list(frame.columns) == ["time"] + [f"effort.{n}" for n in NAMES]
    assert list(p.to_dataframe().columns)[1:3] == ["position.outer_yaw", "position.outer_pitch"]
    # validate: the fit's joints by default; the fit's training metrics on its own log.
    v = measured.validate(log)
    assert v["joints"] == NAMES
    np.testing.assert_allclose(v["rms"], measured.metrics["train"]["rms"], rtol=1e-9)
    assert model.validate(log, joints="measured")["joints"] == NAMES
    assert measured.validate(log, joints="model")["joints"][4] == "q5"


def test_bad_joints_are_input_errors(psm, fitted):
    log, model, _ = fitted
    with pytest.raises(di.InputError, match="joints"):
        di.fit(psm, log, method="ols", joints="motor")
    with pytest.raises(di.InputError, match="joints"):
        model.validate(log, joints="both")
    # A wrong type is Python's TypeError, as for every keyword.
    with pytest.raises(TypeError, match="joints"):
        model.predict(log, joints=3)
