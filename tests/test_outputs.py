"""Never lose a user's file (issue #12): the output plan, every CLI output option pointed at every
input, a long command killed mid-run, the viewer's --serve/--site folders, ``ibr bench`` without
matplotlib."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import cli
from bad_inputs import make_base
from ibr.io.outputs import IMAGE_EXTS, OutputPlan, STAGING_PREFIX

ROOT = Path(__file__).resolve().parents[1]


def digest(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and not p.is_symlink():
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return make_base(tmp_path_factory.mktemp("outputs_base") / "base")


# --------------------------------------------------------------------------- OutputPlan
def test_plan_refuses_before_any_work(tmp_path):
    (tmp_path / "in.png").write_bytes(b"input")
    os.symlink("in.png", tmp_path / "link.png")
    os.link(tmp_path / "in.png", tmp_path / "hard.png")
    (tmp_path / "dir.png").mkdir()
    cases = [
        (("-o", tmp_path / "in.png"), ValueError, r"-o: .*in.png is the input A .*refusing to overwrite"),
        (("-o", tmp_path / "link.png"), ValueError, r"is the input A"),
        (("-o", tmp_path / "hard.png"), ValueError, r"is the input A"),
        (("-o", tmp_path / "sub" / ".." / "in.png"), FileNotFoundError, r"output folder"),
        (("-o", tmp_path / "x.bmp"), ValueError, r"has the extension '.bmp'; expected one of .png"),
        (("-o", tmp_path / "x"), ValueError, r"has no extension"),
        (("-o", tmp_path / "dir.png"), IsADirectoryError, r"is a folder"),
        (("-o", tmp_path / "nodir" / "x.png"), FileNotFoundError, r"-o: the output folder .*nodir"),
    ]
    for (option, path), exc, match in cases:
        with OutputPlan() as plan:
            plan.add_input("A", tmp_path / "in.png")
            plan.add_file(option, path, IMAGE_EXTS)
            with pytest.raises(exc, match=match):
                plan.check()
    with OutputPlan() as plan:  # two outputs on one path
        plan.add_file("-o", tmp_path / "o.png", IMAGE_EXTS)
        plan.add_file("--holes", tmp_path / "o.png", IMAGE_EXTS)
        with pytest.raises(ValueError, match=r"--holes: .* is also the output of -o"):
            plan.check()
    assert (tmp_path / "in.png").read_bytes() == b"input"
    assert not list(tmp_path.glob(STAGING_PREFIX + "*"))


def test_plan_stages_and_renames_together(tmp_path):
    (tmp_path / "old.png").write_bytes(b"old")
    os.chmod(tmp_path / "old.png", 0o640)
    with OutputPlan() as plan:
        a = plan.add_file("-o", tmp_path / "old.png", IMAGE_EXTS)
        b = plan.add_file("--b", tmp_path / "new.exr", IMAGE_EXTS)
        plan.check()
        plan.stage(a).write_bytes(b"A")
        plan.stage(b).write_bytes(b"B")
        assert (tmp_path / "old.png").read_bytes() == b"old" and not (tmp_path / "new.exr").exists()
        assert sorted(plan.commit()) == sorted([tmp_path / "old.png", tmp_path / "new.exr"])
    assert (tmp_path / "old.png").read_bytes() == b"A" and (tmp_path / "new.exr").read_bytes() == b"B"
    assert (tmp_path / "old.png").stat().st_mode & 0o777 == 0o640  # the replaced file's mode is kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.exr", "old.png"]


@pytest.mark.parametrize("failure", [RuntimeError("boom"), KeyboardInterrupt()])
def test_plan_failure_leaves_everything_as_it_was(tmp_path, failure):
    (tmp_path / "old.png").write_bytes(b"old")
    with pytest.raises(type(failure)):
        with OutputPlan() as plan:
            a = plan.add_file("-o", tmp_path / "old.png", IMAGE_EXTS)
            f = plan.add_folder("--out", tmp_path / "frames", ("frame_*.png",))
            plan.check()
            plan.stage(a).write_bytes(b"half")
            plan.stage(f, "frame_000.png").write_bytes(b"f")
            raise failure
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.png"]
    assert (tmp_path / "old.png").read_bytes() == b"old"


@pytest.mark.parametrize("case", ["hard links", "no hard links", "a is a symbolic link"])
def test_plan_rolls_back_when_a_rename_fails(tmp_path, monkeypatch, case):
    """A rename failing half way puts the replaced files back, also where the file system has no
    hard links (the backup was skipped there and the rollback deleted the user's file) and where
    an output was a symbolic link (the rollback deleted it)."""
    if case == "no hard links":
        def no_link(*args, **kwargs):
            raise OSError(1, "hard links not supported")

        monkeypatch.setattr(os, "link", no_link)
    for n in ("a.png", "b.png"):
        (tmp_path / n).write_bytes(b"old " + n.encode())
    if case == "a is a symbolic link":
        (tmp_path / "a.png").rename(tmp_path / "keep.png")
        (tmp_path / "a.png").symlink_to(tmp_path / "keep.png")
    real = os.replace
    calls = []

    def flaky(src, dst):
        calls.append(dst)
        if Path(dst).name == "b.png" and len([c for c in calls if Path(c).name == "b.png"]) == 1:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(OSError, match="No space left"):
        with OutputPlan() as plan:
            a = plan.add_file("-a", tmp_path / "a.png", IMAGE_EXTS)
            b = plan.add_file("-b", tmp_path / "b.png", IMAGE_EXTS)
            plan.check()
            plan.stage(a).write_bytes(b"new a")
            plan.stage(b).write_bytes(b"new b")
            plan.commit()
    assert (tmp_path / "a.png").read_bytes() == b"old a.png"  # restored from the backup link
    assert (tmp_path / "a.png").is_symlink() == (case == "a is a symbolic link")
    assert (tmp_path / "b.png").read_bytes() == b"old b.png"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["a.png", "b.png"] + (["keep.png"] if case == "a is a symbolic link" else []))


def test_frame_folder_removes_only_its_own_pattern_and_says_so(tmp_path):
    fr = tmp_path / "fr"
    fr.mkdir()
    for n in ("frame_000_t0.000.png", "frame_007_t0.700.png", "keep.png", "frame_notes.txt"):
        (fr / n).write_bytes(b"old")
    lines = []
    with OutputPlan("ibr test", log=lines.append) as plan:
        f = plan.add_folder("--out", fr, ("frame_*_t*.png",))
        plan.check()
        plan.stage(f, "frame_000_t0.000.png").write_bytes(b"new")
        with pytest.raises(ValueError, match="does not follow the patterns"):
            plan.stage(f, "other.png")
        plan.commit()
    assert sorted(p.name for p in fr.iterdir()) == ["frame_000_t0.000.png", "frame_notes.txt", "keep.png"]
    assert (fr / "frame_000_t0.000.png").read_bytes() == b"new" and (fr / "keep.png").read_bytes() == b"old"
    assert lines == [f"ibr test: removed 1 file(s) of an earlier run from {fr}/ (frame_*_t*.png; other files untouched)"]


def test_new_nested_frame_folder_appears_whole(tmp_path):
    with OutputPlan() as plan:
        f = plan.add_folder("--out", tmp_path / "a" / "b", ("frame_*.png",))
        plan.check()
        (plan.stage(f) / "frame_1.png").write_bytes(b"1")
        assert not (tmp_path / "a").exists()
        plan.commit()
    assert (tmp_path / "a" / "b" / "frame_1.png").read_bytes() == b"1"
    assert (tmp_path / "a" / "b").stat().st_mode & 0o777 != 0o700  # not left private like a temp folder


def test_frame_folder_refuses_an_input_of_its_pattern(tmp_path):
    (tmp_path / "frame_000.png").write_bytes(b"input")
    with OutputPlan() as plan:
        plan.add_input("VIEW 'color'", tmp_path / "frame_000.png")
        plan.add_folder("--out", tmp_path, ("frame_*.png",))
        with pytest.raises(ValueError, match=r"--out: .*frame_000.png\) is the input VIEW 'color'"):
            plan.check()


def test_writer_errors_name_the_users_path(tmp_path):
    with pytest.raises(OSError) as info:
        with OutputPlan() as plan:
            out = plan.add_file("-o", tmp_path / "o.png", IMAGE_EXTS)
            plan.check()
            raise OSError(f"{plan.stage(out)}: write failed")
    assert str(info.value) == f"{tmp_path / 'o.png'}: write failed"
    assert STAGING_PREFIX not in str(info.value)


def test_stale_staging_of_a_dead_process_is_removed(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f"{STAGING_PREFIX}{int(dead.stdout)}-abc"
    stale.mkdir()
    (stale / "frame_1.png").write_bytes(b"partial")
    mine = tmp_path / f"{STAGING_PREFIX}{os.getpid()}-xyz"  # a live process's staging is left alone
    mine.mkdir()
    with OutputPlan() as plan:
        plan.add_file("-o", tmp_path / "o.png", IMAGE_EXTS)
        plan.check()
        assert not stale.exists() and mine.exists()


def test_unwritable_folder_is_refused_with_the_users_path(tmp_path, monkeypatch):
    import ibr.io.outputs as outputs

    def refuse(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(outputs.tempfile, "mkdtemp", refuse)
    with OutputPlan() as plan:
        plan.add_file("-o", tmp_path / "o.png", IMAGE_EXTS)
        with pytest.raises(PermissionError, match=r"-o: cannot write into the folder .* of .*o.png \(Permission denied\)"):
            plan.check()


# --------------------------------------------------------------------------- every output option at every input
VIEW_INPUTS = ["a.json", "a_color.png", "a_depth.exr"]
MATRIX = {
    # command: (argv with {o} where the output goes, {other outputs as new files}, the inputs)
    "warp": (["warp", "{d}/a.json", "--to", "{d}/b.json"], {"-o": "o.png", "--depth-out": "d.exr", "--holes-out": "h.png"},
             VIEW_INPUTS + ["b.json", "b_color.png", "b_depth.exr"]),
    "interpolate": (["interpolate", "{d}/a.json", "{d}/b.json", "--t", "0.5"],
                    {"--out": "fr", "--video": "v.mp4", "--contact-sheet": "c.png"},
                    VIEW_INPUTS + ["b.json", "b_color.png", "b_depth.exr"]),
    "mesh": (["mesh", "{d}/a.json"], {"--obj": "m.obj", "--ply": "m.ply", "--viz": "s.png"}, VIEW_INPUTS),
    "stereo": (["stereo", "{d}/a.json"], {"-o": "s.png"}, VIEW_INPUTS),
    "distort": (["distort", "{d}/img.png", "--c1", "0.2"], {"-o": "o.png"}, ["img.png"]),
    "timewarp": (["timewarp", "{d}/a.json", "--poses", "{d}/poses.json"], {"-o": "tw"}, VIEW_INPUTS + ["poses.json"]),
    "cubemap": (["cubemap", "{d}/pano.png"], {"-o": "c.png"}, ["pano.png"]),
    "view": (["view", "{d}/pano.png", "--width", "16", "--height", "8"], {"-o": "v.png"}, ["pano.png"]),
    "view --tour": (["view", "{d}/pano.png", "--width", "16", "--height", "8", "--tour", "2"], {"-o": "t.gif"}, ["pano.png"]),
    "view --serve": (["view", "{d}/pano.png", "--serve", "--port", "0"], {"--site": "site"}, ["pano.png", "."]),
    "samples": (["samples", "--no-middlebury"], {"--out": "s"}, []),
}


def _matrix_cases():
    for cmd, (argv, outs, inputs) in MATRIX.items():
        for opt in outs:
            for inp in inputs:
                yield pytest.param(cmd, opt, inp, id=f"{cmd} {opt} {inp}")
                if inp != ".":
                    yield pytest.param(cmd, opt, "link:" + inp, id=f"{cmd} {opt} symlink to {inp}")


@pytest.mark.parametrize("cmd,opt,target", list(_matrix_cases()))
def test_every_output_option_pointed_at_every_input(base, tmp_path, cmd, opt, target, capsys):
    import shutil

    d = tmp_path / "d"
    shutil.copytree(base, d)
    argv, outs, _ = MATRIX[cmd]
    if target.startswith("link:"):
        os.symlink(target[5:], d / ("out_link" + Path(target[5:]).suffix))
        pointed = d / ("out_link" + Path(target[5:]).suffix)
    else:
        pointed = d / target
    line = [a.format(d=d) for a in argv]
    for o, name in outs.items():
        line += [o, str(pointed if o == opt else d / "new" / name)]
    (d / "new").mkdir()
    before = digest(d)
    rc = cli.main(line)
    err = capsys.readouterr().err
    assert rc in (1, 2), err  # refused
    assert "Traceback" not in err
    assert digest(d) == before  # no input's bytes changed, nothing written anywhere
    assert not list(d.rglob(STAGING_PREFIX + "*"))


def test_samples_refuses_the_bundled_folder_and_leaves_it_intact(capsys, tmp_path):
    from samples import DATA_DIR

    before = digest(DATA_DIR)
    assert cli.main(["samples", "--out", str(DATA_DIR)]) == 1
    assert "bundled data folder itself" in capsys.readouterr().err
    assert cli.main(["samples", "--out", str(DATA_DIR / "room_a.json")]) == 1
    assert "is inside the bundled data folder" in capsys.readouterr().err
    assert digest(DATA_DIR) == before
    (tmp_path / "f.txt").write_text("x")
    assert cli.main(["samples", "--out", str(tmp_path / "f.txt")]) == 1
    assert "is not a folder" in capsys.readouterr().err
    assert (tmp_path / "f.txt").read_text() == "x"


# --------------------------------------------------------------------------- killing a long command
def _start_cli(args, cwd):
    """``python cli.py ARGS`` with stderr piped, as a user starts it from a shell: Ctrl-C
    (SIGINT) restored to its default in the child. A shell without job control starts background
    commands with SIGINT ignored, and Python then installs no KeyboardInterrupt handler: a test
    run that way (``.ci/run ... &``) saw the command ignore the test's SIGINT and hang."""
    return subprocess.Popen([sys.executable, str(ROOT / "cli.py"), *args], cwd=cwd, stderr=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, text=True, env=dict(os.environ, PYTHONUNBUFFERED="1"),
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _run_and_kill(args, cwd, sig, after_lines=4, timeout=120):
    proc = _start_cli(args, cwd)
    seen = []
    deadline = time.monotonic() + timeout
    for line in proc.stderr:  # non-TTY progress: one line per frame
        seen.append(line)
        if line.startswith("interpolate ") and int(line.split()[1].split("/")[0]) >= after_lines:
            break
        assert time.monotonic() < deadline, "".join(seen)
    proc.send_signal(sig)
    rest = proc.stderr.read()
    proc.wait(timeout=60)
    return proc.returncode, "".join(seen) + rest


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGKILL], ids=["TERM", "INT", "KILL"])
def test_killing_interpolate_with_video_leaves_no_partial_or_mixed_output(base, tmp_path, sig):
    """`ibr interpolate --frames 400 --video` killed after a few frames: the old frames, the old
    video and the other files of the folder are exactly as before; no new frame, no video, no
    temporary file is visible. SIGKILL can leave only a hidden staging folder, which the next run
    into that folder removes."""
    import shutil

    d = tmp_path / "d"
    shutil.copytree(base, d)
    fr = d / "fr"
    fr.mkdir()
    (fr / "frame_000_t0.000.png").write_bytes(b"earlier run")
    (fr / "notes.txt").write_text("mine")
    (d / "v.mp4").write_bytes(b"earlier video")
    before = digest(d)
    rc, err = _run_and_kill(["interpolate", "a.json", "b.json", "--frames", "400", "--out", "fr", "--video", "v.mp4",
                             "--contact-sheet", "sheet.png"], d, sig)
    assert rc != 0, err
    assert "Traceback" not in err, err
    assert {k: v for k, v in digest(d).items() if STAGING_PREFIX not in k} == before, err
    visible = sorted(p.name for p in fr.iterdir() if not p.name.startswith("."))
    assert visible == ["frame_000_t0.000.png", "notes.txt"]
    assert not (d / "sheet.png").exists()
    hidden = [p for p in list(d.iterdir()) + list(fr.iterdir()) if p.name.startswith(".")]
    if sig == signal.SIGKILL:
        assert all(p.name.startswith(STAGING_PREFIX) for p in hidden)
        assert cli.main(["interpolate", str(d / "a.json"), str(d / "b.json"), "--t", "0.5", "--out", str(fr),
                         "--video", str(d / "v.mp4")]) == 0
        assert not [p for p in list(d.iterdir()) + list(fr.iterdir()) if p.name.startswith(".")]
        assert sorted(p.name for p in fr.iterdir()) == ["frame_000_t0.500.png", "notes.txt"]
    else:
        assert hidden == []


# --------------------------------------------------------------------------- the viewer's folders
def _serve(args, cwd):
    proc = _start_cli(["view", *args], cwd)
    for line in proc.stderr:
        if "serving" in line:
            return proc, line
    proc.wait(timeout=30)
    raise AssertionError(f"view --serve did not start (exit {proc.returncode})")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["Ctrl-C", "TERM"])
def test_serve_removes_its_temporary_site_on_exit(base, sig):
    proc, line = _serve([str(base / "pano.png"), "--serve", "--port", "0"], base)
    folder = Path(line.split("serving ", 1)[1].split(" at ")[0])
    assert (folder / "index.html").is_file()
    proc.send_signal(sig)
    rest = proc.stderr.read()
    proc.wait(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in rest, rest
    assert not folder.exists()


def test_site_with_force_replaces_only_viewer_files_and_serves_only_them(base, tmp_path):
    import urllib.error
    import urllib.request

    site = tmp_path / "site"
    site.mkdir()
    (site / "secret.txt").write_text("not for the web")
    (site / "index.html").write_text("old page")
    assert cli.main(["view", str(base / "pano.png"), "--serve", "--site", str(site), "--port", "0"]) == 1
    assert (site / "index.html").read_text() == "old page"
    proc, line = _serve([str(base / "pano.png"), "--serve", "--site", str(site), "--force", "--port", "0"], tmp_path)
    try:
        url = line.split(" at ", 1)[1].split()[0]
        root = url.split("index.html")[0]
        assert b"TEXTURE_CUBE_MAP" in urllib.request.urlopen(url, timeout=10).read()
        with pytest.raises(urllib.error.HTTPError, match="404"):
            urllib.request.urlopen(root + "secret.txt", timeout=10)
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    assert (site / "secret.txt").read_text() == "not for the web"  # kept, not served
    from panorama.viewer import SITE_FILES

    names = {p.name for p in site.iterdir()} - {"canvas.js"}  # canvas.js: the canvas UI of #14
    assert names == {"secret.txt", *(n for n in SITE_FILES if not n.endswith("_r.png") and n != "mesh.bin")}  # mono, no depth


# --------------------------------------------------------------------------- ibr bench without matplotlib
def test_bench_without_matplotlib_prints_tables_into_the_users_folder(tmp_path, monkeypatch, capsys):
    """A stand-in benchmark that plots when it can (as the real ones do): without matplotlib the
    command prints the table and one line about the extra; results go to --out."""
    import commands.bench as bench

    fake = tmp_path / "benchmarks"
    fake.mkdir()
    (fake / "bench_fake.py").write_text(
        "from pathlib import Path\n"
        "RESULTS = Path(__file__).parent / 'results'\n"
        "def main(argv=None):\n"
        "    print('case  ms\\nfake  1.0')\n"
        "    RESULTS.mkdir(parents=True, exist_ok=True)\n"
        "    (RESULTS / 'table.txt').write_text('fake 1.0')\n"
        "    try:\n"
        "        import matplotlib\n"
        "    except ImportError:\n"
        "        return 0\n"
        "    (RESULTS / 'plot.png').write_bytes(b'png')\n"
        "    return 0\n")
    monkeypatch.setattr(bench, "_bench_dir", lambda: fake)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib raises ImportError
    monkeypatch.chdir(tmp_path)
    assert cli.main(["bench", "fake"]) == 0
    out = capsys.readouterr()
    assert "fake  1.0" in out.out
    assert out.err.count('plots need pip install -e ".[bench]"') == 1
    assert (tmp_path / "ibr-bench" / "table.txt").is_file()  # default folder under the current one
    assert not (fake / "results").exists()  # never beside the installed scripts
    assert cli.main(["bench", "fake", "--out", str(tmp_path / "mine")]) == 0
    assert (tmp_path / "mine" / "table.txt").is_file()
    assert cli.main(["bench", "fake", "--full", "--out", str(tmp_path / "mine")]) == 0
    monkeypatch.setattr(bench, "_bench_dir", lambda: ROOT / "benchmarks")
    assert cli.main(["bench", "stereo", "--full", "--out", str(tmp_path / "x")]) == 1  # full reports are figures
    assert 'install the plotting extra: pip install -e ".[bench]"' in capsys.readouterr().err


def test_real_benchmarks_write_where_they_are_pointed():
    """The benchmarks that write figures have a module-level RESULTS (what `ibr bench --out`
    redirects)."""
    import ast

    for name in ("mesh", "panorama", "render", "stereo", "synth"):
        path = ROOT / "benchmarks" / f"bench_{name}.py"
        tree = ast.parse(path.read_text())
        names = {t.id for node in tree.body if isinstance(node, ast.Assign) for t in node.targets
                 if isinstance(t, ast.Name)}
        assert "RESULTS" in names, f"{path.name}: no module-level RESULTS"


def test_a_short_png_write_raises_and_keeps_the_old_file(tmp_path):
    """OpenImageIO's PNG writer returns success on a short write (a full disk) and reports it
    only in ``geterror()``; the truncated file was renamed over the good one. Simulated with a
    file-size limit in a child process: the write must raise and the old file stay as it was."""
    good = tmp_path / "a.png"
    code = f"""
import resource, signal, sys
import numpy as np
sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r})
from ibr.io import write_image
write_image({str(good)!r}, np.zeros((8, 8, 3), np.uint8))
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (4000, resource.RLIM_INFINITY))
noise = np.random.default_rng(0).integers(0, 255, (64, 64, 3), dtype=np.uint8)
try:
    write_image({str(good)!r}, noise)
except OSError as exc:
    print("raised:", exc)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert "raised:" in out.stdout and "write failed" in out.stdout, out.stdout + out.stderr
    from ibr.io import read_image

    np.testing.assert_array_equal(read_image(good), np.zeros((8, 8, 3), np.uint8))
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"]  # no temporary file left


@pytest.mark.parametrize("argv, written, users", [
    (["interpolate", "{a}", "{b}", "--frames", "2", "--out", "{o}"], ["frame_000_t0.000.png", "frame_001_t1.000.png"],
     ["frame_notes.png", "frame_intro_title.png", "frame_2024_poster.png"]),
    (["stereo", "{seq}", "--auto", "-o", "{o}"], ["stereo_0000.png", "stereo_0001.png"], ["stereo_cover.png"]),
    (["interpolate", "{seq}", "--factor", "1", "--out", "{o}"], ["frame_0000.png", "frame_0001.png"],
     ["frame_notes.png", "frame_2024_poster.png"]),
])
def test_frame_folders_leave_look_alike_user_files_alone(tmp_path, argv, written, users):
    """An existing output folder loses only the command's own frames of an earlier run. The
    patterns were globs (``frame_*.png``, ``frame_*_t*.png``, ``stereo_*.png``) that took a
    user's frame_notes.png, frame_intro_title.png, frame_2024_poster.png or stereo_cover.png;
    ``#`` (one or more digits) in the patterns now keeps them."""
    import json

    from ibr.io.outputs import matches_patterns

    base = make_base(tmp_path / "in")
    seq = base / "seq.json"
    seq.write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": ["a.json", "b.json"]}))
    out = tmp_path / "o"
    out.mkdir()
    stale = written[0].replace("000", "099", 1) if "_t" in written[0] else written[0].replace("0000", "0099")
    for n in users + [stale]:
        (out / n).write_bytes(b"user")
    args = [x.format(a=base / "a.json", b=base / "b.json", seq=seq, o=out) for x in argv]
    assert cli.main(args) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(users + written), names  # the earlier run's frame (stale) is gone, users' files kept
    assert all((out / n).read_bytes() == b"user" for n in users)
    assert matches_patterns("frame_0007.png", ("frame_#.png",)) and not matches_patterns("frame_7a.png", ("frame_#.png",))


def test_outputs_clashing_with_a_frame_folder_or_behind_a_dangling_link(tmp_path):
    """Found by a hostile-input audit: (1) a contact sheet named like one of the frames of --out
    in that folder replaced the frame (both outputs on one file); (2) --out a symbolic link to a
    missing folder rendered everything, then failed naming the internal staging path. (A
    symbolic-link output lost by a rollback: test_plan_rolls_back_when_a_rename_fails.)"""
    out = tmp_path / "o"
    out.mkdir()
    with pytest.raises(ValueError, match="--contact-sheet: .* is named like a frame of --out"):
        with OutputPlan() as plan:
            plan.add_folder("--out", out, ("frame_#_t#.#.png",))
            plan.add_file("--contact-sheet", out / "frame_000_t0.250.png", IMAGE_EXTS)
            plan.check()
    with OutputPlan() as plan:  # another name in that folder is fine
        plan.add_folder("--out", out, ("frame_#_t#.#.png",))
        plan.add_file("--contact-sheet", out / "sheet.png", IMAGE_EXTS)
        plan.check()
    (tmp_path / "dl").symlink_to(tmp_path / "missing")
    with pytest.raises(FileNotFoundError, match="--out: .*dl is a symbolic link to .*missing, which does not exist"):
        with OutputPlan() as plan:
            plan.add_folder("--out", tmp_path / "dl", ("frame_#.png",))
            plan.check()


def test_face_folders_and_viewer_sites_leave_look_alike_user_files_alone(tmp_path):
    """``px.*`` took a user's px.txt and pz.backup.png (ibr cubemap -o folder, ibr stitch-photos
    --cube); the site's ``tile-*.png`` and ``scene-*-*.png`` took tile-notes.png and
    scene-my-holiday.png (ibr view --site --force). Only the command's own names are removed."""
    from samples import DATA_DIR

    pano = DATA_DIR / "rig" / "capture_pano_color.png"
    faces = tmp_path / "faces"
    faces.mkdir()
    users = ["px.txt", "pz.backup.png", "nx_notes.png"]
    for n in users + ["py.jpg"]:  # py.jpg: an earlier run's face in another format
        (faces / n).write_bytes(b"user")
    assert cli.main(["cubemap", str(pano), "-o", str(faces)]) == 0
    names = sorted(p.name for p in faces.iterdir())
    assert names == sorted(users + [f"{n}.png" for n in ("px", "nx", "py", "ny", "pz", "nz")]), names
    site = tmp_path / "site"
    site.mkdir()
    keep = ["tile-notes.png", "scene-my-holiday.png", "notes.txt"]
    for n in keep + ["tile-1-px-0-0.png"]:
        (site / n).write_bytes(b"user")
    assert cli.main(["view", str(pano), "--site", str(site), "--force"]) == 0
    left = {p.name for p in site.iterdir()}
    assert set(keep) <= left and "tile-1-px-0-0.png" not in left


def test_regressions_of_the_look_alike_fixes(tmp_path, capsys):
    """Found by the review of these fixes: an import --name holding '#' (a digits wildcard in
    patterns now) failed after the work; cube faces --ext .PNG failed at commit; RGBA to .jpg
    (the new JPEG channel check) failed after the work; canvas face folders still removed px.txt."""
    import json

    from ibr.io import write_image
    from samples import DATA_DIR

    src = Path(__file__).parent / "data" / "import" / "blender_rgb" / "transforms.json"
    assert cli.main(["import", "nerf", str(src), "--out", str(tmp_path / "imp"), "--name", "take#1"]) == 0
    assert (tmp_path / "imp" / "take#1.json").is_file()
    pano = DATA_DIR / "rig" / "capture_pano_color.png"
    assert cli.main(["cubemap", str(pano), "-o", str(tmp_path / "faces"), "--ext", ".PNG"]) == 0
    assert (tmp_path / "faces" / "px.PNG").is_file()
    rgba = np.dstack([np.full((32, 64, 3), 100, np.uint8), np.full((32, 64), 255, np.uint8)])
    write_image(tmp_path / "rgba.png", rgba)
    assert cli.main(["view", str(tmp_path / "rgba.png"), "-o", str(tmp_path / "v.jpg"), "--width", "16",
                     "--height", "8"]) == 0
    assert cli.main(["cubemap", str(pano), "-o", str(tmp_path / "scene")]) == 0  # a face-folder panorama
    folder = tmp_path / "cf"
    folder.mkdir()
    (folder / "px.txt").write_bytes(b"user")
    assert cli.main(["canvas", str(tmp_path / "scene"), "--image", str(tmp_path / "rgba.png"), "--center", "0", "0",
                     "2", "--normal", "0", "0", "-1", "--size", "1", "0.5", "-o", str(folder)]) == 0
    assert (folder / "px.txt").read_bytes() == b"user" and (folder / "px.png").is_file()
    assert json.loads(src.read_text())  # the input untouched


def test_last_review_round(tmp_path):
    """(1) A float RGBA image to .jpg kept its alpha (converted to uint8 first); (2) faces of an
    earlier run spelt px.PNG stayed beside the new px.png; (3) a job with one missing declared
    input lost the protection of its existing inputs against --report; (4) the folders a failed
    job's staging created were removed shallowest-first across outputs (one stayed)."""
    import json

    from commands._common import face_file_patterns, image_for
    from ibr.io.outputs import matches_patterns
    from ibr.sequence import load_jobs, run_batch
    from ibr.sequence.jobs import check_batch_files

    rgba = np.full((4, 4, 4), 0.5, np.float32)
    assert image_for(Path("v.jpg"), rgba).shape == (4, 4, 3) and image_for(Path("v.jpg"), rgba).dtype == np.uint8
    assert matches_patterns("px.PNG", face_file_patterns(".png")) and not matches_patterns("px.txt", face_file_patterns())
    (tmp_path / "scene.png").write_bytes(b"input")
    jobs = [{"id": "j1", "argv": ["stereo", "scene.png", "-o", "o.png"], "inputs": ["missing.json"]}]
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": jobs}))
    with pytest.raises(ValueError, match="--report: .*scene.png is an input of job j1"):
        check_batch_files(load_jobs(path), path, tmp_path / ".ibr-batch", tmp_path / "scene.png")
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1,
                                "jobs": [{"id": "both", "argv": ["warp", "nothere.json", "--to", "nothere.json",
                                                                 "-o", "new/a/x.png", "--holes-out", "new/b/y.png"]}]}))
    report = run_batch(load_jobs(path), records=tmp_path / ".ibr-batch", workers=1)
    assert report.counts["failed"] == 1 and not (tmp_path / "new").exists()


def test_final_review_round(tmp_path, monkeypatch, capsys):
    """(1) ``ibr bench a b`` looked for the second topic's script in the first one's cache folder;
    (2) --report over an input that a view names, when another declared input was missing, and
    over a hard link of the batch file; (3) face folders written as px.PNG could not be read back."""
    import json
    import os

    import commands.bench as bench
    from ibr.sequence import load_jobs
    from ibr.sequence.jobs import check_batch_files
    from panorama.files import find_face_files

    fake = tmp_path / "benchmarks"
    fake.mkdir()
    for t in ("a", "b"):
        (fake / f"bench_{t}.py").write_text("CACHE = None\ndef main(argv=None):\n    print('ran')\n    return 0\n")
    monkeypatch.setattr(bench, "_bench_dir", lambda: fake)
    assert cli.main(["bench", "a", "b", "--out", str(tmp_path / "o")]) == 0
    assert capsys.readouterr().out.count("ran") == 2
    d = tmp_path / "batch"
    (d / "views").mkdir(parents=True)
    (d / "views" / "v_color.png").write_bytes(b"png")
    (d / "views" / "v.json").write_text(json.dumps({"format": "ibr-view", "version": 1, "color": "v_color.png",
                                                    "camera": {}}))
    path = d / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jobs": [
        {"id": "j1", "argv": ["stereo", "views/v.json", "-o", "o.png"], "inputs": ["missing.json"]}]}))
    with pytest.raises(ValueError, match="--report: .*v_color.png is an input of job j1"):
        check_batch_files(load_jobs(path), path, d / ".ibr-batch", d / "views" / "v_color.png")
    os.link(path, d / "alias.json")
    with pytest.raises(ValueError, match="--report: .*alias.json is the batch file"):
        check_batch_files(load_jobs(path), path, d / ".ibr-batch", d / "alias.json")
    faces = tmp_path / "faces"
    faces.mkdir()
    for n in ("px", "nx", "py", "ny", "pz", "nz"):
        (faces / f"{n}.PNG").write_bytes(b"x")
    assert [p.name for p in find_face_files(faces)][0] == "px.PNG"


def test_a_range_map_is_refused_as_8bit_grey_not_written_white(tmp_path):
    """A one-channel float image with values outside [0, 1] (a range map) clipped to 8-bit was
    all white, exit 0 (`ibr view RANGE.exr -o v.png`, `ibr view RANGE.exr --site S`): now refused
    naming the output; 0-1 grey, HDR colour and an 8-bit PNG input still write."""
    import cli
    from commands._common import image_for
    from ibr.io import read_image, write_image
    from panorama.viewer import write_site

    rng = np.full((32, 64), 2.0, np.float32)
    rng[:, :20] = 7.5
    write_image(tmp_path / "range.exr", rng)
    with pytest.raises(ValueError, match=r"-o: v.png would hold 8-bit grey levels 0-1, .* holds 2 to 7.5"):
        image_for(tmp_path / "v.png", rng)
    with pytest.raises(ValueError, match=r"pano: the site's faces .* a range map is the depth"):
        write_site(tmp_path / "site", rng)
    assert not (tmp_path / "site").exists()
    for argv in (["-o", "v.png"], ["--tour", "2", "-o", "tour"], ["--site", "site"]):  # before any view
        assert cli.main(["view", str(tmp_path / "range.exr"), *argv[:-1], str(tmp_path / argv[-1])]) == 1
        assert not (tmp_path / argv[-1]).exists()
    grey_hdr = np.full((32, 64), 0.3, np.float32)
    grey_hdr[:4, :4] = 3.0  # a grey image with highlights, not a range map: clipped as colour is
    assert (image_for(tmp_path / "gh.png", grey_hdr) == np.rint(0.3 * 255)).mean() > 0.9
    grey = np.linspace(0, 1, 64, dtype=np.float32)[None].repeat(32, 0)
    np.testing.assert_array_equal(image_for(tmp_path / "g.png", grey)[0], np.rint(grey[0] * 255).astype(np.uint8))
    hdr = np.full((32, 64, 3), 3.0, np.float32)  # HDR colour clips (highlights), as before
    assert (image_for(tmp_path / "h.png", hdr) == 255).all()
    assert cli.main(["view", str(tmp_path / "range.exr"), "-o", str(tmp_path / "v.exr")]) == 0
    assert read_image(tmp_path / "v.exr").max() > 1
