"""Regressions from a new-user audit of the command line: each bad input ends in a one-line error
naming the argument (exit 1), nothing is written, and no option is silently ignored."""

import json
from pathlib import Path

import pytest

import cli

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "samples" / "data"


def _error_line(capsys, command):
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith(f"ibr {command}: error:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("extra", [["--report", "r.json"], ["--factor", "3"], ["--no-tail"],
                                   ["--truth", str(DATA / "room_t050.json")]])
def test_interpolate_pair_refuses_sequence_options(tmp_path, capsys, extra):
    """A pair used to ignore --report/--factor/--no-tail/--truth silently (exit 0, no report)."""
    extra = [str(tmp_path / e) if e == "r.json" else e for e in extra]
    out = tmp_path / "frames"
    code = cli.main(["interpolate", str(DATA / "room_a.json"), str(DATA / "room_b.json"), "--t", "0.5",
                     "--out", str(out), *extra])
    assert code == 1
    line = _error_line(capsys, "interpolate")
    assert f"error: {extra[0]}: only used with a sequence" in line
    assert not out.exists() and not (tmp_path / "r.json").exists()


def test_interpolate_bundled_pair_refuses_report(tmp_path, capsys):
    assert cli.main(["interpolate", "--out", str(tmp_path / "o"), "--report", str(tmp_path / "r.json")]) == 1
    assert "error: --report: only used with a sequence" in _error_line(capsys, "interpolate")
    assert list(tmp_path.iterdir()) == []


def test_timewarp_poses_not_text_names_the_option(tmp_path, capsys):
    """A JPEG (not UTF-8) given as --poses used to give a bare codec error."""
    poses = tmp_path / "poses.json"
    poses.write_bytes(b"\xff\xd8\xff\xe0" + bytes(range(256)))
    out = tmp_path / "frames"
    assert cli.main(["timewarp", str(DATA / "room_a.json"), "--poses", str(poses), "-o", str(out)]) == 1
    line = _error_line(capsys, "timewarp")
    assert line.startswith(f"ibr timewarp: error: --poses: {poses} is not valid JSON")
    assert not out.exists()
