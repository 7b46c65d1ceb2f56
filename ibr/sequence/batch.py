"""Run a batch of jobs on a local process pool or on an existing Dask cluster.

The work of one job (:func:`ibr.sequence.jobs.run_job`: checksums, staging, the command's process,
commit, record) is the same everywhere; only who calls it differs:

* **local** (default): a :class:`concurrent.futures.ProcessPoolExecutor` sized to the machine. A
  pool process that dies (killed, out of memory) breaks the pool: the jobs that had not returned
  are submitted again to a fresh pool (at most ``retries`` times each); an attempt that had
  already committed is recognised by its record and not run twice.
* **Dask** (``scheduler=``): ``distributed.Client(address)`` submits one task per job; the
  scheduler moves the task of a worker that dies to another worker (Dask's own retry, up to its
  ``distributed.scheduler.allowed-failures``), and ``KilledWorker`` is reported as the job's
  failure. No scheduling logic lives here.

A failing job never stops the others: its status is ``failed`` with the command's last stderr
lines. :class:`BatchReport` holds every result, prints a summary table and writes a JSON report.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import time
import uuid
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..io.images import atomic_path
from .jobs import Job, run_job

__all__ = ["BatchReport", "run_batch"]


@dataclass
class BatchReport:
    """Results of :func:`run_batch`.

    Attributes
    ----------
    results : list of dict
        One :func:`~ibr.sequence.jobs.run_job` result per job, in the batch file's order.
    seconds : float
        Wall time of the batch.
    where : str
        ``"local pool (N processes)"`` or ``"dask <address>"``.
    run_id : str
    """

    results: list
    seconds: float
    where: str
    run_id: str
    counts: dict = field(init=False)

    def __post_init__(self):
        self.counts = {s: sum(r["status"] == s for r in self.results) for s in ("done", "skipped", "failed")}

    @property
    def ok(self) -> bool:
        """True when no job failed."""
        return self.counts["failed"] == 0

    def table(self, *, max_rows: int = 40) -> str:
        """A plain-text summary: totals, then the failed jobs (all of them) and the slowest done ones."""
        done = [r for r in self.results if r["status"] == "done"]
        lines = [f"batch: {len(self.results)} job{'s' if len(self.results) != 1 else ''} on {self.where} in {self.seconds:.1f} s: "
                 f"{self.counts['done']} done, {self.counts['skipped']} skipped (up to date), "
                 f"{self.counts['failed']} failed"]
        if done:
            rate = len(done) / self.seconds if self.seconds > 0 else float("inf")
            lines[0] += f"; {rate:.2f} jobs/s"
        rows = [r for r in self.results if r["status"] == "failed"]
        rows += sorted(done, key=lambda r: -r["seconds"])[: max(0, max_rows - len(rows))]
        if rows:
            w = max(len(r["id"]) for r in rows)
            lines.append(f"{'job':<{w}}  {'status':<7}  {'seconds':>7}  worker / error")
            for r in rows:
                what = r["error"].splitlines()[-1] if r["status"] == "failed" and r["error"] else r["worker"]
                lines.append(f"{r['id']:<{w}}  {r['status']:<7}  {r['seconds']:7.2f}  {what}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": "ibr-batch-report", "version": 1, "run": self.run_id, "where": self.where,
                "seconds": round(self.seconds, 3), "counts": self.counts, "jobs": self.results}

    def write(self, path) -> Path:
        """Write the JSON report atomically."""
        path = Path(path)
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="utf-8")
        return path


def _lost(job: Job, error: str, attempts: int) -> dict:
    return {"id": job.id, "argv": list(job.argv), "status": "failed", "seconds": 0.0, "worker": "",
            "returncode": None, "error": f"{error} (after {attempts} attempt(s))", "outputs": [],
            "interrupted_attempts": 0, "recovered": False}


def _run_local(jobs, run_id, records, workers, threads_per_job, timeout, retries, on_result):
    results: dict[str, dict] = {}
    attempts = {j.id: 0 for j in jobs}
    pending = list(jobs)
    while pending:
        for j in pending:
            attempts[j.id] += 1
        broken: list[Job] = []
        # spawn: a pool started from a process with threads (a Dask client, a GUI) never forks them
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = {pool.submit(run_job, j.to_dict(), run_id, str(records), threads_per_job=threads_per_job,
                                   timeout=timeout): j for j in pending}
            not_done = set(futures)
            while not_done:
                finished, not_done = wait(not_done, return_when=FIRST_COMPLETED)
                for fut in finished:
                    job = futures[fut]
                    try:
                        res = fut.result()
                    except BrokenProcessPool:
                        broken.append(job)
                        continue
                    except Exception as exc:  # noqa: BLE001 - e.g. a result that cannot be unpickled
                        res = _lost(job, f"{type(exc).__name__}: {exc}", attempts[job.id])
                    results[job.id] = res
                    if on_result is not None:
                        on_result(res)
        pending = []
        for job in broken:
            if attempts[job.id] > retries:
                res = _lost(job, "the pool process running it died", attempts[job.id])
                results[job.id] = res
                if on_result is not None:
                    on_result(res)
            else:
                pending.append(job)
    return results


def _run_dask(jobs, run_id, records, scheduler, threads_per_job, timeout, on_result):
    from distributed import Client, as_completed  # optional extra: pip install "ibr[dask]"

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    address = client.scheduler.address
    try:
        futures = {}
        for j in jobs:
            fut = client.submit(run_job, j.to_dict(), run_id, str(records), threads_per_job=threads_per_job,
                                timeout=timeout, key=f"ibr-job-{j.id}-{run_id}", pure=False)
            futures[fut.key] = (fut, j)
        results: dict[str, dict] = {}
        for fut in as_completed([f for f, _ in futures.values()]):
            job = futures[fut.key][1]
            try:
                res = fut.result()
            except Exception as exc:  # noqa: BLE001 - KilledWorker, lost scheduler ...
                res = _lost(job, f"{type(exc).__name__}: {exc}", 0)
            fut.release()  # the result is read: a later worker loss must not recompute it
            results[job.id] = res
            if on_result is not None:
                on_result(res)
        return results, address
    finally:
        if client is not scheduler:
            client.close()


def run_batch(
    jobs: list[Job],
    *,
    records,
    scheduler=None,
    workers: int | None = None,
    threads_per_job: int = 1,
    timeout: float | None = None,
    retries: int = 3,
    on_result: Callable[[dict], None] | None = None,
) -> BatchReport:
    """Run jobs concurrently and idempotently (module docstring).

    Parameters
    ----------
    jobs : list of Job
        From :func:`ibr.sequence.load_jobs`.
    records : str or Path
        Records folder (must be on a file system every worker sees).
    scheduler : str or distributed.Client, optional
        Dask scheduler address (``"tcp://host:8786"``) or a connected client; default: the local pool.
    workers : int, optional
        Local pool size (default ``os.cpu_count()``); ignored with ``scheduler``.
    threads_per_job : int
        Threads each job's process may use (default 1: the pool, not the job, uses the cores).
    timeout : float, optional
        Seconds per job before its process is killed.
    retries : int
        Local pool: how often a job whose pool process died is submitted again.
    on_result : callable, optional
        Called with each result as it arrives (progress lines; tests use it to kill a worker).
    """
    jobs = list(jobs)
    if not jobs:
        raise ValueError("jobs: expected at least one job, got none")
    if not all(isinstance(j, Job) for j in jobs):
        raise TypeError("jobs: expected Job objects (from ibr.sequence.load_jobs)")
    if isinstance(threads_per_job, bool) or not isinstance(threads_per_job, int) or threads_per_job < 1:
        raise ValueError(f"threads_per_job: expected an integer >= 1, got {threads_per_job!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers: expected an integer >= 1, got {workers!r}")
    records = Path(records).resolve()
    records.mkdir(parents=True, exist_ok=True)
    run_id = time.strftime("%Y%m%dT%H%M%S") + "-" + uuid.uuid4().hex[:8]
    start = time.perf_counter()
    if scheduler is None:
        n = workers or os.cpu_count() or 1
        results = _run_local(jobs, run_id, records, n, threads_per_job, timeout, retries, on_result)
        where = f"local pool ({n} processes)"
    else:
        results, address = _run_dask(jobs, run_id, records, scheduler, threads_per_job, timeout, on_result)
        where = f"dask {address}"
    return BatchReport([results[j.id] for j in jobs], time.perf_counter() - start, where, run_id)
