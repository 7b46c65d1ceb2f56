"""``ibr`` command line: thin subcommands over the ``ibr`` and ``panorama`` libraries.

Exit codes: 0 success, 2 a command line the parser refuses (unknown option, bad choice, a value
of the wrong type), 1 every other error (option values the command checks, bad data, missing
files, a failed computation). Run ``ibr <command> --help`` for each command's options.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# (subcommand, module in commands/) in the order shown by --help.
COMMANDS = [
    ("samples", "samples"),
    ("interpolate", "interpolate"),
    ("warp", "warp"),
    ("mesh", "mesh"),
    ("bench", "bench"),
    ("stereo", "stereo"),
    ("distort", "distort"),
    ("timewarp", "timewarp"),
    ("cubemap", "cubemap"),
    ("view", "view"),
    ("stitch", "stitch"),
    ("canvas", "canvas"),
    ("batch", "batch"),
    ("stitch-photos", "stitch_photos"),
    ("import", "import_data"),
]


def _available_commands():
    for name, module in COMMANDS:
        try:
            yield name, importlib.import_module(f"commands.{module}")
        except ModuleNotFoundError as exc:
            if exc.name != f"commands.{module}":
                raise


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ibr",
        description="Image-based rendering from RGB-D views: new views, stereo pairs and panoramas.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in _available_commands():
        p = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_run=module.run, _first_run=getattr(module, "first_run_kernels", None), _parser=p)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:  # told by the command's own parser, with its usage (the top level's said "ibr COMMAND ...")
            (getattr(args, "_parser", None) or parser).error(f"unrecognized arguments: {' '.join(extra)}")
    except SystemExit as exc:  # argparse exits 2 on usage errors, 0 on --help
        return int(exc.code or 0)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        _start_first_run_helper(args)
        return int(args._run(args) or 0)
    except KeyboardInterrupt:
        print("ibr: interrupted", file=sys.stderr)
        return 1
    except BrokenPipeError:  # e.g. 'ibr bench list | head -3': the reader left; quietly, as a SIGPIPE exit
        _silence_stdout()
        return 128 + 13
    except (ValueError, TypeError, OSError, RuntimeError) as exc:
        print(f"ibr {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:
        cv2 = sys.modules.get("cv2")  # no cv2.error without cv2 loaded; main() does not import it
        if cv2 is None or not isinstance(exc, cv2.error):
            raise
        print(f"ibr {args.command}: error: {opencv_message(exc)}", file=sys.stderr)
        return 1


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's last flush of a closed pipe does not
    print another error at exit (the recipe of Python's signal module documentation)."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real stdout (a test's stand-in)
        pass


def opencv_message(exc: Exception) -> str:
    """One line from a ``cv2.error``: its status and reason without OpenCV's version and source path.

    Parameters
    ----------
    exc : cv2.error
        The exception; its text reads ``OpenCV(5.0.0) /path/resize.cpp:4217: error:
        (-215:Assertion failed) !ssize.empty() in function 'resize'``.

    Returns
    -------
    str
        ``OpenCV assertion failed: !ssize.empty() in function 'resize'`` for that text; the last
        non-empty line prefixed with ``OpenCV: `` when the text has another form.
    """
    import re

    text = str(exc).strip()
    found = re.search(r"error: \(-?\d+:([^)]*)\)\s*(.*)", text, re.S)
    if found is None:
        return "OpenCV: " + (text.splitlines()[-1].strip() if text else type(exc).__name__)
    reason = " ".join(found.group(2).split())
    return f"OpenCV {found.group(1).strip().lower()}: {reason}"


def _start_first_run_helper(args) -> None:
    """On a first run (an empty numba cache), start compiling the kernels the command will need in
    a second process now, before the command's own imports and input checks (0.25 s earlier than
    from inside the command, on the first run's critical path, #13). A command module names its
    kernels with ``first_run_kernels(args) -> (modules, warm kind) or None``."""
    from commands._common import forget_first_run, note_first_run

    forget_first_run()  # a new command: look at the cache again
    kernels = args._first_run(args) if args._first_run is not None else None
    if kernels is not None:  # quietly: the command says it after its own input checks
        modules, warm = kernels
        note_first_run(*modules, warm=warm, announce=False)


def run(argv: list[str] | None = None) -> None:
    """The ``ibr`` console command: :func:`main`, then exit with its code without tearing the
    interpreter down. Freeing numba's compiled code and the modules at exit took 0.25-0.4 s of
    every command (#13); by then every output is renamed into place and closed, so the exit
    handlers (the first-run helper's cleanup among them) run, the standard streams are flushed
    and the process ends (threads still running are not joined: none is by then). A program
    that calls the CLI in-process should call :func:`main`, which returns the exit code.
    ``IBR_FULL_EXIT=1`` keeps the ordinary exit (e.g. to see leak reports).
    """
    import atexit
    import os

    code = main(argv)
    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)
    if run_exit_handlers is None or os.environ.get("IBR_FULL_EXIT", "0") not in ("", "0"):
        sys.exit(code)
    run_exit_handlers()
    for stream in (sys.stdout, sys.stderr, sys.__stdout__, sys.__stderr__):
        try:
            if stream is not None:  # None: the descriptor was closed at start (``ibr ... >&-``)
                stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more to say
            pass
    os._exit(code)


if __name__ == "__main__":
    run()
