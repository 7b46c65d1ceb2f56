"""The stage layout (docs/architecture.md): public names and their homes, and the import rules."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Which stages each stage may import (docs/architecture.md, "Rules"). "ibr._lazy" is the
# package plumbing every __init__ uses and belongs to no stage.
ALLOWED = {
    "ibr.base": set(),
    "ibr.mesh": {"ibr.base"},
    "ibr.render": {"ibr.base", "ibr.mesh"},
    "ibr.stereo": {"ibr.base", "ibr.mesh", "ibr.render"},
    "ibr.synth": {"ibr.base"},
    "ibr.io": {"ibr.base", "ibr.mesh"},
    "ibr.canvas": {"ibr.base", "ibr.mesh", "ibr.render"},
    "ibr.sequence": {"ibr.base", "ibr.mesh", "ibr.render", "ibr.stereo", "ibr.io"},
    "panorama": {"ibr.base", "ibr.mesh", "ibr.render", "ibr.stereo", "ibr.synth", "ibr.io", "ibr.canvas"},
}

# Public names -> the module that defines them. The README and docs show these.
PUBLIC = {
    "ibr.Camera": "ibr.base.camera",
    "ibr.look_at": "ibr.base.camera",
    "ibr.interpolate_cameras": "ibr.base.camera",
    "ibr.camera_from_gl_projection": "ibr.base.camera",
    "ibr.gl_frustum_from_projection": "ibr.base.camera",
    "ibr.View": "ibr.base.view",
    "ibr.load_view": "ibr.io.view_files",
    "ibr.save_view": "ibr.io.view_files",
    "ibr.read_image": "ibr.io.images",
    "ibr.write_image": "ibr.io.images",
    "ibr.read_depth": "ibr.io.images",
    "ibr.write_depth": "ibr.io.images",
    "ibr.build_mesh": "ibr.mesh.quad_mesh",
    "ibr.QuadMesh": "ibr.mesh.quad_mesh",
    "ibr.warp": "ibr.render.view_synthesis",
    "ibr.interpolate": "ibr.render.view_synthesis",
    "ibr.Rendering": "ibr.render.rendering",
    "ibr.io.atomic_path": "ibr.io.images",
    "ibr.io.write_obj": "ibr.io.mesh_files",
    "ibr.render.render_mesh": "ibr.render.rasterize",
    "ibr.render.iter_interpolate": "ibr.render.view_synthesis",
    "ibr.stereo.StereoCamera": "ibr.stereo.stereo_camera",
    "ibr.stereo.auto_stereo": "ibr.stereo.stereo_camera",
    "ibr.stereo.stereo_pair": "ibr.stereo.pair",
    "ibr.stereo.predistort": "ibr.stereo.lens",
    "ibr.stereo.upconvert": "ibr.stereo.timewarp",
    "ibr.synth.make_scene": "ibr.synth.scenes",
    "ibr.synth.render": "ibr.synth.scene",
    "ibr.synth.render_rays": "ibr.synth.scene",
    "panorama.perspective": "panorama.convert",
    "panorama.equirect_to_cubemap": "panorama.convert",
    "panorama.cubemap_to_equirect": "panorama.convert",
    # modules that were top-level before the layout keep working as attributes
    "ibr.depth.z_from_disparity": "ibr.base.depth",
    "ibr.lens.predistort": "ibr.stereo.lens",
    "ibr.timewarp.timewarp": "ibr.stereo.timewarp",
    "ibr.stereo_pair.stereo_pair": "ibr.stereo.pair",
    "ibr.middlebury.motorcycle_views": "ibr.io.middlebury",
}


def _resolve(dotted: str):
    parts = dotted.split(".")
    obj = importlib.import_module(parts[0])
    for p in parts[1:]:
        obj = getattr(obj, p)
    return obj


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_public_name_has_its_home(name):
    obj = _resolve(name)
    assert obj.__module__ == PUBLIC[name]


def _stage(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] == "panorama":
        return "panorama"
    if parts[0] == "ibr" and len(parts) > 1 and f"ibr.{parts[1]}" in ALLOWED:
        return f"ibr.{parts[1]}"
    return None


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path: Path):
    """Every module a file imports (module level and inside functions), absolute names."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            yield mod
            for alias in node.names:  # `from ibr.render import composite` names a module too
                yield f"{mod}.{alias.name}"


def _stage_files():
    for top in ("ibr", "panorama"):
        yield from sorted((ROOT / top).rglob("*.py"))


def test_every_ibr_module_lives_in_a_stage():
    loose = [p.name for p in (ROOT / "ibr").glob("*.py") if p.name not in ("__init__.py", "_lazy.py")]
    assert loose == []


def test_stages_import_only_the_stages_below_them():
    bad = []
    for path in _stage_files():
        here = _stage(_module_name(path))
        if here is None:
            continue
        for mod in _imports(path):
            there = _stage(mod)
            if there is None or there == here:
                continue
            if there not in ALLOWED[here]:
                bad.append(f"{path.relative_to(ROOT)} ({here}) imports {mod} ({there})")
    assert bad == []


def test_the_rules_are_the_ones_documented():
    """docs/architecture.md states the same table the test enforces."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    for stage, allowed in ALLOWED.items():
        line = next((ln for ln in text.splitlines() if ln.startswith(f"| `{stage}` ")), None)
        assert line is not None, stage
        cells = line.split("|")[2]
        named = {c.strip().strip("`") for c in cells.split(",") if c.strip() and c.strip() != "—"}
        assert named == allowed, (stage, named)


def test_the_import_check_sees_a_violation(tmp_path):
    """The checker is not blind: a render module importing ibr.io is reported."""
    fake = ROOT / "ibr" / "render" / "_layout_probe.py"
    assert not fake.exists()
    fake.write_text("from ..io import read_image\n")
    try:
        mods = set(_imports(fake))
        assert "ibr.io" in mods and _stage("ibr.io") not in ALLOWED["ibr.render"]
    finally:
        fake.unlink()
