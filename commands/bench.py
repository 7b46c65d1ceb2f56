"""``ibr bench``: run the benchmarks in ``benchmarks/`` (quick mode by default)."""

from __future__ import annotations

HELP = "run a benchmark from benchmarks/ in quick mode (default: render, speed vs error)"


def add_arguments(parser) -> None:
    parser.add_argument("topics", nargs="*", default=["render"], metavar="TOPIC",
                        help="benchmarks/bench_<TOPIC>.py to run (default: render); 'list' lists them")
    parser.add_argument("--full", action="store_true", help="full run instead of --quick (minutes)")


def _bench_dir():
    from pathlib import Path

    here = Path(__file__).resolve().parent.parent / "benchmarks"
    if not here.is_dir():
        raise FileNotFoundError(
            f"benchmarks: {here} not found; the benchmarks ship with the source tree "
            "(clone the repository and `pip install -e .[bench]`)")
    return here


def run(args) -> int:
    import importlib.util
    import sys

    from commands._common import info

    folder = _bench_dir()
    available = sorted(p.stem[len("bench_"):] for p in folder.glob("bench_*.py"))
    if args.topics == ["list"]:
        print("\n".join(available))
        return 0
    for topic in args.topics:
        if topic not in available:
            raise ValueError(f"topic: expected one of {', '.join(map(repr, available))}, got {topic!r}")
    code = 0
    for topic in args.topics:
        path = folder / f"bench_{topic}.py"
        info(f"bench: {path.name}{'' if args.full else ' --quick'}")
        spec = importlib.util.spec_from_file_location(f"_ibr_bench_{topic}", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module
        spec.loader.exec_module(module)
        if not hasattr(module, "main"):
            raise RuntimeError(f"{path.name}: has no main(argv) function")
        try:
            result = module.main([] if args.full else ["--quick"])
        except TypeError:  # a main() without argv
            saved = sys.argv
            sys.argv = [str(path)] + ([] if args.full else ["--quick"])
            try:
                result = module.main()
            finally:
                sys.argv = saved
        code = code or int(result or 0)
    return code
