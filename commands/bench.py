"""``ibr bench``: run the benchmarks in ``benchmarks/`` (quick mode by default).

Results (figures, cached renders) go to ``--out`` (default ``./ibr-bench`` under the current
folder), never into the installed package or the docs. Without matplotlib (the ``bench`` extra)
the quick benchmarks print their tables and one line saying that plots need
``pip install -e ".[bench]"``.
"""

from __future__ import annotations

HELP = "run a benchmark from benchmarks/ in quick mode (default: render, speed vs error)"

#: Topics whose --full run cannot do without matplotlib (their reports are figures).
_PLOTS_REQUIRED_FULL = ("mesh", "stereo")


def add_arguments(parser) -> None:
    parser.add_argument("topics", nargs="*", default=["render"], metavar="TOPIC",
                        help="benchmarks/bench_<TOPIC>.py to run (default: render); 'list' lists them")
    parser.add_argument("--full", action="store_true", help="full run instead of --quick (minutes)")
    parser.add_argument("--out", default="ibr-bench", metavar="DIR",
                        help="folder for figures and cached data (default: ./%(default)s; created if missing)")


def _bench_dir():
    from pathlib import Path

    here = Path(__file__).resolve().parent.parent / "benchmarks"
    if not here.is_dir():
        raise FileNotFoundError(
            f"benchmarks: {here} not found; the benchmarks ship with the source tree "
            "(clone the repository and `pip install -e .[bench]`)")
    return here


def _have_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


def run(args) -> int:
    import importlib.util
    import sys
    from pathlib import Path

    from commands._common import info

    folder = _bench_dir()
    available = sorted(p.stem[len("bench_"):] for p in folder.glob("bench_*.py"))
    if args.topics == ["list"]:
        print("\n".join(available))
        return 0
    if "list" in args.topics:  # 'ibr bench list mesh' said "expected one of ..., got 'list'"
        others = [t for t in args.topics if t != "list"]
        raise ValueError(f"topic: 'list' lists the benchmarks ({', '.join(available)}) and takes no other topic; "
                         f"run 'ibr bench list', or 'ibr bench {' '.join(others)}' to run "
                         f"{'it' if len(others) == 1 else 'them'}")
    for topic in args.topics:
        if topic not in available:
            raise ValueError(f"topic: expected one of {', '.join(map(repr, available))}, got {topic!r}")
    plots = _have_matplotlib()
    if not plots and args.full:
        blocked = [t for t in args.topics if t in _PLOTS_REQUIRED_FULL]
        if blocked:
            raise ValueError(f"--full: the full {', '.join(blocked)} benchmark(s) draw figures; "
                             "install the plotting extra: pip install -e \".[bench]\"")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"--out: {out} exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    if not plots:
        info('bench: matplotlib not installed: tables only; plots need pip install -e ".[bench]"')
    code = 0
    for topic in args.topics:
        path = folder / f"bench_{topic}.py"
        argv = [] if args.full else ["--quick"]
        if topic == "render" and not plots:
            argv.append("--no-plot")
        info(f"bench: {path.name} {' '.join(argv)} -> results in {out}/")
        spec = importlib.util.spec_from_file_location(f"_ibr_bench_{topic}", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module
        spec.loader.exec_module(module)
        for name, where in (("RESULTS", out), ("DOCS", out), ("CACHE", out / "cache")):
            if hasattr(module, name):  # results, figure copies and caches go to the user's folder
                setattr(module, name, where)
        if not hasattr(module, "main"):
            raise RuntimeError(f"{path.name}: has no main(argv) function")
        import inspect

        if inspect.signature(module.main).parameters:  # main(argv); a TypeError inside it is its own
            result = module.main(argv)
        else:  # a main() without argv reads sys.argv
            saved = sys.argv
            sys.argv = [str(path)] + argv
            try:
                result = module.main()
            finally:
                sys.argv = saved
        code = code or int(result or 0)
    return code
