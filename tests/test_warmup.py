"""The first-run helper (ibr.render.warmup): it compiles the rasterizer and the hole fill with
the argument types of a real run, so the main process finds them in numba's cache."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _kernels_compiled_by(run: str, env) -> list[str]:
    """The sorted kernels (``module.function``, the module's last part) that ``run`` (Python
    lines) compiles in a fresh process."""
    probe = (
        "from numba.core import event\n"
        "done = []\n"
        "class L(event.Listener):\n"
        "    def on_start(self, ev): pass\n"
        "    def on_end(self, ev):\n"
        "        f = ev.data['dispatcher'].py_func\n"
        "        done.append(f.__module__.rsplit('.', 1)[-1] + '.' + f.__name__)\n"
        "event.register('numba:compile', L())\n"
        + run
        + "print(' '.join(sorted(set(done))))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], env=env, check=True, timeout=600, capture_output=True,
                         text=True, cwd=ROOT).stdout
    return out.strip().splitlines()[-1].split()


def test_the_helper_fills_the_cache_a_real_run_uses(tmp_path):
    """With an empty NUMBA_CACHE_DIR the helper writes cache entries for the plane fit, the
    rasterizer and the fill kernels; a real interpolation afterwards compiles none of those (it
    loads them), only the segmentation's edge prefix and split and the compositor."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "nb"), "PYTHONPATH": str(ROOT)}
    marks = tmp_path / "marks"
    marks.mkdir()
    subprocess.run([sys.executable, "-m", "ibr.render.warmup", "frame", str(marks)], env=env, check=True, timeout=300)
    assert sorted(p.name for p in marks.iterdir()) == ["fill", "raster"]  # each group marked once cached
    cached = {p.name.split("-")[0] for p in (tmp_path / "nb").rglob("*.nbi")}
    assert {"_raster_kernels._raster_quads", "_raster_kernels._setup_quads", "_fill_kernels.pp_push",
            "_fill_kernels.axis_background"} <= cached
    # the segmentation and the plane fit are the main process's (it reaches them first)
    assert not {n for n in cached if n.startswith("_segment_kernels")}
    compiled = _kernels_compiled_by(
        "from ibr.io import load_view\n"
        "from ibr.render.view_synthesis import interpolate\n"
        "from samples import DATA_DIR\n"
        "a, b = load_view(DATA_DIR / 'clutter_a.json'), load_view(DATA_DIR / 'clutter_b.json')\n"
        "interpolate(a, b, 0.5, fill='inpaint')\n", env)
    assert not [k for k in compiled if k.startswith(("_raster_kernels", "_fill_kernels"))]
    # the main process's share: the segmentation's edge prefix, split and plane fit, the compositor
    assert {"_segment_kernels._split_edges_kernel", "_segment_kernels._fit_planes_kernel",
            "_composite_kernels.composite_rgbt"} <= set(compiled)


def test_the_stitch_helper_fills_the_cache_a_real_stitch_uses(tmp_path):
    """``python -m ibr.render.warmup stitch`` writes the cache entries of the ray rasterizer's
    setup, the plane fit, the blend's accumulation and the mono panorama's hole fill, but not of
    the ray raster kernel and the blend's resolve (the main process's share); a real mono stitch
    with the fill afterwards compiles the segmentation and those two only. ``stitch-ods`` caches
    the ODS eyes' row fill instead of the mono fill."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "nb"), "PYTHONPATH": str(ROOT)}
    marks = tmp_path / "marks"
    marks.mkdir()
    subprocess.run([sys.executable, "-m", "ibr.render.warmup", "stitch", str(marks)], env=env, check=True, timeout=300)
    assert sorted(p.name for p in marks.iterdir()) == ["background-fill", "blend", "plane-fit", "ray-setup"]
    cached = {p.name.split("-")[0] for p in (tmp_path / "nb").rglob("*.nbi")}
    assert {"_ray_kernels._setup_rays", "_ray_kernels._region", "_blend_kernels.accumulate_spherical",
            "_segment_kernels._fit_planes_kernel", "_fill_kernels.background_fill"} <= cached
    assert not {"_ray_kernels._raster_rays", "_blend_kernels.resolve", "_fill_kernels.fill_rows_background"} & cached
    compiled = _kernels_compiled_by(
        "from ibr.io import load_view\n"
        "from panorama.stitch import equirect_camera, stitch_rgbd\n"
        "from panorama.stitch.fill import fill_stitched\n"
        "from samples import DATA_DIR\n"
        "views = [load_view(DATA_DIR / 'rig' / f'rig_0{i}.json') for i in (0, 1)]\n"
        "cam = equirect_camera(256)\n"
        "fill_stitched(stitch_rgbd(views, cam))\n", env)
    assert [k for k in compiled if k.startswith(("_ray_kernels", "_blend_kernels", "_fill_kernels"))] == [
        "_blend_kernels.resolve", "_ray_kernels._raster_rays"]
    assert "_segment_kernels._fit_planes_kernel" not in compiled
    assert any(k.startswith("_segment_kernels") for k in compiled)
    ods = tmp_path / "ods"
    ods.mkdir()
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "nb-ods")
    subprocess.run([sys.executable, "-m", "ibr.render.warmup", "stitch-ods", str(ods)], env=env, check=True,
                   timeout=300)
    assert sorted(p.name for p in ods.iterdir()) == ["blend", "plane-fit", "ray-setup", "row-fill"]
    cached = {p.name.split("-")[0] for p in (tmp_path / "nb-ods").rglob("*.nbi")}
    assert {"_fill_kernels.fill_rows_background", "_fill_kernels.smooth_across_rows"} <= cached
    assert "_fill_kernels.background_fill" not in cached


def test_the_mesh_helper_fills_the_cache_a_real_mesh_uses(tmp_path):
    """``python -m ibr.render.warmup mesh`` caches the split's own callees (the plane test's
    moments and row check, the crease split's line profile) and the plane fit with the argument
    types of a real segmentation: building a mesh afterwards compiles none of them, only the edge
    prefix and the split (the main process's share)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "nb"), "PYTHONPATH": str(ROOT)}
    marks = tmp_path / "marks"
    marks.mkdir()
    subprocess.run([sys.executable, "-m", "ibr.render.warmup", "mesh", str(marks)], env=env, check=True, timeout=300)
    assert sorted(p.name for p in marks.iterdir()) == ["plane-fit", "segment"]
    compiled = _kernels_compiled_by(
        "from ibr.io import load_view\n"
        "from ibr.mesh import build_mesh\n"
        "from samples import DATA_DIR\n"
        "build_mesh(load_view(DATA_DIR / 'room_a.json'))\n", env)
    ours = [k for k in compiled if k.startswith("_segment_kernels")]
    assert "_segment_kernels._split_edges_kernel" in ours and "_segment_kernels._edge_prefix_kernel" in ours
    for kernel in ("_rect_moments", "_row_exceeds", "_add_abs_second_diff", "_fit_planes_kernel"):
        assert f"_segment_kernels.{kernel}" not in ours


def test_import_sets_passive_openmp_wait_unless_the_user_chose():
    """``import ibr`` asks libgomp to let numba's threads sleep after a parallel kernel (#13:
    spinning threads slowed cv2.remap and the band pool by up to 1.4x); a user's value stays."""
    code = "import os, ibr; print(os.environ.get('OMP_WAIT_POLICY'))"
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    env["PYTHONPATH"] = str(ROOT)
    run = lambda e: subprocess.run([sys.executable, "-c", code], env=e, check=True, capture_output=True,  # noqa: E731
                                   text=True, timeout=120).stdout.strip()
    assert run(env) == "PASSIVE"
    assert run({**env, "OMP_WAIT_POLICY": "ACTIVE"}) == "ACTIVE"


def test_await_kernels_waits_for_the_helpers_mark_and_no_longer(tmp_path, monkeypatch):
    """The main process waits for a group the helper is still compiling (instead of compiling it
    a second time), returns when the mark appears or the helper ends, and at once without one."""
    import threading
    import time

    from ibr.base import first_run as warmup

    monkeypatch.setattr(warmup, "_STARTED", [])
    monkeypatch.setattr(warmup, "_READY", set())
    t0 = time.monotonic()
    warmup.await_kernels("raster")  # no helper: no wait
    assert time.monotonic() - t0 < 0.1
    helper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        warmup._STARTED.append((helper, tmp_path, warmup.GROUPS["frame"], os.getpid()))
        t0 = time.monotonic()
        warmup.await_kernels("blend")  # not a group of this helper: no wait
        assert time.monotonic() - t0 < 0.1
        threading.Timer(0.3, (tmp_path / "raster").touch).start()
        t0 = time.monotonic()
        warmup.await_kernels("raster")
        waited = time.monotonic() - t0
        assert 0.25 <= waited < warmup.MAX_WAIT_S
        assert (tmp_path / "raster").exists()
        t0 = time.monotonic()
        warmup.await_kernels("raster")  # awaited before: at once
        assert time.monotonic() - t0 < 0.1
        threading.Timer(0.3, helper.kill).start()  # the helper dies without marking "fill"
        t0 = time.monotonic()
        warmup.await_kernels("fill")
        assert 0.25 <= time.monotonic() - t0 < warmup.MAX_WAIT_S
    finally:
        helper.kill()
        helper.wait()


def test_first_run_refuses_unknown_groups_and_kinds(monkeypatch):
    """A misspelt group or helper kind is an error on every run (not a silent no-wait)."""
    import pytest

    from ibr.base import first_run

    monkeypatch.setattr(first_run, "_STARTED", [])
    with pytest.raises(ValueError, match="group"):
        first_run.await_kernels("rastre")
    with pytest.raises(ValueError, match="kind"):
        first_run.start_helper("frames")
    assert first_run._STARTED == []  # nothing was started for the refused kind


def test_a_forked_child_leaves_the_helper_and_its_marks_alone(tmp_path, monkeypatch):
    """A child forked from the main process (a pool worker) inherits the helper's record and the
    exit hook: it must neither wait for the marks nor remove the parent's marker directory."""
    import time

    from ibr.base import first_run as warmup

    if not hasattr(os, "fork"):
        return
    marks = tmp_path / "marks"
    marks.mkdir()
    helper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    pid = 0
    try:
        monkeypatch.setattr(warmup, "_STARTED", [(helper, marks, warmup.GROUPS["frame"], os.getpid())])
        monkeypatch.setattr(warmup, "_READY", set())
        monkeypatch.setattr(warmup, "MAX_WAIT_S", 60.0)
        pid = os.fork()
        if pid == 0:  # the child: await, then the exit hook as the parent registered it
            try:
                warmup.await_kernels("raster")
                (tmp_path / "returned").touch()
                warmup._stop(helper, marks, warmup._STARTED[0][3])
            finally:
                os._exit(0)
        deadline = time.monotonic() + 30
        while pid and time.monotonic() < deadline:
            if os.waitpid(pid, os.WNOHANG)[0]:
                pid = 0  # reaped
            else:
                time.sleep(0.05)
        assert (tmp_path / "returned").exists()  # did not wait for the parent's helper
        assert marks.is_dir()
        assert helper.poll() is None  # still running: only its owner stops it
    finally:
        if pid:  # a child still waiting after 30 s
            os.kill(pid, 9)
            os.waitpid(pid, 0)
        helper.kill()
        helper.wait()


def test_the_cli_starts_the_helper_before_the_command_runs(monkeypatch, capsys):
    """cli.main asks, quietly, for the first-run helper with the command's kernels before the
    command's own imports and checks (#13: 0.25 s earlier on the first run's critical path): the
    kernels of `ibr interpolate` and of a mesh `ibr warp`, none for a forward-splat warp. The line
    saying so comes from the command's own call, after its input checks (a bad command line
    says nothing of compiling), once; the next command looks at the cache again."""
    import cli
    import commands._common as common
    import commands.interpolate as interpolate
    import commands.warp as warp

    calls, order = [], []
    monkeypatch.setattr(common, "_note_first_run", lambda modules, warm: calls.append((modules, warm)) or True)

    def command(args):
        order.append(("run", len(calls)))
        if args.command == "interpolate":
            common.note_first_run(*interpolate.FRAME_KERNELS, warm="frame")  # after its checks
            common.note_first_run(*interpolate.FRAME_KERNELS, warm="frame")
        return 0

    monkeypatch.setattr(interpolate, "run", command)
    monkeypatch.setattr(warp, "run", command)
    assert cli.main(["interpolate", "--out", "nowhere"]) == 0
    assert calls == [(interpolate.FRAME_KERNELS, "frame")] and order == [("run", 1)]  # asked before it ran
    err = capsys.readouterr().err
    assert err.count("compiling the numba kernels") == 1  # said once, by the command
    assert cli.main(["warp", "a.json", "--to", "b.json", "-o", "x.png", "--method", "forward"]) == 0
    assert len(calls) == 1 and order[-1] == ("run", 1)  # no kernels of the mesh path
    assert cli.main(["warp", "a.json", "--to", "b.json", "-o", "x.png"]) == 0
    assert len(calls) == 2 and order[-1] == ("run", 2)  # a new command looks at the cache again
    assert "compiling" not in capsys.readouterr().err  # the CLI's own ask is quiet


def _numba_index(folder: Path, src: Path, version: str | None = None) -> None:
    """Write the cache index numba writes for function ``f`` of source file ``src`` as it is now
    (numba's own writer and its locator's source stamp, whatever the numba version; ``version``:
    as another numba version would)."""
    import importlib

    import numba.core.caching as caching

    mod = importlib.import_module(".".join(src.relative_to(src.parents[1]).with_suffix("").parts))
    stamp = next(loc for cls in caching.CacheImpl._locator_classes
                 if (loc := cls.from_function(mod.f, str(src))) is not None).get_source_stamp()
    folder.mkdir(parents=True, exist_ok=True)
    index = caching.IndexDataCacheFile(str(folder), f"{src.stem}.f-1.py311", stamp)
    if version is not None:
        index._version = version
    index._save_index({})


def test_kernels_cached_for_another_source_count_as_a_first_run(tmp_path, monkeypatch):
    """A kernel module without a numba cache index numba would load (none, one for an older
    source: an update, one of another numba version) is compiled again, so it counts as a first
    run (helper, and the summary says it compiled); a fresh index does not, and neither does a
    source touched but unchanged (a git checkout: numba stamps the source's bytes, not its time;
    every warm run said "compiling" after one)."""
    import commands._common as common

    pkg = tmp_path / "kpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    src = pkg / "_k_kernels.py"
    src.write_text("def f():\n    return 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert common._stale_kernels("kpkg._k_kernels")  # no index
    cache = pkg / "__pycache__"
    _numba_index(cache, src, version="0.1.0")
    assert common._stale_kernels("kpkg._k_kernels")  # another numba's index
    _numba_index(cache, src)
    assert not common._stale_kernels("kpkg._k_kernels")  # cached for this source
    later = time.time() + 3600
    os.utime(src, (later, later))
    import numba.core.caching as caching

    hashed = hasattr(caching, "_hash_source_file")  # numba >= 0.68 stamps the bytes, older ones (mtime, size)
    assert common._stale_kernels("kpkg._k_kernels") is not hashed  # touched after the index, the same bytes
    st = src.stat()  # an index as numba < 0.68 writes it: fresh while the source keeps its mtime and size
    caching.IndexDataCacheFile(str(cache), "_k_kernels.h-1.py311", (st.st_mtime, st.st_size))._save_index({})
    assert not common._stale_kernels("kpkg._k_kernels")
    src.write_text("def f():\n    return 2\n")
    assert common._stale_kernels("kpkg._k_kernels")  # the source changed since
    (cache / "_k_kernels.g-1.py311.nbi").write_bytes(b"\x80garbage")
    assert common._stale_kernels("kpkg._k_kernels")  # an unreadable index counts for nothing


def test_the_frame_helper_compiles_at_O2_and_the_frames_do_not_change(tmp_path, monkeypatch):
    """start_helper runs the "frame" helper with NUMBA_OPT=2 (its kernels compile faster and run
    as fast; a user's NUMBA_OPT wins; the other helpers keep numba's default), and a frame
    rendered from kernels the O2 helper cached (the rasterizer, the fill) is
    bit-identical to one whose kernels were all compiled at the default level."""
    import ibr.base.first_run as fr

    seen = []

    class FakeProc:
        def __init__(self, argv, env=None, **kw):
            seen.append((argv[3], env.get("NUMBA_OPT") if env else None))
            shutil.rmtree(argv[4], ignore_errors=True)  # the marks folder start_helper made

        def poll(self):
            return 0

    with monkeypatch.context() as m:  # subprocess.Popen itself: undone before the real runs below
        m.setattr(fr.subprocess, "Popen", FakeProc)
        m.setattr(fr, "atexit", type("NoAtexit", (), {"register": staticmethod(lambda *a: None)}))
        for name in ("NUMBA_OPT", "IBR_NO_WARMUP", "NUMBA_DISABLE_JIT"):
            m.delenv(name, raising=False)
        for kind, user in (("frame", None), ("frame", "3"), ("stitch", None), ("mesh", None)):
            m.setattr(fr, "_STARTED", [])
            if user:
                m.setenv("NUMBA_OPT", user)
            fr.start_helper(kind)
            m.delenv("NUMBA_OPT", raising=False)
    assert seen == [("frame", "2"), ("frame", "3"), ("stitch", None), ("mesh", None)]

    render = ("import numpy as np, sys\n"
              "from ibr.io import load_view\n"
              "from ibr.render.view_synthesis import interpolate\n"
              "from samples import DATA_DIR\n"
              "a, b = load_view(DATA_DIR / 'clutter_a.json'), load_view(DATA_DIR / 'clutter_b.json')\n"
              "g = load_view(DATA_DIR / 'clutter_t075.json')\n"
              "r = interpolate(a, b, g.camera, fill='inpaint')\n"
              "np.savez(sys.argv[1], c=r.color, z=r.depth)\n")
    outs = []
    for name, helper_opt in (("o2", "2"), ("o3", None)):
        env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / name), "PYTHONPATH": str(ROOT), "IBR_NO_WARMUP": "1"}
        env.pop("NUMBA_OPT", None)
        if helper_opt:
            marks = tmp_path / f"marks-{name}"
            marks.mkdir()
            subprocess.run([sys.executable, "-m", "ibr.render.warmup", "frame", str(marks)],
                           env={**env, "NUMBA_OPT": helper_opt}, check=True, timeout=300)
        out = tmp_path / f"{name}.npz"
        compiled = _kernels_compiled_by(render.replace("sys.argv[1]", repr(str(out))), env)
        if helper_opt:  # the render loaded the helper's -O2 kernels (it compiled none of them)
            assert not [k for k in compiled if k.startswith(("_raster_kernels", "_fill_kernels"))]
        outs.append(np.load(out))
    assert np.array_equal(outs[0]["c"], outs[1]["c"])
    assert np.array_equal(outs[0]["z"], outs[1]["z"], equal_nan=True)


@pytest.mark.parametrize("argv", [["interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/o"],
                                  ["warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.png"],
                                  ["mesh", "{d}/a.json", "--obj", "{d}/m.obj"]])
def test_a_first_run_with_a_missing_input_says_only_the_error(tmp_path, monkeypatch, capsys, argv):
    """On a first run (kernels to compile) a command whose input is missing prints its error and
    nothing about compiling: the line comes after the inputs are read."""
    import cli
    import commands._common as common

    monkeypatch.setattr(common, "_note_first_run", lambda modules, warm: True)
    assert cli.main([a.format(d=tmp_path) for a in argv]) == 1
    err = capsys.readouterr().err
    assert "file not found" in err and "compiling" not in err


def test_a_sequence_interpolation_says_it_compiles(tmp_path, monkeypatch, capsys):
    """`ibr interpolate SEQ --factor F` on a first run: cli.main starts the helper quietly and the
    sequence path says it compiles once its first key is read (it said nothing)."""
    import cli
    import commands._common as common
    from ibr.io import load_view
    from ibr.sequence.files import save_sequence
    from samples import DATA_DIR

    views = [load_view(DATA_DIR / "room_a.json"), load_view(DATA_DIR / "room_b.json")]
    seq = save_sequence(views, tmp_path / "walk.json", fps=10)
    monkeypatch.setattr(common, "_note_first_run", lambda modules, warm: True)
    assert cli.main(["interpolate", str(seq), "--factor", "2", "--out", str(tmp_path / "f")]) == 0
    assert capsys.readouterr().err.count("compiling the numba kernels") == 1


def test_the_first_run_check_looks_where_numba_caches(tmp_path, monkeypatch):
    """The kernel cache folder is numba's own choice (tests compare with its locators): under
    NUMBA_CACHE_DIR the folder named after this checkout's module folder (another checkout's
    index there does not count), ``__pycache__`` when it is usable, else the user-wide folder
    (an index there counted for nothing: every warm run started the helper and said compiling)."""
    import hashlib

    import commands._common as common
    import numba.core.caching as caching

    pkg = tmp_path / "kpkg2"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    src = pkg / "_k_kernels.py"
    src.write_text("def f():\n    return 1\n")
    os.utime(src, (1_000_000, 1_000_000))
    monkeypatch.syspath_prepend(str(tmp_path))

    def numba_choice():
        import importlib

        mod = importlib.import_module("kpkg2._k_kernels")
        for cls in caching.CacheImpl._locator_classes:
            loc = cls.from_function(mod.f, mod.__file__)
            if loc is not None:
                return Path(loc.get_cache_path())

    cache = tmp_path / "nbcache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    import numba

    numba.config.reload_config()
    try:
        assert common._numba_cache_dir(src) == numba_choice()
        other = cache / f"kpkg2_{hashlib.sha1(b'/elsewhere/kpkg2').hexdigest()}"
        other.mkdir(parents=True)
        _numba_index(other, src)
        assert common._stale_kernels("kpkg2._k_kernels")  # another checkout's index
        _numba_index(common._numba_cache_dir(src), src)
        assert not common._stale_kernels("kpkg2._k_kernels")
    finally:
        monkeypatch.delenv("NUMBA_CACHE_DIR")
        numba.config.reload_config()
    assert common._numba_cache_dir(src) == numba_choice() == pkg / "__pycache__"
    shutil.rmtree(pkg / "__pycache__", ignore_errors=True)
    (pkg / "__pycache__").write_text("not a folder")  # in-tree unusable: numba goes user-wide
    user_wide = numba_choice()  # numba made this folder to test it: remove it again
    try:
        assert common._numba_cache_dir(src) == user_wide != pkg / "__pycache__"
    finally:
        shutil.rmtree(user_wide, ignore_errors=True)


def test_a_first_run_with_a_view_without_depth_says_only_the_error(tmp_path, monkeypatch, capsys):
    """A view file without depth is refused before any kernel runs; on a first run the command
    said "compiling" first."""
    import cli
    import commands._common as common
    from ibr.io import load_view, save_view
    from ibr.base.view import View
    from samples import DATA_DIR

    v = load_view(DATA_DIR / "room_a.json")
    save_view(View(v.color, None, v.camera, "flat"), tmp_path / "flat.json")
    monkeypatch.setattr(common, "_note_first_run", lambda modules, warm: True)
    code = cli.main(["warp", str(tmp_path / "flat.json"), "--to", str(DATA_DIR / "room_b.json"), "-o",
                     str(tmp_path / "o.png")])
    err = capsys.readouterr().err
    assert code == 1 and "depth" in err and "compiling" not in err
