"""A fleet of logs fitted on Dask: the map (`di.observe`, one log per task) on worker
processes, the reduce (merging the observations, `+`), then one fit; against the same
fit in one process. Prints the wall-clock time of each and the speed-up.

    python examples/fleet.py [--logs 16] [--periods 20] [--workers 2] [--repeat 3] [LOG ...]

Without LOG, `dvrk-ident simulate` writes the logs into a temporary folder (the bundled
example's parameters and excitation trajectory, `--periods` periods of 5.6 s at
200 Hz each, noise seeded per log); the binary is $DVRK_IDENT_BIN or
target/release/dvrk-ident. Needs `pip install "dask[distributed]"` and the module.
A benchmark, not a test: its times depend on the machine and its load.
"""

import argparse
import functools
import operator
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import dvrk_ident as di

REPO = Path(__file__).resolve().parents[1]


def simulate(folder, count, periods):
    exe = os.environ.get("DVRK_IDENT_BIN", str(REPO / "target" / "release" / "dvrk-ident"))
    paths = []
    for k in range(count):
        path = Path(folder) / f"arm_{k:03d}.mcap"
        subprocess.run(
            [exe, "simulate", "psm", "--params", REPO / "examples" / "psm_params.json",
             "--excitation", REPO / "examples" / "psm_trajectory.json",
             "--periods", str(periods), "--noise", "0.002", "--seed", str(k),
             "--out", path, "--quiet"],
            check=True,
        )
        paths.append(str(path))
    return paths


def timed(f, repeat):
    """The result of f() and its median wall-clock time over `repeat` runs, s."""
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - start)
    return result, statistics.median(times), times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("logs", nargs="*")
    parser.add_argument("--logs", dest="count", type=int, default=16)
    parser.add_argument("--periods", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--method", default="wls")
    parser.add_argument("--engine-threads", type=int, default=None,
                        help="RAYON_NUM_THREADS of the Dask workers (default: one per CPU, "
                             "as the engine in one process)")
    args = parser.parse_args()

    import dask.bag as db
    import distributed

    psm = di.Model.load("psm")
    with tempfile.TemporaryDirectory() as folder:
        paths = args.logs or simulate(folder, args.count, args.periods)
        print(f"{len(paths)} logs, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")

        # One process: read every log, the fit of them all (the engine's own threads).
        def single():
            return di.fit(psm, [di.read_log(p, psm) for p in paths], method=args.method)

        # One process, the map and reduce in a loop.
        def serial():
            obs = functools.reduce(operator.add, (di.observe(psm, p) for p in paths))
            return di.fit(psm, obs, method=args.method)

        reference, t_single, all_single = timed(single, args.repeat)
        _, t_serial, all_serial = timed(serial, args.repeat)

        if args.engine_threads:
            # Read by the worker processes when they start; this process's engine
            # threads already exist.
            os.environ["RAYON_NUM_THREADS"] = str(args.engine_threads)
        started = time.perf_counter()
        with distributed.LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True,
            dashboard_address=None,
        ) as cluster, distributed.Client(cluster) as client:
            t_start = time.perf_counter() - started
            observe = functools.partial(di.observe, psm)

            def on_dask():
                obs = (db.from_sequence(paths, npartitions=len(paths))
                       .map(observe).fold(operator.add).compute(scheduler=client))
                return di.fit(psm, obs, method=args.method)

            result, t_dask, all_dask = timed(on_dask, args.repeat)

    beta = np.array([b["value"] for b in result.base_parameters])
    beta_ref = np.array([b["value"] for b in reference.base_parameters])
    samples = reference.metrics["train"]["samples"]
    print(f"{samples} samples after processing; base parameters Dask vs one process: "
          f"{np.linalg.norm(beta - beta_ref) / np.linalg.norm(beta_ref):.1e} relative")
    for name, t, all_t in [("one process, fit of the logs", t_single, all_single),
                           ("one process, observe + merge + fit", t_serial, all_serial),
                           (f"Dask, {args.workers} worker processes", t_dask, all_dask)]:
        runs = ", ".join(f"{x:.2f}" for x in all_t)
        print(f"{name:<40} {t:7.2f} s (runs: {runs})")
    threads = args.engine_threads or os.cpu_count()
    print(f"Dask workers with {threads} engine thread(s) each; "
          f"cluster start-up {t_start:.2f} s (not counted); "
          f"speed-up over one process {t_single / t_dask:.2f}x")


if __name__ == "__main__":
    main()
