"""Generic CLI behaviour (help, exit codes 0/1/2) and the ``samples`` command."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cli
from ibr.io import load_view

ROOT = Path(__file__).resolve().parents[1]


def test_top_level_help_and_usage_errors(capsys):
    assert cli.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "samples" in out and "usage: ibr" in out
    assert cli.main([]) == 2  # no command: usage on stderr
    assert "usage: ibr" in capsys.readouterr().err
    assert cli.main(["no-such-command"]) == 2
    assert "invalid choice" in capsys.readouterr().err


def test_every_available_command_has_help(capsys):
    names = [name for name, _ in cli._available_commands()]
    assert "samples" in names
    for name in names:
        assert cli.main([name, "--help"]) == 0, name
        assert f"usage: ibr {name}" in capsys.readouterr().out


def test_usage_error_is_2_and_runtime_error_is_1(tmp_path, capsys):
    assert cli.main(["samples", "--bogus"]) == 2
    assert "unrecognized arguments: --bogus" in capsys.readouterr().err
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert cli.main(["samples", "--out", str(blocker)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("ibr samples: error: --out:") and "is not a folder" in err
    assert blocker.read_text() == "x"  # the input was not touched


def test_entry_point_exit_codes_in_a_subprocess(tmp_path):
    run = lambda *a: subprocess.run([sys.executable, str(ROOT / "cli.py"), *a], capture_output=True,  # noqa: E731
                                    text=True, cwd=tmp_path)
    assert run("--help").returncode == 0
    bad = run("samples", "--out")
    assert bad.returncode == 2 and "expected one argument" in bad.stderr


def test_console_command_skips_teardown_but_flushes_and_runs_exit_handlers(tmp_path):
    """``cli.run`` (the ``ibr`` command) ends with os._exit after main (#13: the interpreter's
    teardown cost 0.25-0.4 s): the exit code is main's, piped output is complete, atexit handlers
    (the first-run helper's cleanup) have run; IBR_FULL_EXIT=1 exits the ordinary way."""
    marker = tmp_path / "handler_ran"
    code = ("import atexit, sys, cli; sys.path.insert(0, {root!r}); "
            "atexit.register(lambda: open({marker!r}, 'w').write('yes')); cli.run({argv!r})")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}  # block-buffered pipes
    env["PYTHONPATH"] = str(ROOT)
    for full_exit in ("", "1"):
        for argv, rc in ((["--help"], 0), (["mesh", str(tmp_path / "missing.json")], 1), (["nope"], 2)):
            marker.unlink(missing_ok=True)
            out = subprocess.run([sys.executable, "-c", code.format(root=str(ROOT), marker=str(marker), argv=argv)],
                                 capture_output=True, text=True, cwd=tmp_path, env={**env, "IBR_FULL_EXIT": full_exit})
            assert out.returncode == rc, (argv, out.stderr)
            assert marker.read_text() == "yes"
            if rc == 0:  # stdout is a pipe (block-buffered): all of the help arrived
                assert out.stdout.rstrip().endswith(cli.build_parser().format_help().rstrip().splitlines()[-1])
            elif rc == 1:
                assert out.stderr.startswith("ibr mesh: error:") and "missing.json" in out.stderr
    # started with stdout closed (sys.stdout is None): still main's code, no traceback
    closed = subprocess.run([sys.executable, "-c", code.format(root=str(ROOT), marker=str(marker), argv=["--help"])],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env,
                            pass_fds=(), preexec_fn=lambda: os.close(1))
    assert closed.returncode == 0 and "Traceback" not in closed.stderr, closed.stderr


@pytest.fixture(scope="module")
def samples_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("samples") / "out"
    assert cli.main(["samples", "--out", str(out)]) == 0
    return out


def test_samples_writes_the_middlebury_pair(samples_dir):
    from ibr.io.middlebury import motorcycle_views

    left, right = motorcycle_views()
    a, b = load_view(samples_dir / "motorcycle_left.json"), load_view(samples_dir / "motorcycle_right.json")
    np.testing.assert_array_equal(a.color, left.color)
    np.testing.assert_array_equal(b.color, right.color)
    np.testing.assert_array_equal(np.isnan(a.depth), np.isnan(left.depth))
    np.testing.assert_allclose(a.depth, left.depth, rtol=1e-6)  # via the disparity PFM
    assert b.depth is None and a.camera.allclose(left.camera) and b.camera.allclose(right.camera)
    doc = json.loads((samples_dir / "motorcycle_left.json").read_text())
    assert doc["depth"]["encoding"] == "disparity" and doc["depth"]["doffs"] == 31.086


def test_samples_copies_every_bundled_view(samples_dir):
    from samples import DATA_DIR

    bundled = sorted(p.name for p in DATA_DIR.glob("*.json") if json.loads(p.read_text()).get("format") == "ibr-view")
    for name in bundled:
        assert "_" in Path(name).stem, f"{name}: expected <scene>_<view>.json"
        src, dst = load_view(DATA_DIR / name), load_view(samples_dir / name)
        np.testing.assert_array_equal(dst.color, src.color)
        assert dst.camera.allclose(src.camera, atol=0)
        if src.depth is None:
            assert dst.depth is None
        else:
            np.testing.assert_array_equal(dst.depth, src.depth)
    names = {p.name for p in samples_dir.glob("*.json")}
    extra = {"manifest.json"} if (DATA_DIR / "manifest.json").is_file() else set()
    assert names == set(bundled) | {"motorcycle_left.json", "motorcycle_right.json"} | extra
    assert not [p for p in samples_dir.rglob(".*")]  # no temporary files left behind


def test_samples_copies_the_rig_and_it_stitches(samples_dir):
    """The bundled rig lands in ``--out``/rig byte for byte (views, rig.json, the centre panorama),
    and its views load and stitch from there as from samples/data/rig."""
    from samples import DATA_DIR

    bundled = sorted(p.name for p in (DATA_DIR / "rig").iterdir() if p.is_file())
    assert sorted(p.name for p in (samples_dir / "rig").iterdir()) == bundled
    for name in bundled:
        assert (samples_dir / "rig" / name).read_bytes() == (DATA_DIR / "rig" / name).read_bytes(), name
    views = sorted((samples_dir / "rig").glob("rig_*.json"))
    assert len(views) == len(json.loads((DATA_DIR / "rig" / "rig.json").read_text())["views"]) == 10
    out = samples_dir.parent / "pano.png"
    assert cli.main(["stitch", str(samples_dir / "rig"), "-o", str(out), "--width", "64", "--depth-out", "none"]) == 0
    assert out.is_file()  # the copied rig folder is a rig: its views and centre


def test_samples_rerun_replaces_and_refuses_its_own_data_folder(samples_dir, capsys):
    assert cli.main(["samples", "--out", str(samples_dir), "--no-middlebury"]) == 0
    from samples import DATA_DIR

    assert cli.main(["samples", "--out", str(DATA_DIR)]) == 1
    assert "bundled data folder itself" in capsys.readouterr().err


def test_counted_says_one_frame_and_two_frames():
    from commands._common import counted

    assert [counted(n, "frame") for n in (0, 1, 2)] == ["0 frames", "1 frame", "2 frames"]
