"""Recordings as labs make them, written by tools this project did not write (rosbags,
the official mcap + mcap-ros2-support writer; see bags.py): every format must fit to
the same base parameters as the headered CSV of the same samples (1e-9 relative), from
Python and from the command line; several logs per fit."""

import json
from pathlib import Path
import subprocess

import numpy as np
import pytest

import dvrk_ident as di
from conftest import excitation, shared_file

bags = pytest.importorskip("bags")
pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

T0_NS = 1_700_000_000 * 1_000_000_000


def measured(psm, e):
    """The excitation in measured joints with nanosecond stamps: (stamps, q, dq, tau)."""
    C = psm.coupling
    stamps = T0_NS + np.arange(len(e["t"]), dtype=np.int64) * 5_000_000
    return stamps, e["q"] @ C.T, e["dq"] @ C.T, e["noisy"] @ np.linalg.inv(C)


@pytest.fixture(scope="module")
def recordings(psm, tmp_path_factory):
    """One synthetic PSM log in every format, and its headered CSV."""
    d = tmp_path_factory.mktemp("bags")
    e = excitation(psm, seconds=30.0)
    stamps, q, dq, tau = measured(psm, e)
    names = psm.measured_joints
    paired = bags.psm_topics(names, stamps, q, dq, tau)
    single = bags.psm_topics(names, stamps, q, dq, tau, jaw_topic=False)
    csv = d / "log.csv"
    di.JointLog(stamps, q, tau, dq=dq, joint_names=names).write(csv)
    files = {
        "rosbag2 mcap folder": bags.rosbag2(d / "mcap_bag", paired, storage="mcap"),
        "metadata.yaml": bags.rosbag2(d / "meta_bag", paired, storage="mcap") / "metadata.yaml",
        "rosbag2 sqlite3 folder": bags.rosbag2(d / "sqlite_bag", paired, storage="sqlite3"),
        "split in three": bags.rosbag2(d / "split_bag", paired, storage="mcap", split=3),
        "zstd file compression": bags.rosbag2(d / "zfile", paired, storage="mcap", compression="file"),
        "zstd message compression": bags.rosbag2(d / "zmsg", single, storage="mcap", compression="message"),
        "sqlite3 message compression": bags.rosbag2(d / "zmsg3", paired, storage="sqlite3", compression="message"),
        "ROS 1 bag": bags.ros1(d / "noetic.bag", paired),
        "ROS 1 bag, lz4 chunks": bags.ros1(d / "noetic_lz4.bag", single, compression="lz4"),
        "ROS 1 bag, bz2 chunks": bags.ros1(d / "noetic_bz2.bag", paired, compression="bz2"),
        "official MCAP writer": bags.official_mcap(d / "official.mcap", paired),
        "official MCAP writer, lz4": bags.official_mcap(d / "official_lz4.mcap", single, compression="lz4"),
    }
    files[".db3 alone"] = next((d / "sqlite_bag").glob("*.db3"))
    files[".mcap.zstd alone"] = next((d / "zfile").glob("*.mcap.zstd"))
    files["lz4-compressed .mcap"] = bags.compress_file(
        next((d / "mcap_bag").glob("*.mcap")), d / "whole.mcap.lz4", "lz4")
    return dict(dir=d, csv=csv, files=files, e=e)


def base_values(result):
    return np.array([b["value"] for b in result.base_parameters])


def test_every_format_fits_as_the_csv(psm, recordings):
    reference = di.fit(psm, di.read_log(recordings["csv"], psm), method="ols")
    want = base_values(reference)
    for name, path in recordings["files"].items():
        data = di.read_log(path, psm)
        assert data.joint_names == psm.measured_joints, name
        assert data.coordinates == "measured", name
        got = base_values(di.fit(psm, data, method="ols"))
        worst = np.max(np.abs(got - want) / np.maximum(np.abs(want), 1e-6 * np.abs(want).max()))
        assert worst < 1e-9, f"{name}: {worst:.1e}"


def test_every_format_from_the_command_line(run_cli, psm, recordings, tmp_path):
    want = base_values(di.fit(psm, di.read_log(recordings["csv"], psm), method="ols"))
    for name, path in recordings["files"].items():
        doc = run_cli("fit", path, "--robot", "psm", "--method", "ols", "--json")
        got = np.array([b["value"] for b in doc["base_parameters"]])
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.abs(want).max(), err_msg=name)
        [info] = doc["inputs"]
        assert len(info["sha256"]) == 64 and info["bytes"] > 0
        if name.endswith("folder") or name == "split in three":
            assert "/PSM1/measured_js + /PSM1/jaw/measured_js" in info["source"], info
    # The same through streaming.
    folder = recordings["files"]["split in three"]
    doc = run_cli("fit", folder, "--robot", "psm", "--method", "ols", "--json", "--stream")
    np.testing.assert_allclose([b["value"] for b in doc["base_parameters"]], want, rtol=1e-9)


def test_the_pairing_and_the_topics_are_reported(psm, recordings):
    folder = recordings["files"]["rosbag2 mcap folder"]
    data = di.read_log(folder, psm)
    assert "/PSM1/measured_js + /PSM1/jaw/measured_js" in data.source
    # Without the robot the pair is not known: the message names the keyword.
    with pytest.raises(di.InputError) as e:
        di.read_log(folder)
    msg = str(e.value)
    assert "topic=" in msg and "--topic" not in msg, msg
    topics = {t["topic"]: t for t in di.list_topics(folder)}
    assert {"/PSM1/measured_js", "/PSM1/jaw/measured_js", "/PSM1/status"} <= set(topics)


def test_times_from_stamps_are_exact(psm, recordings):
    """Nanosecond stamps: the bag's times and Data built from the int64 or datetime64
    stamps are the same floats, k / 200 exactly."""
    e = recordings["e"]
    stamps, q, dq, tau = measured(psm, e)
    from_bag = di.read_log(recordings["files"]["ROS 1 bag"], psm)
    k = np.arange(len(stamps))
    np.testing.assert_array_equal(from_bag.time, (k * 5_000_000) / 1e9)
    for t in (stamps, stamps.astype("datetime64[ns]"), (stamps - T0_NS).astype("timedelta64[ns]"),
              stamps.astype("datetime64[ns]").astype("datetime64[us]")):
        d = di.JointLog(t, q, tau, dq=dq, joint_names=psm.measured_joints)
        np.testing.assert_array_equal(d.time, from_bag.time)
    # Float seconds since the epoch have lost the nanoseconds: the rate shows it.
    lossy = di.JointLog(stamps / 1e9, q, tau, dq=dq, joint_names=psm.measured_joints)
    assert abs(lossy.rate - 200.0) > 1e-6
    assert abs(from_bag.rate - 200.0) < 1e-9


def test_not_a_log_says_what_it_is(psm, tmp_path):
    p = tmp_path / "log.db3"
    p.write_bytes(b"\x1f\x8b\x08\x00garbage")
    with pytest.raises(di.InputError) as e:
        di.read_log(p, psm)
    msg = str(e.value)
    assert "gzip-compressed data" in msg and "supported: a rosbag2 folder" in msg, msg
    with pytest.raises(di.InputError):
        di.fit(psm, di.read_log(p))


def test_decompression_is_bounded_and_max_unpacked_mib_sets_the_bound():
    """A compressed file (sqlite3 as a whole, MCAP chunks) that expands beyond its bound
    is refused, naming the file and the bound, before it is expanded; max_unpacked_mib
    sets the bound (the CLI's --max-unpacked-mib)."""
    hostile = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "hostile"
    for name, what in [
        ("bomb.db3.zst", "it decompresses to more than"),
        ("chunk_100mib.mcap", "its compressed chunks decompress to more than"),
    ]:
        with pytest.raises(di.InputError) as e:
            di.read_log(hostile / name)
        msg = str(e.value)
        assert name in msg and f"{what} 64 MiB" in msg, msg
        # The setting that raises the bound, named as the keyword.
        assert msg.endswith("raise it with max_unpacked_mib=") and "--max" not in msg, msg
        with pytest.raises(di.InputError) as e:
            di.read_log(hostile / name, max_unpacked_mib=1)
        assert f"{what} 1 MiB" in str(e.value), str(e.value)
    # One chunk of 100 MiB: refused under a bound of 50 MiB, before it is decompressed.
    with pytest.raises(di.InputError) as e:
        di.read_log(hostile / "chunk_100mib.mcap", max_unpacked_mib=50)
    assert "more than 50 MiB" in str(e.value), str(e.value)


def test_several_logs_per_fit(psm, recordings, run_cli, tmp_path):
    """A log cut in two parts recorded apart: Python's fit([a, b]) and `fit a b` agree,
    list both inputs with their own metrics, and differ from one log."""
    files = recordings["files"]
    a = di.read_log(files["ROS 1 bag"], psm)[:2500]
    b = di.read_log(files["official MCAP writer"], psm)[3500:]
    pa, pb = tmp_path / "a.csv", tmp_path / "b.mcap"
    a.write(pa)
    b.write(pb, topic="/PSM1/measured_js")
    la, lb = di.read_log(pa, psm), di.read_log(pb, psm)
    r = di.fit(psm, [la, lb], method="wls", test=[lb])
    doc = run_cli("fit", pa, pb, "--robot", "psm", "--method", "wls", "--test", pb, "--json")
    np.testing.assert_allclose(base_values(r), [b["value"] for b in doc["base_parameters"]], rtol=1e-12)
    assert [i["role"] for i in r.inputs] == ["train", "train", "test"]
    for mine, cli in zip(r.inputs, doc["inputs"]):
        assert mine["sha256"] == cli["sha256"]
        np.testing.assert_allclose(mine["metrics"]["rms"], cli["metrics"]["rms"], rtol=1e-12)
    trim = 200
    assert r.inputs[0]["metrics"]["samples"] == len(la) - 2 * trim
    assert r.metrics["train"]["samples"] == len(la) + len(lb) - 4 * trim
    # The same samples without a file (a slice has none): hashed by samples, listed
    # all the same, the same fit.
    r2 = di.fit(psm, [la[:], lb[:]], method="wls", test=lb[:])
    assert [i["path"] for i in r2.inputs] == ["", "", ""]
    assert r2.parameters == r.parameters


def test_real_psm_data_in_a_rosbag2_folder_and_a_ros1_bag(psm, tmp_path):
    """The real 2019 PSM log in measured joints, as a ROS 2 lab and a ROS 1 lab would
    record it: the same base parameters as its CSV."""
    path = shared_file("data", "dvrk", "psm", "one_results.csv")
    wpi = di.read_log(path, psm, format="wpi-csv", rate=200)
    C = psm.coupling
    n = len(wpi)
    stamps = T0_NS + np.arange(n, dtype=np.int64) * 5_000_000
    q, dq, tau = wpi.q @ C.T, wpi.dq @ C.T, wpi.tau @ np.linalg.inv(C)
    topics = bags.psm_topics(psm.measured_joints, stamps, q, dq, tau)
    csv = tmp_path / "one.csv"
    di.JointLog(stamps, q, tau, dq=dq, joint_names=psm.measured_joints).write(csv)
    want = base_values(di.fit(psm, di.read_log(csv, psm), method="ols", cutoff=16.965))
    for rec in (bags.rosbag2(tmp_path / "one_bag", topics, storage="sqlite3", split=2),
                bags.ros1(tmp_path / "one.bag", topics, compression="lz4")):
        got = base_values(di.fit(psm, di.read_log(rec, psm), method="ols", cutoff=16.965))
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * np.abs(want).max())
