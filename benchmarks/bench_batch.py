"""Throughput of ``ibr batch`` on a Dask LocalCluster: 2 workers against 1, and 4 workers on 2 cores.

Run (under the benchmark lock, the machine is shared)::

    flock /tmp/ibr-bench.lock python benchmarks/bench_batch.py [--jobs 200] [--rounds 2]

The batch is ``--jobs`` ``ibr stereo`` command lines (side-by-side pairs of 64 x 48 synthetic
views; about 1 s each, most of it the job process starting). The 1-worker and the 2-worker
clusters run it in the same run: ``--rounds`` slices, each run on both clusters back to back in
alternating (ABBA) order so that load from other users hits both alike. Printed: the ratio of
total throughputs (jobs/s) and the median of the per-round ratios (robust to a load burst).
Then a 4-worker cluster (oversubscribing the 2 cores) runs the whole batch once more; its outputs
must equal the 1-worker outputs pixel for pixel, and every job must be committed exactly once.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

MODES = ("sbs", "anaglyph", "dubois", "tb")


def make_views(folder: Path, n: int = 8):
    from ibr.io import save_view
    from ibr.synth import camera_path, make_scene, render_path

    (folder / "views").mkdir(parents=True, exist_ok=True)
    (folder / "out").mkdir(exist_ok=True)  # the jobs' output folder (a job, like the command, does not make it)
    views = render_path(make_scene("room"), camera_path("room", n, width=64, height=48), supersample=1, name="v")
    for v in views:
        save_view(v, folder / "views" / f"{v.name}.json")
    return [f"views/{v.name}.json" for v in views]


def write_jobs(folder: Path, views, ids) -> Path:
    jobs = [{"id": f"job-{i:04d}", "argv": ["stereo", views[i % len(views)], "--mode", MODES[i % len(MODES)],
                                            "-o", f"out/job_{i:04d}.png"]} for i in ids]
    path = folder / f"jobs_{ids[0]:04d}.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}))
    return path


def run(path: Path, client) -> tuple[float, object]:
    from ibr.sequence import load_jobs, run_batch

    t0 = time.perf_counter()
    rep = run_batch(load_jobs(path), records=path.parent / ".ibr-batch", scheduler=client)
    return time.perf_counter() - t0, rep


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=200, help="jobs per configuration (default: %(default)s)")
    ap.add_argument("--rounds", type=int, default=5,
                    help="rounds; each runs one slice on each cluster, order alternating (default: %(default)s)")
    ap.add_argument("--quick", action="store_true", help="24 jobs, 1 round (ibr bench)")
    args = ap.parse_args(argv)
    if args.quick:
        args.jobs, args.rounds = 24, 1
    import numpy as np
    from distributed import Client, LocalCluster

    from ibr.io import read_image

    work = Path(tempfile.mkdtemp(prefix="ibr-bench-batch-"))
    try:
        base = {n: work / f"w{n}" for n in (1, 2, 4)}
        views = make_views(work / "views_src")
        for folder in base.values():
            shutil.copytree(work / "views_src", folder)
        per = args.jobs // args.rounds
        slices = [list(range(k * per, (k + 1) * per)) for k in range(args.rounds)]
        kw = dict(threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=50)
        totals = {1: 0.0, 2: 0.0}
        counts = {1: 0, 2: 0}
        ratios = []
        with LocalCluster(n_workers=1, **kw) as c1, Client(c1) as k1, LocalCluster(n_workers=2, **kw) as c2, \
                Client(c2) as k2:
            clients = {1: k1, 2: k2}
            warm = write_jobs(work / "views_src", views, [9999])  # job process start-up and numba cache, once
            run(warm, k1), run(warm, k2)
            for r, ids in enumerate(slices):
                order = (1, 2) if r % 2 == 0 else (2, 1)  # ABBA: 1 2 | 2 1 | 1 2 ...
                dts = {}
                for n in order:  # the same jobs on both clusters, back to back
                    dt, rep = run(write_jobs(base[n], views, ids), clients[n])
                    assert rep.counts["done"] == len(ids), rep.table()
                    totals[n] += dt
                    counts[n] += len(ids)
                    dts[n] = dt
                ratios.append(dts[1] / dts[2])
                print(f"round {r}: {len(ids)} jobs, 1 worker {dts[1]:.1f} s, 2 workers {dts[2]:.1f} s: "
                      f"{ratios[-1]:.2f}x (machine load average {os.getloadavg()[0]:.1f}, this run adds ~1-2)",
                      flush=True)
        jobs_done = counts[1]
        rate1, rate2 = counts[1] / totals[1], counts[2] / totals[2]
        print(f"\n{jobs_done} jobs per configuration (ibr stereo, 64x48, ~1 s each)")
        print(f"{'workers':>8} {'seconds':>9} {'jobs/s':>8} {'vs 1 worker':>12}")
        print(f"{1:>8} {totals[1]:9.1f} {rate1:8.2f} {1.0:12.2f}")
        print(f"{2:>8} {totals[2]:9.1f} {rate2:8.2f} {rate2 / rate1:12.2f}")

        # 4 workers on 2 cores: the whole batch at once; same pixels, each job committed once.
        ids = [i for s in slices for i in s]
        with LocalCluster(n_workers=4, **kw) as c4, Client(c4) as k4:
            dt4, rep4 = run(write_jobs(base[4], views, ids), k4)
        log = [json.loads(x) for x in (base[4] / ".ibr-batch" / "commits.log").read_text().splitlines()]
        once = sorted(x["id"] for x in log if x["run"] == rep4.run_id) == sorted(f"job-{i:04d}" for i in ids)
        same = all(np.array_equal(read_image(base[4] / "out" / f"job_{i:04d}.png"),
                                  read_image(base[1] / "out" / f"job_{i:04d}.png")) for i in ids)
        leftovers = [p.name for p in (base[4] / "out").iterdir() if p.name.startswith(".")]
        print(f"{4:>8} {dt4:9.1f} {len(ids) / dt4:8.2f} {len(ids) / dt4 / rate1:12.2f}   "
              f"(oversubscribed: {rep4.counts['done']} done, {rep4.counts['failed']} failed; "
              f"pixels equal to 1 worker: {same}; committed exactly once: {once}; leftovers: {len(leftovers)})")
        ok = rep4.counts["done"] == len(ids) and same and once and not leftovers
        print(f"\n2 workers vs 1: {rate2 / rate1:.2f}x over all jobs, median of the per-round ratios "
              f"{np.median(ratios):.2f}x (target >= 1.7x); 4 workers on 2 cores correct: {ok}")
        return 0 if ok else 1
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
