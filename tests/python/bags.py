"""Recordings written the way labs record them, by writers this project did not write:
`rosbags` (rosbag2 folders with MCAP or sqlite3 storage, split files, file and message
compression; ROS 1 bags) and the official `mcap` + `mcap-ros2-support` writer.

A recording is given as a dict topic -> Series; every JointState is written in its
topic's joint order with its own header stamp, and two unrelated topics are added (a
pose and a status string, as a dVRK console publishes beside the joints), plus a
setpoint JointState without efforts, which the automatic topic choice must pass over.

Used by tests/python/test_bags.py and by the generator of the Rust fixtures,
crates/dvrk-logs/tests/fixtures/bags/gen_bags.py.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# The receive (log) time of a message is its stamp plus this, ns.
LOG_DELAY_NS = 250_000


@dataclass
class Series:
    """One JointState topic: stamps (int ns since the epoch) and (N, joints) arrays
    (velocity may be None: empty velocity arrays)."""

    names: list
    stamps_ns: np.ndarray
    position: np.ndarray
    velocity: np.ndarray | None
    effort: np.ndarray


def _typestore(ros1=False):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _messages(topics: dict, store, ros1: bool):
    """(log time ns, topic, msgtype, serialized bytes) of every message, in log-time
    order (stable: topic order at equal times), the extra topics included."""
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    PoseStamped = store.types["geometry_msgs/msg/PoseStamped"]
    Pose = store.types["geometry_msgs/msg/Pose"]
    Point = store.types["geometry_msgs/msg/Point"]
    Quaternion = store.types["geometry_msgs/msg/Quaternion"]
    String = store.types["std_msgs/msg/String"]
    ser = store.serialize_ros1 if ros1 else store.serialize_cdr

    def header(ns, seq=0):
        stamp = Time(sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))
        if ros1:
            return Header(seq=seq, stamp=stamp, frame_id="")
        return Header(stamp=stamp, frame_id="")

    out = []
    first = next(iter(topics.values()))
    for order, (topic, s) in enumerate(topics.items()):
        for k, ns in enumerate(s.stamps_ns):
            msg = JointState(
                header=header(int(ns), k),
                name=list(s.names),
                position=np.ascontiguousarray(s.position[k], dtype=np.float64),
                velocity=(
                    np.zeros(0)
                    if s.velocity is None
                    else np.ascontiguousarray(s.velocity[k], dtype=np.float64)
                ),
                effort=np.ascontiguousarray(s.effort[k], dtype=np.float64),
            )
            t = int(ns) + LOG_DELAY_NS
            out.append((t, order, topic, "sensor_msgs/msg/JointState", ser(msg, "sensor_msgs/msg/JointState")))
    n_topics = len(topics)
    for k, ns in enumerate(first.stamps_ns):
        t = int(ns) + LOG_DELAY_NS
        if k % 2 == 0:
            setpoint = JointState(
                header=header(int(ns), k),
                name=list(first.names),
                position=np.ascontiguousarray(first.position[k], dtype=np.float64),
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
            out.append((t, n_topics, "/PSM1/setpoint_js", "sensor_msgs/msg/JointState",
                        ser(setpoint, "sensor_msgs/msg/JointState")))
            pose = PoseStamped(
                header=header(int(ns), k),
                pose=Pose(
                    position=Point(x=0.01 * k, y=0.0, z=-0.1),
                    orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
                ),
            )
            out.append((t, n_topics + 1, "/PSM1/measured_cp", "geometry_msgs/msg/PoseStamped",
                        ser(pose, "geometry_msgs/msg/PoseStamped")))
        if k % 8 == 0:
            out.append((t, n_topics + 2, "/PSM1/status", "std_msgs/msg/String",
                        ser(String(data=f"sample {k}"), "std_msgs/msg/String")))
    out.sort(key=lambda m: (m[0], m[1]))
    return [(t, topic, kind, data) for t, _, topic, kind, data in out]


def rosbag2(path, topics: dict, *, storage="mcap", compression=None, split=1):
    """A rosbag2 folder at `path` (must not exist) written by rosbags: `storage` "mcap"
    or "sqlite3", `compression` None, "file" or "message" (zstd), `split` files (the
    messages cut in that many consecutive parts, each a file of the folder, listed in
    order in metadata.yaml as `ros2 bag record --max-bag-size` does)."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin
    from ruamel.yaml import YAML

    path = Path(path)
    store = _typestore()
    msgs = _messages(topics, store, ros1=False)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    parts = np.array_split(np.arange(len(msgs)), split)
    work = Path(tempfile.mkdtemp(prefix="bags-"))
    try:
        metas = []
        for i, idx in enumerate(parts):
            part = work / f"{path.name}_{i}"
            writer = Writer(part, version=9, storage_plugin=plugin)
            if compression == "file":
                writer.set_compression(CompressionMode.FILE, CompressionFormat.ZSTD)
            elif compression == "message":
                writer.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
            with writer:
                conns = {}
                for j in idx:
                    t, topic, kind, data = msgs[j]
                    if topic not in conns:
                        conns[topic] = writer.add_connection(topic, kind, typestore=store)
                    writer.write(conns[topic], t, data)
            metas.append(part)
        path.mkdir()
        yaml = YAML(typ="safe")
        first = yaml.load((metas[0] / "metadata.yaml").read_text())
        info = first["rosbag2_bagfile_information"]
        files, relative = [], []
        for i, part in enumerate(metas):
            meta = yaml.load((part / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
            for entry in meta["files"]:
                src = part / entry["path"]
                # rosbag2's split names: <bag>_<index>.<ext>
                name = f"{path.name}_{i}" + "".join(Path(entry["path"]).suffixes)
                shutil.move(src, path / name)
                files.append({**entry, "path": name})
                relative.append(name)
        info["relative_file_paths"] = relative
        info["files"] = files
        info["message_count"] = sum(f["message_count"] for f in files)
        with open(path / "metadata.yaml", "w") as out:
            yaml.dump(first, out)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return path


def ros1(path, topics: dict, *, compression=None):
    """A ROS 1 bag (format 2.0) written by rosbags: `compression` None, "lz4" or "bz2"
    chunks."""
    from rosbags.rosbag1 import Writer

    store = _typestore(ros1=True)
    msgs = _messages(topics, store, ros1=True)
    writer = Writer(Path(path))
    if compression == "lz4":
        writer.set_compression(Writer.CompressionFormat.LZ4)
    elif compression == "bz2":
        writer.set_compression(Writer.CompressionFormat.BZ2)
    with writer:
        conns = {}
        for t, topic, kind, data in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, kind, typestore=store)
            writer.write(conns[topic], t, data)
    return Path(path)


def official_mcap(path, topics: dict, *, compression="zstd"):
    """An MCAP file written by the official `mcap` + `mcap-ros2-support` writer, the
    messages as dicts (its own CDR encoder); `compression` "zstd", "lz4" or None."""
    from mcap.writer import CompressionType
    from mcap_ros2.writer import Writer

    store = _typestore()
    kinds = {
        "sensor_msgs/msg/JointState": None,
        "geometry_msgs/msg/PoseStamped": None,
        "std_msgs/msg/String": None,
    }
    first = next(iter(topics.values()))
    ctype = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, None: CompressionType.NONE}[compression]

    def stamp(ns):
        return {"sec": int(ns // 1_000_000_000), "nanosec": int(ns % 1_000_000_000)}

    events = []
    for order, (topic, s) in enumerate(topics.items()):
        for k, ns in enumerate(s.stamps_ns):
            msg = {
                "header": {"stamp": stamp(ns), "frame_id": ""},
                "name": list(s.names),
                "position": [float(v) for v in s.position[k]],
                "velocity": [] if s.velocity is None else [float(v) for v in s.velocity[k]],
                "effort": [float(v) for v in s.effort[k]],
            }
            events.append((int(ns) + LOG_DELAY_NS, order, topic, "sensor_msgs/msg/JointState", msg))
    n = len(topics)
    for k, ns in enumerate(first.stamps_ns):
        t = int(ns) + LOG_DELAY_NS
        if k % 2 == 0:
            events.append((t, n, "/PSM1/setpoint_js", "sensor_msgs/msg/JointState", {
                "header": {"stamp": stamp(ns), "frame_id": ""},
                "name": list(first.names),
                "position": [float(v) for v in first.position[k]],
                "velocity": [], "effort": [],
            }))
            events.append((t, n + 1, "/PSM1/measured_cp", "geometry_msgs/msg/PoseStamped", {
                "header": {"stamp": stamp(ns), "frame_id": ""},
                "pose": {"position": {"x": 0.01 * k, "y": 0.0, "z": -0.1},
                         "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
            }))
        if k % 8 == 0:
            events.append((t, n + 2, "/PSM1/status", "std_msgs/msg/String", {"data": f"sample {k}"}))
    events.sort(key=lambda e: (e[0], e[1]))
    with open(path, "wb") as f:
        writer = Writer(f, compression=ctype)
        for kind in kinds:
            text, _ = store.generate_msgdef(kind, ros_version=2)
            kinds[kind] = writer.register_msgdef(kind, text)
        for t, _, topic, kind, msg in events:
            writer.write_message(topic, kinds[kind], msg, log_time=t, publish_time=t)
        writer.finish()
    return Path(path)


def compress_file(src, dst, fmt):
    """`src` compressed as a whole into `dst`: "zstd" (zstandard) or "lz4" (lz4.frame)."""
    data = Path(src).read_bytes()
    if fmt == "zstd":
        import zstandard

        out = zstandard.ZstdCompressor().compress(data)
    else:
        import lz4.frame

        out = lz4.frame.compress(data)
    Path(dst).write_bytes(out)
    return Path(dst)


def psm_topics(names, stamps_ns, position, velocity, effort, *, jaw_topic=True):
    """The dVRK 2.x PSM layout: the six arm joints on /PSM1/measured_js and, with
    `jaw_topic`, the jaw (last column) on /PSM1/jaw/measured_js with the same stamps;
    else all seven on /PSM1/measured_js."""
    if not jaw_topic:
        return {"/PSM1/measured_js": Series(list(names), stamps_ns, position, velocity, effort)}
    cut = lambda a, sl: None if a is None else a[:, sl]  # noqa: E731
    arm, jaw = slice(0, 6), slice(6, 7)
    return {
        "/PSM1/measured_js": Series(list(names[:6]), stamps_ns, position[:, arm], cut(velocity, arm), effort[:, arm]),
        "/PSM1/jaw/measured_js": Series(list(names[6:]), stamps_ns, position[:, jaw], cut(velocity, jaw), effort[:, jaw]),
    }
