"""One output plan per command: every output checked before work, staged, renamed together.

A command (or any batch job) that writes files builds one :class:`OutputPlan`. It names its
inputs and its outputs up front; :meth:`OutputPlan.check` refuses the whole run **before any work**
if an output could lose a user's file or fail late; the work then writes every output to a
staged (temporary) path; :meth:`OutputPlan.commit` renames all staged files into place together
at the very end. Leaving the ``with`` block without ``commit()`` -- an exception, Ctrl-C, or
SIGTERM (turned into ``KeyboardInterrupt`` while the plan is active) -- removes everything that
was staged, so a failed or interrupted command leaves no partial file and touches no existing one.

How a command uses it
---------------------
::

    from ibr.io.outputs import DEPTH_EXTS, IMAGE_EXTS, OutputPlan

    with OutputPlan("ibr warp", log=info) as plan:
        plan.add_view_input("VIEW", args.view)       # the JSON *and* the colour/depth files it names
        plan.add_view_input("--to", args.to)         # a bare camera JSON is fine too
        out = plan.add_file("-o", args.output, IMAGE_EXTS)
        dep = plan.add_file("--depth-out", args.depth_out, DEPTH_EXTS)   # None if not given
        frames = plan.add_folder("--out", args.out, patterns=("frame_#.png",))
        plan.check()                                 # raises before any work
        ...                                          # load, compute
        write_image(plan.stage(out), color)          # any writer, given the staged path
        write_image(plan.stage(frames, "frame_000.png"), f0)
        plan.commit()                                # all renames, then the old frames go

What :meth:`~OutputPlan.check` refuses (each message names the option and the user's path)
-------------------------------------------------------------------------------------------
* an extension the output cannot be written as (``ValueError``; no extension, ``.bmp``, ``.gif`` ...);
* a file output that is an existing folder (``IsADirectoryError``), a folder output that is an
  existing file (``NotADirectoryError``), a file whose folder does not exist
  (``FileNotFoundError``; unless that folder is a new frame folder of the same plan: the file is
  staged in it and appears with it), a folder that cannot be written (``PermissionError``: the
  plan creates its staging folder there, which proves it can);
* an output equal -- after resolving symbolic links, or as the same inode (hard links) -- to any
  input, including the colour and depth files a view file names (``ValueError``);
* two outputs on the same path (``ValueError``);
* a frame folder holding an *input* among the files of its own naming pattern (``ValueError``).

Frame folders
-------------
:meth:`~OutputPlan.add_folder` declares a folder of files named by ``patterns`` (globs; ``#`` is one
or more digits, so ``frame_#.png`` never takes a user's ``frame_notes.png``). The folder
is either new (created at commit, staged as a whole and renamed into place) or existing: then
commit moves the new files in and removes the files of the *same patterns* left by an earlier run
(and only those), logging how many it removed. Other files in the folder are never touched.

Staging
-------
Staged files live in one hidden folder per destination folder, ``.ibr-staging-<pid>-<random>/``,
keeping their final names (so writers that pick the format by extension, or write companion
files such as an OBJ's ``.mtl`` beside it, work unchanged). A process killed with SIGKILL can
leave only such a hidden folder behind; the next plan writing into that folder removes staging
folders whose process is gone.
"""

from __future__ import annotations

import contextlib
import fnmatch
import functools
import os
import re
import shutil
import signal
import tempfile
import threading
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable

__all__ = [
    "ANIMATION_EXTS",
    "DEPTH_EXTS",
    "IMAGE_EXTS",
    "JSON_EXTS",
    "OutputPlan",
    "STAGING_PREFIX",
    "VIDEO_EXTS",
    "same_file",
    "matches_patterns",
    "number_width",
]

#: Extensions :func:`ibr.io.write_image` writes (the dtype rules are checked by the writer).
IMAGE_EXTS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".pfm")
#: Extensions :func:`ibr.io.write_depth` writes (``.png`` = 16-bit codes with a scale).
DEPTH_EXTS = (".exr", ".tif", ".tiff", ".pfm", ".png")
#: Containers OpenCV's ``VideoWriter`` writes here (mp4v for mp4/m4v/mov, MJPG for avi).
VIDEO_EXTS = (".mp4", ".m4v", ".mov", ".avi")
#: Tours: a GIF or a video.
ANIMATION_EXTS = (".gif",) + VIDEO_EXTS
JSON_EXTS = (".json",)

STAGING_PREFIX = ".ibr-staging-"


def number_width(count: int, at_least: int = 4) -> int:
    """Digits of the numbers 0 .. ``count`` - 1 in file names, zero-padded so that the names sort
    in number order (``frame_0999``, ``frame_1000``; 1001 frames at 3 digits put
    ``frame_1000_...`` before ``frame_100_...``): the width of ``count - 1``, at least
    ``at_least``. Readers take any width (``#`` in :func:`matches_patterns`, ``\\d+``)."""
    return max(int(at_least), len(str(max(int(count) - 1, 0))))


def _abs(path: Path) -> Path:
    return Path(os.path.abspath(path))


#: Environment variable through which ``ibr batch`` tells a command the final path of each output
#: it redirected into a staging folder (JSON: {absolute staged path: final path}).
BATCH_FINALS_ENV = "IBR_BATCH_FINALS"


def _batch_finals() -> dict:
    import json

    text = os.environ.get(BATCH_FINALS_ENV)
    if not text:
        return {}
    try:
        finals = json.loads(text)
    except ValueError:
        return {}
    return finals if isinstance(finals, dict) else {}


def same_file(a, b) -> bool:
    """True when paths ``a`` and ``b`` name the same file: equal after resolving symbolic links,
    or (both existing) the same inode, which catches hard links and case-insensitive folders."""
    a, b = Path(a), Path(b)
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _remove_stale_staging(folder: Path) -> None:
    """Remove ``.ibr-staging-<pid>-*`` folders in ``folder`` whose process no longer runs."""
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            if not (entry.name.startswith(STAGING_PREFIX) and entry.is_dir(follow_symlinks=False)):
                continue
            pid = entry.name[len(STAGING_PREFIX):].split("-", 1)[0]
            if pid.isdigit() and int(pid) != os.getpid() and not _pid_alive(int(pid)):
                shutil.rmtree(entry.path, ignore_errors=True)



@functools.lru_cache(maxsize=256)
def _pattern_regex(pattern: str) -> re.Pattern:
    return re.compile(fnmatch.translate(pattern).replace(re.escape("#"), "[0-9]+"))


def matches_patterns(name: str, patterns) -> bool:
    """Whether the file name ``name`` follows one of ``patterns``: globs (``*``, ``?``, ``[...]``,
    case-sensitive) in which ``#`` stands for one or more digits. ``frame_#.png`` takes
    ``frame_0007.png`` but not ``frame_notes.png`` or ``frame_2024_poster.png``, which ``frame_*.png``
    took (and a command removed as an earlier run's frame)."""
    return any(_pattern_regex(p).match(name) for p in patterns)

@dataclass
class _Output:
    option: str
    path: Path                      # as given by the user
    folder: bool                    # a frame folder (True) or one file
    exts: tuple[str, ...] | None = None
    patterns: tuple[str, ...] = ()
    staged: Path | None = None      # staged file, or staged folder for a frame folder
    names: list[str] = field(default_factory=list)   # files staged into a frame folder
    create: bool = False            # the frame folder does not exist yet
    anchor: Path | None = None      # nearest existing ancestor of a new frame folder
    inside: "_Output | None" = None  # a file output in a frame folder this plan creates


class OutputPlan:
    """Inputs and outputs of one command; see the module docstring for the protocol.

    Parameters
    ----------
    command : str
        Name used in log lines (e.g. ``"ibr interpolate"``).
    log : callable, optional
        Called with one line per notable action (old frames removed). Default: silent.
    """

    def __init__(self, command: str = "ibr", *, log: Callable[[str], None] | None = None):
        self.command = command
        self.log = log or (lambda message: None)
        self.inputs: list[tuple[str, Path]] = []
        self.outputs: list[_Output] = []
        self._staging: dict = {}        # destination folder (abs), or (folder, id) for a frame folder -> staging
        self._checked = False
        self._done = False
        self._old_sigterm = None
        self._poseless: list[Path] = []  # view / camera files without world_from_cam (noted at check)

    # ----------------------------------------------------------------- declaring
    def add_input(self, what: str, path) -> Path | None:
        """Record an input file or folder (``None`` is ignored). Missing inputs are the loader's
        business; the plan only makes sure no output lands on one."""
        if path is None:
            return None
        p = Path(path)
        self.inputs.append((what, p))
        if p.is_dir():  # a folder input (e.g. cube face files): every file directly in it
            with contextlib.suppress(OSError):
                for child in sorted(p.iterdir()):
                    if child.is_file():
                        self.inputs.append((f"{what} ({child.name})", child))
        return p

    def add_view_input(self, what: str, path) -> Path | None:
        """Record a view file (or bare camera JSON) and the colour and depth files it names.

        The JSON is only peeked at here (``color`` and ``depth.path``, relative to the file);
        :func:`ibr.io.load_view` does the validation and reports a broken file. A camera without
        ``world_from_cam`` (valid: the identity pose) is logged as a note by :meth:`check`.
        """
        p = self.add_input(what, path)
        if p is None:
            return None
        import json

        try:
            doc = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError):
            return p
        if not isinstance(doc, dict):
            return p
        from .view_files import camera_without_pose, named_files

        for key, file in named_files(p, doc):
            self.add_input(f"{what} {key}", file)
        if camera_without_pose(doc) and not any(same_file(p, q) for q in self._poseless):
            self._poseless.append(p)
        return p

    def add_file(self, option: str, path, exts: Iterable[str] | None = None) -> Path | None:
        """Declare one output file (``None``: the option was not given; returns ``None``).

        ``exts`` lists the allowed extensions (lower case, with the dot); ``None`` allows any.
        Returns the path as given; pass it to :meth:`stage` to get where to write it.
        """
        if path is None:
            return None
        if self._checked:
            raise RuntimeError("OutputPlan: declare every output before check()")
        p = Path(path)
        self.outputs.append(_Output(option, p, False, None if exts is None else tuple(exts)))
        return p

    def add_folder(self, option: str, path, patterns: Iterable[str]) -> Path | None:
        """Declare a frame folder whose files follow ``patterns`` (globs in which ``#`` stands for
        one or more digits, such as ``frame_#.png``: :func:`matches_patterns`).

        Existing files of these patterns are an earlier run's and are removed at commit; no
        other file of the folder is touched. Returns the folder path as given.
        """
        if path is None:
            return None
        if self._checked:
            raise RuntimeError("OutputPlan: declare every output before check()")
        patterns = tuple(patterns)
        if not patterns:
            raise ValueError("patterns: a frame folder needs at least one file-name pattern")
        p = Path(path)
        self.outputs.append(_Output(option, p, True, None, patterns))
        return p

    # ----------------------------------------------------------------- checking
    def _find(self, path) -> _Output:
        key = _abs(Path(path))
        for o in self.outputs:
            if _abs(o.path) == key:
                return o
        raise KeyError(f"OutputPlan: {path} was not declared as an output")

    def _check_input_clash(self, o: _Output, target: Path) -> None:
        for what, p in self.inputs:
            if same_file(target, p):
                where = "" if _abs(target) == _abs(o.path) else f" (its file {target.name})"
                raise ValueError(f"{o.option}: {o.path}{where} is the input {what} ({p}); "
                                 "refusing to overwrite an input -- choose another output path")

    def _check_file(self, o: _Output) -> None:
        p = o.path
        if o.exts is not None and p.suffix.lower() not in o.exts:
            got = "has no extension" if not p.suffix else f"has the extension {p.suffix!r}"
            raise ValueError(f"{o.option}: {p} {got}; expected one of {', '.join(o.exts)}")
        if p.is_dir():
            raise IsADirectoryError(f"{o.option}: {p} is a folder, expected a file name")
        folder = p.parent
        o.inside = None
        if not folder.is_dir():
            # a file in a frame folder the plan creates (--contact-sheet OUT/sheet.png with --out OUT)
            o.inside = next((f for f in self.outputs if f.folder and not folder.exists()
                             and os.path.realpath(f.path) == os.path.realpath(folder)), None)
            if o.inside is None:
                raise FileNotFoundError(f"{o.option}: the output folder {folder} of {p} does not exist")
        self._check_input_clash(o, p)

    def _check_folder(self, o: _Output) -> None:
        p = o.path
        if p.is_symlink() and not p.exists():  # it would be created at the link, after the work
            raise FileNotFoundError(f"{o.option}: {p} is a symbolic link to {os.readlink(p)}, which does not "
                                    "exist; create that folder or choose another")
        if p.exists() and not p.is_dir():
            raise NotADirectoryError(f"{o.option}: {p} exists and is not a folder")
        if not p.exists() and p.suffix.lower() in IMAGE_EXTS + ANIMATION_EXTS + JSON_EXTS:  # would become a folder
            shown = ", ".join(o.patterns[:3]) + (", ..." if len(o.patterns) > 3 else "")
            raise ValueError(f"{o.option}: {p} is named like a file, but this output is a folder (of {shown}); "
                             "give a name without a file extension")
        self._check_folder_inputs(o)
        if p.is_dir():
            o.create = False
            taken = [e for e in p.iterdir() if e.is_dir() and matches_patterns(e.name, o.patterns)]
            if taken:  # a frame would be written onto a folder (IsADirectoryError after the work)
                raise IsADirectoryError(f"{o.option}: {taken[0]} is a folder where an output file goes; rename it "
                                        f"or choose another {o.option}")
        else:
            anchor = _abs(p).parent
            while not anchor.exists():
                anchor = anchor.parent
            if not anchor.is_dir():
                raise NotADirectoryError(f"{o.option}: {anchor} (on the way to {p}) is not a folder")
            o.create, o.anchor = True, anchor

    def _check_folder_inputs(self, o: _Output) -> None:
        """Frame folder ``o`` is no input, and none of its own files (an earlier run's, replaced
        at commit) is one."""
        p = o.path
        for what, i in self.inputs:
            if same_file(p, i):
                raise ValueError(f"{o.option}: {p} is the input {what}; choose another output folder")
        if p.is_dir():
            for name in self._own_files(o):
                self._check_input_clash(o, p / name)

    def _check_batch_final(self, o: _Output) -> None:
        """Under ``ibr batch`` the command writes into a staging folder (:mod:`ibr.sequence.jobs`):
        check the path the output will be renamed to (:data:`BATCH_FINALS_ENV`) as well, against
        the inputs and for a file output against an existing folder, as a run alone would."""
        final = _batch_finals().get(str(_abs(o.path)))
        if final is None:
            return
        final = Path(final)
        if o.folder:
            self._check_folder_inputs(replace(o, path=final))
        else:
            if final.is_dir():
                raise IsADirectoryError(f"{o.option}: {final} is a folder, expected a file name")
            self._check_input_clash(replace(o, path=final), final)

    def _own_files(self, o: _Output) -> list[str]:
        """Names of the existing files in frame folder ``o`` that match its patterns."""
        try:
            names = sorted(e.name for e in os.scandir(o.path) if e.is_file(follow_symlinks=False)
                           or e.is_symlink())
        except OSError:
            return []
        return [n for n in names if matches_patterns(n, o.patterns)]

    def check(self) -> "OutputPlan":
        """Check every declared output and create the staging folders; raise before any work.

        Raises ``ValueError`` (bad extension, an output equal to an input or to another output),
        ``FileNotFoundError`` (missing folder), ``IsADirectoryError``/``NotADirectoryError``,
        ``PermissionError`` (folder not writable). Returns the plan.
        """
        seen: dict[str, _Output] = {}
        for o in self.outputs:
            (self._check_folder if o.folder else self._check_file)(o)
            self._check_batch_final(o)
            key = os.path.realpath(o.path)
            if key in seen:
                raise ValueError(f"{o.option}: {o.path} is also the output of {seen[key].option}; "
                                 "give each output its own path")
            seen[key] = o
        for f in (o for o in self.outputs if o.folder):  # a file among a frame folder's own names
            for o in self.outputs:
                if not o.folder and same_file(_abs(o.path).parent, f.path) and matches_patterns(o.path.name, f.patterns):
                    raise ValueError(f"{o.option}: {o.path} is named like a frame of {f.option} "
                                     f"({', '.join(f.patterns)}) in the same folder; choose another name")
        for o in self.outputs:
            if o.folder:  # a frame folder gets a staging folder of its own
                o.staged = self._staging_for(o, o.anchor if o.create else _abs(o.path), own=True)
        for o in self.outputs:
            if o.folder:
                continue
            if o.inside is not None:  # staged in the new folder's staging folder, renamed with it
                o.staged = o.inside.staged / o.path.name
            else:
                o.staged = self._staging_for(o, _abs(o.path).parent) / o.path.name
        self._checked = True
        self._note_poseless()
        return self

    def _note_poseless(self) -> None:
        """Log that the view / camera inputs without ``world_from_cam`` have the identity pose (one
        line per file, or one line for more than three)."""
        from .view_files import NO_POSE_NOTE

        files = self._poseless
        if len(files) > 3:
            names = ", ".join(str(p) for p in files[:2])
            self.log(NO_POSE_NOTE.format(path=f"{len(files)} view files ({names}, ...)").replace(" has ", " have ", 1)
                     .replace("camera at", "each camera at", 1))
        else:
            for p in files:
                self.log(NO_POSE_NOTE.format(path=p))

    def _staging_for(self, o: _Output, folder: Path, *, own: bool = False) -> Path:
        folder = Path(os.path.realpath(folder))
        key = (folder, id(o)) if own else folder
        if key not in self._staging:
            _remove_stale_staging(folder)
            try:
                self._staging[key] = Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-",
                                                           dir=folder))
            except OSError as exc:
                raise PermissionError(f"{o.option}: cannot write into the folder {folder} of {o.path} "
                                      f"({exc.strerror or exc})") from None
        return self._staging[key]

    # ----------------------------------------------------------------- writing
    def stage(self, output, name: str | None = None) -> Path:
        """The staged path to write output ``output`` to (a path returned by :meth:`add_file`), or
        file ``name`` of frame folder ``output`` (``name`` must match the folder's patterns), or,
        without ``name``, the staged frame folder itself (for writers that fill a folder; every
        file they leave there must match the patterns)."""
        if not self._checked:
            raise RuntimeError("OutputPlan: call check() before staging outputs")
        o = self._find(output)
        if not o.folder:
            if name is not None:
                raise ValueError(f"name: {o.option} is one file, not a folder")
            return o.staged
        if name is None:
            return o.staged
        if Path(name).name != name:
            raise ValueError(f"name: expected a plain file name inside {o.option}, got {name!r}")
        if not matches_patterns(name, o.patterns):
            raise ValueError(f"name: {name!r} does not follow the patterns {', '.join(o.patterns)} "
                             f"of {o.option}")
        if name not in o.names:
            o.names.append(name)
        return o.staged / name

    def user_path(self, staged) -> Path | None:
        """The user's path of a staged path (for messages), or None."""
        s = _abs(Path(staged))
        for o in self.outputs:
            if o.staged is None:
                continue
            if not o.folder and s == _abs(o.staged):
                return o.path
            if o.folder and s.parent == _abs(o.staged):
                return o.path / s.name
        return None

    # ----------------------------------------------------------------- commit / discard
    def commit(self) -> list[Path]:
        """Rename every staged output into place, then remove a frame folder's old own-pattern
        files; return the final paths. If a rename fails, the files already replaced are
        restored from the backups taken just before (best effort) and the error is raised."""
        if not self._checked:
            raise RuntimeError("OutputPlan: call check() before commit()")
        if self._done:
            raise RuntimeError("OutputPlan: already committed or discarded")
        moves: list[tuple[Path, Path, Path]] = []        # (staged, final, staging folder)
        new_folders: list[_Output] = []
        for o in self.outputs:
            if not o.folder:
                if not o.staged.is_file():
                    raise OSError(f"{o.option}: {o.path}: nothing was written")
                if o.inside is None:  # (a file inside a new frame folder comes with the folder)
                    moves.append((o.staged, o.path, o.staged.parent))
                continue
            guests = {f.path.name for f in self.outputs if f.inside is o}
            o.names = sorted(e.name for e in os.scandir(o.staged))
            odd = [n for n in o.names if not matches_patterns(n, o.patterns) and n not in guests]
            if odd:
                raise ValueError(f"{o.option}: files {', '.join(odd)} do not follow the patterns "
                                 f"{', '.join(o.patterns)} of the frame folder")
            if o.create:
                new_folders.append(o)
            else:
                moves += [(o.staged / n, o.path / n, o.staged) for n in o.names]
        backups: list[tuple[Path, Path]] = []
        links: list[tuple[str, Path]] = []  # output paths that were symbolic links: (target, path)
        done: list[Path] = []
        try:
            for i, (src, dst, stage) in enumerate(moves):
                if dst.is_symlink():  # replaced by the new file; put back as it was on failure
                    links.append((os.readlink(dst), dst))
                elif dst.exists():
                    backup = stage / f".backup-{i}"
                    try:  # the old file, to put back if a later rename fails
                        os.link(dst, backup)
                    except OSError:  # no hard links here (some file systems): a copy; if that fails
                        shutil.copy2(dst, backup)  # too, nothing has been replaced yet: roll back
                    backups.append((backup, dst))
                    with contextlib.suppress(OSError):
                        os.chmod(src, dst.stat().st_mode & 0o7777)
                os.replace(src, dst)
                done.append(dst)
            for o in new_folders:
                o.path.parent.mkdir(parents=True, exist_ok=True)
                if o.path.exists():  # appeared meanwhile: move the files one by one
                    for n in o.names:
                        os.replace(o.staged / n, o.path / n)
                else:
                    os.chmod(o.staged, 0o777 & ~_umask())  # mkdtemp made it private
                    os.rename(o.staged, o.path)
                done.append(o.path)
        except BaseException:
            restored = {dst for _, dst in backups} | {dst for _, dst in links}
            for backup, dst in backups:
                with contextlib.suppress(OSError):
                    os.replace(backup, dst)
            for target, dst in links:
                if dst in done:
                    with contextlib.suppress(OSError):
                        dst.unlink()
                        os.symlink(target, dst)
            for dst in done:
                if dst not in restored and dst.is_file():
                    with contextlib.suppress(OSError):
                        dst.unlink()
            self.discard()
            raise
        for o in self.outputs:
            if o.folder and not o.create:
                stale = [n for n in self._own_files(o) if n not in o.names]
                for n in stale:
                    with contextlib.suppress(FileNotFoundError):
                        (o.path / n).unlink()
                if stale:
                    self.log(f"{self.command}: removed {len(stale)} file(s) of an earlier run from {o.path}/ "
                             f"({', '.join(o.patterns)}; other files untouched)")
        self._cleanup()
        self._done = True
        return ([dst for _, dst, _ in moves] + [o.path for o in new_folders]
                + [o.path for o in self.outputs if o.inside is not None])

    def discard(self) -> None:
        """Remove everything staged; final paths are left exactly as they were."""
        self._cleanup()
        self._done = True

    def _cleanup(self) -> None:
        for stage in self._staging.values():
            shutil.rmtree(stage, ignore_errors=True)
        self._staging.clear()

    # ----------------------------------------------------------------- context manager
    def __enter__(self) -> "OutputPlan":
        if threading.current_thread() is threading.main_thread():
            def _terminate(signum, frame):
                raise KeyboardInterrupt(f"{self.command}: terminated (signal {signum})")

            with contextlib.suppress(ValueError, OSError):
                self._old_sigterm = signal.signal(signal.SIGTERM, _terminate)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        staging = [str(s) for s in self._staging.values()]
        try:
            if not self._done:
                self.discard()
        finally:
            if self._old_sigterm is not None:
                with contextlib.suppress(ValueError, OSError):
                    signal.signal(signal.SIGTERM, self._old_sigterm)
                self._old_sigterm = None
        if exc is not None and isinstance(exc, (OSError, ValueError)) and staging:
            message = str(exc)
            if any(s in message for s in staging):
                # a writer named its staged file: name the user's path instead
                for o in self.outputs:
                    if o.staged is not None:
                        message = message.replace(str(o.staged), str(o.path))
                for s in staging:
                    message = message.replace(s + os.sep, "").replace(s, ".")
                try:
                    new = type(exc)(message)
                except Exception:  # noqa: BLE001 - exotic exception signature: keep the original
                    return None
                raise new from None
        return None
