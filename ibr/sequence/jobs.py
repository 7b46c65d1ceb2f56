"""Idempotent batch jobs: one ``ibr`` command line each, staged outputs, a record of checksums.

A batch file lists jobs; a job is any ``ibr`` command line::

    {"format": "ibr-batch", "version": 1,
     "jobs": [{"id": "stereo_0001", "argv": ["stereo", "views/f_0001.json", "--mode", "sbs",
                                              "-o", "out/f_0001.png"]},
              {"command": "ibr interpolate views/f_0001.json views/f_0002.json --out out/mid_0001"},
              ...]}

(a bare list of jobs is accepted too). ``argv`` (or ``command``, split like a shell, a leading
``ibr`` optional) is the command line; ``id`` (default: a hash of the command line) names the
job's record; ``outputs`` lists the command-line values that are outputs (default: the values of
``-o/--out/--output/--video/--contact-sheet/--obj/--ply/--viz/--depth-out/--holes-out/--report/``
``--coverage/--cube/--site``, in any form the command reads: ``-o x``, ``--out=x``, ``-ox``; with the
``ibr`` parser (``load_jobs(path, parser=...)``, as ``ibr batch`` does) abbreviations too, and a
command line the command would refuse as a usage error is refused up front with its message);
``inputs`` adds input files the command line does not name; ``cwd`` (default: the batch file's
folder) is where relative paths start. Jobs are independent: no job may read another's output.

Running a job (:func:`run_job`, on any worker) is idempotent and leaves no partial file:

1. its inputs are checksummed (SHA-256): every existing file named on the command line, plus the
   colour/depth files of view files and the views of sequence manifests
   (:func:`ibr.sequence.referenced_files`), plus ``inputs``;
2. if the job's record exists with the same command line, the same input checksums and every
   output file present with its recorded checksum, nothing runs (``skipped``);
3. otherwise every output value on the command line is redirected into a hidden staging folder
   ``.ibr-batch-<id>-<token>/`` beside the output (or, when the output's folder does not exist,
   beside its nearest existing ancestor, keeping the missing folders in the staged path: nothing
   is created, and the command refuses a missing output folder as it does run alone), the
   command runs in a child process
   (``python -c`` running ``cli.main``; the child exits when its parent dies), and only when it
   succeeds are the staged files renamed into place (each rename atomic; files already in an output
   folder that the command did not write are left alone); the record, written
   atomically after them, marks the job done. A worker killed at any point leaves at most a
   staging folder, which the next attempt of the job removes before it starts. A job whose
   output (or a file of its output folder) is one of its inputs, after resolving links, fails
   before anything is renamed: the command itself cannot see that while it writes into the
   staging folder. A failing command's message names the job's own paths (``-o: out/m1.txt``),
   never the staged ones.

Records live in one folder (default ``.ibr-batch/`` beside the batch file): ``<id>.json`` with
the command line, input and output checksums, the run and attempt that committed it, and
``commits.log``, one line per commit (how the tests see that every job was committed once; a
worker killed between the record and its line leaves the line to the attempt that finds the
record).
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

from ..base.validate import check_keys
from ..io.images import atomic_path
from ..io.outputs import BATCH_FINALS_ENV
from .files import referenced_files

__all__ = [
    "BATCH_FORMAT",
    "OUTPUT_OPTIONS",
    "RECORD_FORMAT",
    "STAGE_PREFIX",
    "Job",
    "file_sha256",
    "load_jobs",
    "run_job",
]

BATCH_FORMAT = "ibr-batch"
RECORD_FORMAT = "ibr-batch-record"
STAGE_PREFIX = ".ibr-batch-"

#: Options whose value is an output path, for jobs that do not list their ``outputs``.
OUTPUT_OPTIONS = ("-o", "--out", "--output", "--video", "--contact-sheet", "--obj", "--ply", "--viz",
                  "--depth-out", "--holes-out", "--report", "--coverage", "--cube", "--site")
#: Of those, the ones a command reads instead (``ibr canvas --video CLIP``: the clip shown on the plane).
INPUT_OPTIONS = {"canvas": ("--video",)}
#: Values of an output option that name no file (``ibr stitch --depth-out none``: no depth written).
NO_OUTPUT = {("stitch", "--depth-out"): ("none",)}


def _is_output(command: str, option: str, value) -> bool:
    return (option in OUTPUT_OPTIONS and option not in INPUT_OPTIONS.get(command, ())
            and isinstance(value, str) and value not in NO_OUTPUT.get((command, option), ()))

#: Thread-count variables set to ``threads_per_job`` in each job's process (the pool, not the job,
#: uses the cores): numba, OpenMP/BLAS, OpenCV's parallel_for.
THREAD_ENV = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
              "OPENCV_FOR_THREADS_NUM")

# The job's process: exits when its parent (the worker) dies, then runs the ibr command line.
_BOOTSTRAP = (
    "import os, sys, threading, time\n"
    "_parent = os.getppid()\n"
    "def _watch():\n"
    "    while True:\n"
    "        time.sleep(0.2)\n"
    "        if os.getppid() != _parent:\n"
    "            os._exit(137)\n"
    "threading.Thread(target=_watch, daemon=True).start()\n"
    "import cli\n"
    "sys.exit(cli.main(sys.argv[1:]))\n"
)

_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")


@dataclass(frozen=True)
class Job:
    """One ``ibr`` command line of a batch (module docstring).

    Attributes
    ----------
    id : str
        Record name: letters, digits, ``._-``.
    argv : tuple of str
        The command line without the leading ``ibr`` (e.g. ``("stereo", "a.json", "-o", "a.png")``).
    cwd : str
        Absolute folder where relative paths start.
    outputs : tuple of str
        Command-line values that are output paths (files or folders).
    inputs : tuple of str
        Extra input paths (relative to ``cwd``) beyond those named on the command line.
    """

    id: str
    argv: tuple
    cwd: str
    outputs: tuple
    inputs: tuple = ()

    def to_dict(self) -> dict:
        return {"id": self.id, "argv": list(self.argv), "cwd": self.cwd, "outputs": list(self.outputs),
                "inputs": list(self.inputs)}


#: Short output options, which argparse also takes attached to their value (``-oout/a.png``).
_SHORT_OUTPUTS = tuple(o for o in OUTPUT_OPTIONS if len(o) == 2 and o[1] != "-")


def _option_value_pairs(argv):
    """(index, option, value) for ``--opt value``, ``--opt=value`` and, for the short output
    options, the attached ``-oVALUE`` forms."""
    for i, a in enumerate(argv):
        if a.startswith("-") and "=" in a:
            opt, _, val = a.partition("=")
            yield i, opt, val
        elif a[:2] in _SHORT_OUTPUTS and len(a) > 2:  # -oout/k8.png (was not seen as an output)
            yield i, a[:2], a[2:]
        elif a.startswith("-") and i + 1 < len(argv):
            yield i + 1, a, argv[i + 1]


def _infer_outputs(argv) -> tuple:
    return tuple(val for _, opt, val in _option_value_pairs(argv) if _is_output(argv[0], opt, val))


def _on_command_line(argv, value: str) -> bool:
    """Whether ``value`` is one of ``argv``'s tokens or the value of an option (``--x=value``,
    ``-ovalue``): where the staging can redirect it."""
    return value in argv or any(val == value for _, _, val in _option_value_pairs(argv))


def _parse(parser, argv, where: str):
    """``argv`` parsed by ``parser`` (the ``ibr`` command-line parser): a command line the command
    would refuse as a usage error is refused here with the command's own message (a misspelt
    ``--objj out/x.obj`` was reported as "no output found"). None for a ``--help`` line."""
    import io

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            return parser.parse_args(list(argv))
    except SystemExit as exc:
        if not exc.code:
            return None
        lines = [line for line in err.getvalue().splitlines() if line.strip()]
        message = re.sub(r"^[^:]*: error: ", "", lines[-1]) if lines else "the command line does not parse"
        raise ValueError(f"{where}: ibr {argv[0]}: {message}") from None


def _parsed_outputs(parser, args, argv) -> tuple:
    """The values of ``argv``'s output options (:data:`OUTPUT_OPTIONS`) as ``parser`` read them:
    abbreviations (``--ob`` for ``--obj``), ``--opt=value`` and ``-ovalue`` included."""
    sub = next((a.choices.get(argv[0]) for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    if sub is None or args is None:
        return _infer_outputs(argv)
    values = []
    for action in sub._actions:
        options = [o for o in action.option_strings if _is_output(argv[0], o, "")]
        if not options:
            continue
        value = getattr(args, action.dest, None)
        if value is None or value is action.default or isinstance(value, bool):
            continue
        given = value if isinstance(value, (list, tuple)) else [value]
        values += [v for v in given if _is_output(argv[0], options[0], v)]
    # a default output (interpolate's "out") is not on the command line: it cannot be redirected
    return tuple(dict.fromkeys(v for v in values if _on_command_line(argv, v)))


def _job_from(entry, index: int, base: Path, parser=None) -> Job:
    where = f"jobs[{index}]"
    if isinstance(entry, (str, list)):
        entry = {"command": entry} if isinstance(entry, str) else {"argv": entry}
    if not isinstance(entry, dict):
        raise ValueError(f"{where}: expected an object with 'argv' or 'command', got {type(entry).__name__}")
    check_keys(where, entry, ("id", "argv", "command", "outputs", "inputs", "cwd"))
    if ("argv" in entry) == ("command" in entry):
        raise ValueError(f"{where}: give exactly one of 'argv' (a list) and 'command' (a string)")
    if "command" in entry:
        if not isinstance(entry["command"], str):
            raise ValueError(f"{where}: 'command' must be a string, got {entry['command']!r}")
        try:
            argv = shlex.split(entry["command"])
        except ValueError as exc:  # an unclosed quote
            raise ValueError(f"{where}: command: {exc} in {entry['command']!r}") from None
    else:
        argv = entry["argv"]
        if not isinstance(argv, list) or not all(isinstance(a, str) for a in argv):
            raise ValueError(f"{where}: 'argv' must be a list of strings, got {argv!r}")
    argv = list(argv)
    if argv and argv[0] in ("ibr", "ibr.exe"):
        argv = argv[1:]
    if not argv or argv[0].startswith("-"):
        raise ValueError(f"{where}: expected an ibr command line (e.g. 'stereo A.json -o A.png'), got {argv!r}")
    if argv[0] == "batch":
        raise ValueError(f"{where}: a batch job cannot run 'ibr batch'")
    args = _parse(parser, argv, where) if parser is not None else None
    if getattr(args, "serve", False) or (args is None and "--serve" in argv):  # it would run until killed
        raise ValueError(f"{where}: ibr {argv[0]} --serve serves a page until it is stopped, which a batch job cannot "
                         "do; write the page with --site DIR alone")
    outputs = entry.get("outputs")
    if outputs is None:
        outputs = _parsed_outputs(parser, args, argv) if parser is not None else _infer_outputs(argv)
    elif not isinstance(outputs, list) or not all(isinstance(o, str) and o for o in outputs):
        raise ValueError(f"{where}: 'outputs' must be a list of paths, got {outputs!r}")
    outputs = tuple(outputs)
    if not outputs:
        raise ValueError(f"{where}: no output found in {shlex.join(argv)!r}; name it with -o/--out or list the "
                         "command-line values that are outputs in 'outputs'")
    for o in outputs:
        if not _on_command_line(argv, o):
            raise ValueError(f"{where}: output {o!r} does not appear on the command line {shlex.join(argv)!r}")
    inputs = entry.get("inputs", [])
    if not isinstance(inputs, list) or not all(isinstance(i, str) and i for i in inputs):
        raise ValueError(f"{where}: 'inputs' must be a list of paths, got {inputs!r}")
    cwd = entry.get("cwd", ".")
    if not isinstance(cwd, str):
        raise ValueError(f"{where}: 'cwd' must be a folder path, got {cwd!r}")
    cwd = (base / cwd).resolve()
    if not cwd.is_dir():  # (a missing one was created by the staging of the outputs)
        raise ValueError(f"{where}: 'cwd' {cwd} is not an existing folder")
    job_id = entry.get("id")
    if job_id is None:
        digest = hashlib.sha1(json.dumps([argv, str(cwd)]).encode()).hexdigest()[:12]
        job_id = f"{argv[0]}-{digest}"
    if not isinstance(job_id, str) or not _ID.match(job_id):
        raise ValueError(f"{where}: 'id' must be 1-100 letters, digits, '.', '_' or '-' (not first), got {job_id!r}")
    return Job(job_id, tuple(argv), str(cwd), outputs, tuple(inputs))


def load_jobs(path, *, parser=None) -> list[Job]:
    """Read a batch file (module docstring) into jobs; relative paths start at its folder.

    ``parser``: the ``ibr`` command-line parser (``cli.build_parser()``, as ``ibr batch`` passes
    it): every job's command line is parsed first, a usage error refused with the command's own
    message, and the outputs are found as the command reads its options (abbreviated ones too).
    Without it, outputs are the values of :data:`OUTPUT_OPTIONS` spelt out.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        Invalid JSON or schema; duplicate job ids; two jobs writing the same output.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"jobs: {path} does not exist (expected a batch file, JSON)")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"jobs: {path} is not valid JSON ({exc})") from None
    if isinstance(doc, dict):
        check_keys(f"jobs: {path}", doc, ("format", "version", "jobs"), required=("jobs",))
        if doc.get("format") not in (None, BATCH_FORMAT):
            raise ValueError(f"jobs: {path}: 'format' must be {BATCH_FORMAT!r}, got {doc.get('format')!r}")
        if doc.get("version", 1) != 1 or isinstance(doc.get("version"), bool):
            raise ValueError(f"jobs: {path}: 'version' must be 1, got {doc.get('version')!r}")
        entries = doc.get("jobs")
    else:
        entries = doc
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"jobs: {path}: expected a non-empty list of jobs (or an object with 'jobs'), got {entries!r}")
    base = path.resolve().parent
    jobs = [_job_from(e, i, base, parser) for i, e in enumerate(entries)]
    seen_ids, seen_out = {}, {}
    for i, j in enumerate(jobs):
        if j.id in seen_ids:
            raise ValueError(f"jobs[{i}]: id {j.id!r} is also the id of jobs[{seen_ids[j.id]}]")
        seen_ids[j.id] = i
        for o in j.outputs:
            key = os.path.normpath(os.path.join(j.cwd, o))
            if key in seen_out:
                raise ValueError(f"jobs[{i}]: output {o!r} is also an output of jobs[{seen_out[key]}]")
            seen_out[key] = i
    return jobs


# --------------------------------------------------------------------------- checksums
def file_sha256(path) -> str:
    """SHA-256 hex digest of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _input_files(job: Job, *, strict: bool = True) -> list[Path]:
    """Every input file of ``job`` (sorted): the command line's non-output values that exist,
    what they name (:func:`ibr.sequence.referenced_files`), and ``inputs`` (``strict``: a missing
    declared input raises)."""
    cwd = Path(job.cwd)
    outs = set(job.outputs)
    names = [v for v in job.argv[1:] if v not in outs and not v.startswith("-")]
    names += [val for _, _, val in _option_value_pairs(job.argv) if val not in outs]
    names += list(job.inputs)
    files: set[Path] = set()
    for n in names:
        p = cwd / n
        if p.exists():
            files.update(referenced_files(p))
    for n in job.inputs:
        if strict and not (cwd / n).exists():
            raise FileNotFoundError(f"job {job.id}: input {n!r} does not exist in {cwd}")
    return sorted(files)


def _check_not_inputs(job: Job, finals, inputs) -> None:
    """Refuse (ValueError) when a file about to be written, ``finals``, is an input of the job
    (``inputs``), after resolving links: the command run alone refuses that itself, but in a
    batch it writes into a staging folder and cannot see it (#12, no data loss)."""
    real = {os.path.realpath(p): p for p in inputs}
    for f in finals:
        hit = real.get(os.path.realpath(f))
        if hit is not None:
            raise ValueError(f"job {job.id}: output {os.path.relpath(f, job.cwd)!r} is an input of the job "
                             f"({os.path.relpath(hit, job.cwd)}); refusing to overwrite it")


def check_batch_files(jobs, jobs_path, records, report) -> None:
    """Refuse (ValueError, before any job runs) a batch ``report`` file or a job record
    (``records/<id>.json``) that would replace the batch file itself or an input or output of a
    job (``--report jobs.json`` replaced the job file; ``--records .`` with a job ``room_a``
    wrote a record over the view file room_a.json). Paths are compared after resolving links,
    one set lookup each; a job whose declared input is missing is left to fail on its own."""
    files = {os.path.realpath(jobs_path): "the batch file"}
    for job in jobs:
        # a missing declared input fails its job later; every input that exists is protected here
        for f in _input_files(job, strict=False):
            files.setdefault(os.path.realpath(f), f"an input of job {job.id}")
        for o in job.outputs:
            files.setdefault(os.path.realpath(Path(job.cwd) / o), f"an output of job {job.id}")
    inodes = {}  # hard links (and case-insensitive volumes): the same file under another name
    for f, what in files.items():
        with contextlib.suppress(OSError):
            st = os.stat(f)
            inodes.setdefault((st.st_dev, st.st_ino), what)
    records = Path(records)
    if records.exists() and not records.is_dir():
        raise NotADirectoryError(f"--records: {records} is a file, expected a folder for the job records")
    written = [("--report", Path(report))] + [("--records", _record_path(records, job)) for job in jobs]
    for option, path in written:
        what = files.get(os.path.realpath(path))
        if what is None:
            with contextlib.suppress(OSError):
                st = os.stat(path)
                what = inodes.get((st.st_dev, st.st_ino))
        if what is not None:
            raise ValueError(f"{option}: {path} is {what}; choose another "
                             f"{'report file' if option == '--report' else 'records folder'}")

# --------------------------------------------------------------------------- records
def _record_path(records: Path, job: Job) -> Path:
    return records / f"{job.id}.json"


def _read_record(path: Path):
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return doc if isinstance(doc, dict) and doc.get("format") == RECORD_FORMAT else None


def _up_to_date(record, job: Job, inputs: dict) -> bool:
    # The working folder itself is not compared: a batch folder moved or copied elsewhere with its
    # records keeps its finished jobs (inputs and outputs are compared by content, relative to it).
    if record is None or record.get("argv") != list(job.argv):
        return False
    if record.get("inputs") != inputs:
        return False
    outs = record.get("outputs")
    if not isinstance(outs, dict) or not outs:
        return False
    cwd = Path(job.cwd)
    for rel, digest in outs.items():
        p = cwd / rel
        if not p.is_file() or file_sha256(p) != digest:
            return False
    return True


def _log_commit_once(records: Path, line: dict) -> None:
    """Append ``line`` to ``commits.log`` unless it is there: the commit of an attempt whose worker
    died after writing the job's record (the commit itself, atomic) and before its log line."""
    try:
        logged = (records / "commits.log").read_text(encoding="utf-8").splitlines()
    except OSError:
        logged = []
    if not any(_json_line(x) == line for x in logged):
        _append_log(records, line)


def _json_line(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return None


def _append_log(records: Path, line: dict) -> None:
    data = (json.dumps(line, sort_keys=True) + "\n").encode()
    fd = os.open(records / "commits.log", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.write(fd, data)  # one small O_APPEND write: lines of concurrent commits never interleave
    finally:
        os.close(fd)


# --------------------------------------------------------------------------- staging
def _stage_root(final: Path) -> Path:
    """The folder that receives ``final``'s staging folder: its parent, or when that does not
    exist (or is a file) the nearest existing folder above it. Nothing is created: the staged
    path keeps the missing folders (``.ibr-batch-…/nodir/x.obj``), so the command meets them as
    it would run alone and refuses a missing output folder with its own message."""
    p = final.parent
    while not p.is_dir() and p.parent != p:
        p = p.parent
    return p


def _stage_argv(job: Job, token: str) -> tuple[list[str], list[Path], dict[Path, Path]]:
    """The command line with every output redirected into a staging folder beside it (or beside
    its nearest existing ancestor, :func:`_stage_root`).

    Returns (argv, staging folders, {staged output path: final output path}).
    """
    cwd = Path(job.cwd)
    stages: dict[Path, Path] = {}
    mapping: dict[str, str] = {}
    staged_to_final: dict[Path, Path] = {}
    try:
        for o in job.outputs:
            final = Path(os.path.normpath(cwd / o))
            root = _stage_root(final)
            stage = stages.setdefault(root, root / f"{STAGE_PREFIX}{job.id}-{token}")
            stage.mkdir(exist_ok=True)
            staged = stage / final.relative_to(root)
            mapping[o] = str(staged)
            staged_to_final[staged] = final
    except OSError:  # (a folder that cannot be written): its staging folders so far go again
        for stage in stages.values():
            shutil.rmtree(stage, ignore_errors=True)
        raise
    argv = []
    for a in job.argv:
        if a.startswith("-") and "=" in a:
            opt, _, val = a.partition("=")
            argv.append(f"{opt}={mapping[val]}" if val in mapping else a)
        elif a not in mapping and a.startswith("-") and not a.startswith("--") and a[2:] in mapping:
            argv.append(a[:2] + mapping[a[2:]])  # -oout/k8.png
        else:
            argv.append(mapping.get(a, a))
    return argv, list(stages.values()), staged_to_final


def _user_paths(job: Job, stages: list[Path], staged_to_final: dict[Path, Path]):
    """(text, replacement) pairs, longest first, that turn the staged and absolute paths a command
    printed back into the paths as the job wrote them (``-o: out/m1.txt …``, not the hidden
    ``/…/out/.ibr-batch-<id>-<token>/m1.txt``)."""
    cwd = Path(job.cwd)
    user = {os.path.normpath(cwd / o): o for o in job.outputs}
    pairs: dict[str, str] = {}
    for staged, final in staged_to_final.items():
        o = user.get(str(final), str(final))
        for form in {str(staged), os.path.realpath(staged)}:
            pairs[form] = o
        for form in {str(final), os.path.realpath(final)}:
            pairs.setdefault(form, o)
    absolute = any(os.path.isabs(o) for o in job.outputs)
    for stage in stages:
        root = stage.parent
        shown = str(root) if absolute else os.path.relpath(root, cwd)
        for form in {str(stage), os.path.realpath(stage)}:
            pairs[form + os.sep] = "" if shown == "." else shown + os.sep
            pairs[form] = shown
    return sorted(pairs.items(), key=lambda kv: -len(kv[0]))


def _as_user_wrote(text: str, pairs) -> str:
    for old, new in pairs:
        text = text.replace(old, new)
    return text


def _remove_stale_stages(job: Job) -> int:
    """Remove staging folders of earlier, interrupted attempts of this job; return how many. They
    are beside each output or above it (:func:`_stage_root`): every existing folder from the
    output's parent up to the job's folder (or, outside it, up to the first existing one)."""
    cwd = Path(job.cwd)
    n = 0
    prefix = f"{STAGE_PREFIX}{job.id}-"
    folders = set()
    for o in job.outputs:
        p = Path(os.path.normpath(cwd / o)).parent
        while True:
            if p.is_dir():
                folders.add(p)
                if p == cwd or cwd not in p.parents:
                    break
            if p.parent == p:
                break
            p = p.parent
    for parent in folders:
        with contextlib.suppress(OSError):
            for entry in os.scandir(parent):
                if entry.name.startswith(prefix) and entry.is_dir(follow_symlinks=False):
                    shutil.rmtree(entry.path, ignore_errors=True)
                    n += 1
    return n


def _commit(stages: list[Path]) -> list[Path]:
    """Rename every staged file into the stage's parent folder at the same relative path (each
    rename atomic; an output folder gets the new files, other files in it are left alone).
    Returns the final files."""
    moves = [(src, stage.parent / src.relative_to(stage)) for stage in stages
             for src in sorted(p for p in stage.rglob("*") if p.is_file())]
    for _, final in moves:  # nothing is moved unless every file can be (an output that is an
        if final.is_dir():  # existing folder failed half way, after the others were replaced)
            raise IsADirectoryError(f"output {final} is an existing folder, expected a file name")
        for up in final.parents:
            if up.exists() and not up.is_dir():
                raise NotADirectoryError(f"output {final}: {up} is a file, expected a folder")
    finals: list[Path] = []
    for src, final in moves:
        final.parent.mkdir(parents=True, exist_ok=True)
        os.replace(src, final)
        finals.append(final)
    for stage in stages:
        shutil.rmtree(stage, ignore_errors=True)
    return finals


def _tail(text: str, lines: int = 6) -> str:
    return "\n".join(text.strip().splitlines()[-lines:])


def run_job(job: Job | dict, run_id: str, records, *, threads_per_job: int = 1, timeout: float | None = None) -> dict:
    """Run one job idempotently (module docstring); never raises for a failing command.

    Parameters
    ----------
    job : Job or dict
        The job (a dict as :meth:`Job.to_dict` gives, for workers that receive plain data).
    run_id : str
        Identifier of the batch run; a record already committed by this run (an attempt whose
        worker died after committing) counts as done, not as skipped.
    records : str or Path
        Records folder (shared by all workers).
    threads_per_job : int
        Threads each job's process may use (:data:`THREAD_ENV`).
    timeout : float, optional
        Seconds before the job's process is killed (the job then fails).

    Returns
    -------
    dict
        ``id``, ``status`` (``"done"``, ``"skipped"`` or ``"failed"``), ``seconds``, ``worker``
        (host:pid), ``returncode``, ``error`` (last lines of the command's stderr or the
        exception), ``outputs`` (files written), ``interrupted_attempts`` (staging folders of
        earlier attempts removed), ``recovered`` (committed by an earlier attempt of this run).
    """
    if isinstance(job, dict):
        job = Job(job["id"], tuple(job["argv"]), job["cwd"], tuple(job["outputs"]), tuple(job.get("inputs", ())))
    records = Path(records)
    start = time.perf_counter()
    result = {"id": job.id, "argv": list(job.argv), "status": "failed", "seconds": 0.0,
              "worker": f"{socket.gethostname()}:{os.getpid()}", "returncode": None, "error": "",
              "outputs": [], "interrupted_attempts": 0, "recovered": False}
    try:
        records.mkdir(parents=True, exist_ok=True)
        result["interrupted_attempts"] = _remove_stale_stages(job)
        input_files = _input_files(job)
        cwd = Path(job.cwd)
        _check_not_inputs(job, [cwd / o for o in job.outputs], input_files)
        inputs = {os.path.relpath(p, cwd): file_sha256(p) for p in input_files}
        record = _read_record(_record_path(records, job))
        if _up_to_date(record, job, inputs):
            result["status"] = "done" if record.get("run") == run_id else "skipped"
            result["recovered"] = record.get("run") == run_id
            result["outputs"] = sorted(record["outputs"])
            if result["recovered"]:  # a worker killed between its record and its log line: the line
                _log_commit_once(records, {"id": job.id, "run": run_id, "attempt": record.get("attempt")})
            return result
        token = uuid.uuid4().hex[:12]
        argv, stages, staged_to_final = _stage_argv(job, token)
        env = dict(os.environ)
        # the command checks the final paths too (its own inputs, e.g. the images a transforms.json
        # names, are known only to it): run alone it refuses what it must not write over
        env[BATCH_FINALS_ENV] = json.dumps({os.path.abspath(k): os.path.abspath(v) for k, v in staged_to_final.items()})
        for var in THREAD_ENV:
            env[var] = str(threads_per_job)
        try:
            proc = subprocess.run([sys.executable, "-c", _BOOTSTRAP, *argv], cwd=job.cwd, env=env,
                                  stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            for s in stages:
                shutil.rmtree(s, ignore_errors=True)
            result["error"] = f"timed out after {timeout} s"
            return result
        result["returncode"] = proc.returncode
        if proc.returncode != 0:
            for s in stages:
                shutil.rmtree(s, ignore_errors=True)
            result["error"] = _as_user_wrote(_tail(proc.stderr), _user_paths(job, stages, staged_to_final)) \
                or f"exit code {proc.returncode}"
            return result
        staged = [p for s in stages for p in s.rglob("*") if p.is_file()]
        if not staged:
            for s in stages:
                shutil.rmtree(s, ignore_errors=True)
            result["error"] = f"the command succeeded but wrote none of its outputs {list(job.outputs)}"
            return result
        try:  # an output folder's files too (the command named only the folder)
            _check_not_inputs(job, [s.parent / p.relative_to(s) for s in stages for p in s.rglob("*") if p.is_file()],
                              input_files)
        except ValueError:
            for s in stages:
                shutil.rmtree(s, ignore_errors=True)
            raise
        try:
            finals = _commit(stages)
        except OSError:
            for s in stages:
                shutil.rmtree(s, ignore_errors=True)
            raise
        outputs = {os.path.relpath(p, cwd): file_sha256(p) for p in finals}
        doc = {"format": RECORD_FORMAT, "version": 1, "id": job.id, "argv": list(job.argv), "cwd": job.cwd,
               "inputs": inputs, "outputs": outputs, "run": run_id, "attempt": token, "worker": result["worker"],
               "seconds": round(time.perf_counter() - start, 4),
               "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        with atomic_path(_record_path(records, job)) as tmp:
            tmp.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        _append_log(records, {"id": job.id, "run": run_id, "attempt": token})
        result["status"] = "done"
        result["outputs"] = sorted(outputs)
        return result
    except Exception as exc:  # noqa: BLE001 - a job's failure is reported, never raised
        result["error"] = f"{type(exc).__name__}: {exc}"
        return result
    finally:
        result["seconds"] = round(time.perf_counter() - start, 4)
