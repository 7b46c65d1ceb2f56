"""``ibr batch JOBS.json``: run a list of ``ibr`` command lines on a local pool or a Dask cluster.

Each job is one ``ibr`` command line (schema in :mod:`ibr.sequence.jobs` and docs/sequences.md).
Jobs are idempotent: outputs are staged and renamed into place only when the command succeeded,
and a record of the inputs' and outputs' checksums makes a re-run skip finished jobs. By default
the jobs run on a local process pool sized to the machine; ``--scheduler tcp://HOST:8786`` sends
them to an existing Dask cluster (``pip install "ibr[dask]"``). A failing job is reported and
the others go on; the exit code is 1 if any job failed.
"""

from __future__ import annotations

HELP = "run a batch of ibr command lines (JSON) on a local process pool or a Dask cluster, idempotently"


def add_arguments(parser) -> None:
    from commands._common import positive_float, positive_int

    parser.add_argument("jobs", metavar="JOBS.json", help="batch file: a list of ibr command lines (docs/sequences.md)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="Dask scheduler address (e.g. tcp://10.0.0.5:8786); default: a local process pool")
    parser.add_argument("--workers", type=positive_int, default=None, metavar="N",
                        help="local pool size (default: the number of CPUs); ignored with --scheduler")
    parser.add_argument("--threads-per-job", type=positive_int, default=1, metavar="N",
                        help="threads each job may use (default: %(default)s; the pool uses the cores)")
    parser.add_argument("--timeout", type=positive_float, default=None, metavar="S", help="seconds per job before it is killed")
    parser.add_argument("--records", metavar="DIR",
                        help="records folder, shared by all workers (default: .ibr-batch/ beside JOBS.json)")
    parser.add_argument("--report", metavar="REPORT.json",
                        help="JSON report of every job (default: JOBS.report.json beside JOBS.json)")


def run(args) -> int:
    from pathlib import Path

    from commands._common import counted, info
    from commands._sequence import Progress
    from ibr.sequence.batch import run_batch
    from ibr.sequence.jobs import check_batch_files, load_jobs

    import cli  # the parser ibr itself uses: each job's command line is checked as ibr would read it

    jobs_path = Path(args.jobs)
    jobs = load_jobs(jobs_path, parser=cli.build_parser())
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers: expected an integer >= 1, got {args.workers}")
    if args.threads_per_job < 1:
        raise ValueError(f"--threads-per-job: expected an integer >= 1, got {args.threads_per_job}")
    if args.timeout is not None and not args.timeout > 0:
        raise ValueError(f"--timeout: expected a positive number of seconds, got {args.timeout}")
    records = Path(args.records) if args.records else jobs_path.resolve().parent / ".ibr-batch"
    report_path = Path(args.report) if args.report else jobs_path.with_name(jobs_path.stem + ".report.json")
    if report_path.is_dir():
        raise IsADirectoryError(f"--report: {report_path} is a folder, expected a .json file name")
    if not report_path.parent.is_dir():
        raise FileNotFoundError(f"--report: the folder {report_path.parent} does not exist")
    check_batch_files(jobs, jobs_path, records, report_path)  # no record or report over a file of the batch
    if args.scheduler:
        try:
            import distributed  # noqa: F401
        except ImportError:
            raise RuntimeError('--scheduler: Dask is not installed; pip install "ibr[dask]" '
                               '(or "dask[distributed]")') from None
    where = f"Dask scheduler {args.scheduler}" if args.scheduler else "the local pool"
    info(f"batch: {counted(len(jobs), 'job')} from {jobs_path} on {where}; records in {records}")
    bar = Progress(len(jobs), "batch", unit="jobs")

    def on_result(res):
        last = (res.get("error") or "").strip().splitlines()[-1:] or ["no message"]
        note = "" if res["status"] != "failed" else f"({res['id']} failed: {last[0]})"
        bar.step(note=note)

    report = run_batch(jobs, records=records, scheduler=args.scheduler, workers=args.workers,
                       threads_per_job=args.threads_per_job, timeout=args.timeout, on_result=on_result)
    print(report.table())
    report.write(report_path)
    info(f"batch: report {report_path}")
    return 0 if report.ok else 1
