"""Writes the compressed seeds of fuzz/seeds/mcap/ (issue 32: compressed inputs in the
fuzz targets), so that the `mcap` target starts from every compressed layout a reader
meets: chunk compression (MCAP lz4 chunks; the zstd one is psm_20_samples.mcap), whole
files in a zstd or lz4 frame (MCAP, sqlite3), ROS 1 chunks (bz2, lz4) and two zstd
bombs (a sqlite3 frame declaring, and a ROS 1 frame only expanding to, more than the
target's bound).

Run from the repository root with the test venv (rosbags, mcap, mcap-ros2-support):

    .venv-ci/bin/python fuzz/seeds/gen_compressed.py

The recordings are those of crates/dvrk-logs/tests/fixtures/bags/gen_bags.py cut to
four samples (the seeds stay small: libFuzzer mutates small inputs faster).
"""

import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "fuzz" / "seeds" / "mcap"
sys.path.insert(0, str(ROOT / "crates" / "dvrk-logs" / "tests" / "fixtures" / "bags"))
import gen_bags  # noqa: E402
import bags  # noqa: E402  (put on the path by gen_bags)


def topics():
    # all seven joints on one topic: the target reads with the automatic topic choice
    return gen_bags.samples(4, jaw_topic=False)


def only_file(folder: Path, pattern: str) -> Path:
    (found,) = folder.glob(pattern)
    return found


def main():
    import zstandard

    t = topics()
    for old in list(OUT.glob("compressed-*")) + list(OUT.glob("bomb-*")):
        old.unlink()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        bags.official_mcap(OUT / "compressed-lz4-chunks.mcap", t, compression="lz4")
        bags.rosbag2(tmp / "file_zstd", t, storage="mcap", compression="file")
        shutil.copy(only_file(tmp / "file_zstd", "*.zstd"), OUT / "compressed-file.mcap.zst")
        bags.official_mcap(tmp / "plain.mcap", t, compression=None)
        bags.compress_file(tmp / "plain.mcap", OUT / "compressed-file.mcap.lz4", "lz4")
        bags.rosbag2(tmp / "sqlite_zstd", t, storage="sqlite3", compression="file")
        shutil.copy(only_file(tmp / "sqlite_zstd", "*.zstd"), OUT / "compressed-file.db3.zst")
        bags.ros1(OUT / "compressed-bz2-chunks.bag", t, compression="bz2")
        bags.ros1(OUT / "compressed-lz4-chunks.bag", t, compression="lz4")
    # A recording's magic and 32 MiB of zeros, twice the target's bound (src/lib.rs,
    # MAX_UNPACKED_MIB): sqlite3 with the size in the frame header, ROS 1 streamed (no
    # size: found only while expanding). Both kinds are expanded into a temporary file
    # before they are opened, so the bound, not the content, must stop them.
    zeros = bytes(32 << 20)
    sqlite = b"SQLite format 3\x00" + zeros
    (OUT / "bomb-declared.db3.zst").write_bytes(zstandard.ZstdCompressor(level=19).compress(sqlite))
    streamed = zstandard.ZstdCompressor(level=19, write_content_size=False).compressobj()
    ros1 = b"#ROSBAG V2.0\n" + zeros
    (OUT / "bomb-streamed.bag.zst").write_bytes(streamed.compress(ros1) + streamed.flush())
    for p in sorted(OUT.glob("compressed-*")) + sorted(OUT.glob("bomb-*")):
        print(f"{p.relative_to(ROOT)}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
