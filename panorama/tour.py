"""Tours: several panoramas in one viewer site, linked by hotspots (issue #18).

A tour file (JSON) names its scenes and their panoramas, relative to the tour file::

    {"first": "hall",
     "scenes": {
       "hall":    {"panorama": "hall.jpg", "title": "Hall", "yaw": 0, "pitch": 0, "fov": 90,
                   "hotspots": [{"yaw": 35, "pitch": -5, "scene": "kitchen"},
                                {"yaw": -60, "pitch": 10, "label": "Painting, 1890"}]},
       "kitchen": {"panorama": "kitchen.jpg", "hotspots": [{"yaw": 200, "pitch": 0, "scene": "hall"}]}}}

Angles in degrees, the viewer's convention (yaw = longitude, 0 = +z, 90 = +x; pitch = latitude,
+90 up). :func:`load_tour` checks it strictly (unknown keys with the nearest valid name, hotspots
at impossible angles, links to scenes the tour does not have); :func:`write_tour_site` writes the
page, ``viewer.json`` and each scene's faces as ``scene-<id>-px.png`` .. ``scene-<id>-nz.png``.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from ibr.base.validate import check_keys, nearest_name

__all__ = ["SCENE_KEYS", "HOTSPOT_KEYS", "load_tour", "write_tour_site"]

TOUR_KEYS = ("first", "scenes")
SCENE_KEYS = ("panorama", "title", "yaw", "pitch", "fov", "hotspots", "layout")
HOTSPOT_KEYS = ("yaw", "pitch", "scene", "label")
_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")


def _angle(where: str, value, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where}: expected a number of degrees, got {value!r}")
    if not lo <= value <= hi:
        raise ValueError(f"{where}: {value} is an impossible angle (expected {lo:g}..{hi:g} degrees)")
    return float(value)


def load_tour(path) -> dict:
    """The checked tour: ``{"first": id, "scenes": {id: {..., "panorama": Path}}}``."""
    from ibr.io.view_files import read_json

    path = Path(path)
    doc = read_json(path, "tour")
    where = f"tour {path.name}"
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: expected an object with 'scenes'")
    check_keys(where, doc, TOUR_KEYS)
    scenes = doc.get("scenes")
    if not isinstance(scenes, dict) or not scenes:
        raise ValueError(f"{where}: 'scenes' must be a non-empty object of scene id -> scene")
    out = {}
    for sid, sc in scenes.items():
        sw = f"{where}: scene {sid!r}"
        if not _ID.match(str(sid)):
            raise ValueError(f"{sw}: ids are letters, digits, '_' and '-' (up to 64)")
        if not isinstance(sc, dict):
            raise ValueError(f"{sw}: expected an object")
        check_keys(sw, sc, SCENE_KEYS)
        if not isinstance(sc.get("panorama"), str):
            raise ValueError(f"{sw}: 'panorama' (an image file, relative to the tour file) is required")
        pano = path.parent / sc["panorama"]
        if not pano.exists():
            raise FileNotFoundError(f"{sw}: 'panorama' refers to a missing file {pano}")
        s = {"panorama": pano, "title": str(sc.get("title", sid)), "layout": sc.get("layout"),
             "yaw": _angle(f"{sw}: 'yaw'", sc.get("yaw", 0.0), -360, 360),
             "pitch": _angle(f"{sw}: 'pitch'", sc.get("pitch", 0.0), -90, 90),
             "fov": _angle(f"{sw}: 'fov'", sc.get("fov", 90.0), 1, 179), "hotspots": []}
        spots = sc.get("hotspots", [])
        if not isinstance(spots, list):
            raise ValueError(f"{sw}: 'hotspots' must be a list")
        for k, h in enumerate(spots):
            hw = f"{sw}: hotspot {k}"
            if not isinstance(h, dict):
                raise ValueError(f"{hw}: expected an object")
            check_keys(hw, h, HOTSPOT_KEYS)
            if ("scene" in h) == ("label" in h):
                raise ValueError(f"{hw}: give either 'scene' (a link) or 'label' (a text)")
            spot = {"yaw": _angle(f"{hw}: 'yaw'", h.get("yaw"), -360, 360),
                    "pitch": _angle(f"{hw}: 'pitch'", h.get("pitch"), -90, 90)}
            if "scene" in h:
                spot["scene"] = h["scene"]
            else:
                spot["label"] = str(h["label"])
            s["hotspots"].append(spot)
        out[sid] = s
    for sid, s in out.items():  # every link leads somewhere
        for k, h in enumerate(s["hotspots"]):
            if "scene" in h and h["scene"] not in out:
                near = nearest_name(str(h["scene"]), out)
                raise ValueError(f"{where}: scene {sid!r} hotspot {k} links to scene {h['scene']!r}, which the tour "
                                 f"does not have{f' (did you mean {near!r}?)' if near else ''}")
    first = doc.get("first", next(iter(out)))
    if first not in out:
        near = nearest_name(str(first), out)
        raise ValueError(f"{where}: 'first' is {first!r}, which the tour does not have"
                         f"{f' (did you mean {near!r}?)' if near else ''}")
    return {"first": first, "scenes": out}


def write_tour_site(folder, tour_path, *, face_size: int | None = None, force: bool = False) -> Path:
    """Write the viewer page, ``viewer.json`` with the tour, and ``scene-<id>-px.png..nz.png``
    for every scene into ``folder`` (new or empty unless ``force``); return the page's path.
    Every scene is read and converted before anything is written."""
    from .files import read_panorama
    from .viewer import MAX_FACE_SIZE, _faces, check_site_folder, copy_page
    from ibr.io import write_image

    if face_size is not None and face_size > MAX_FACE_SIZE:  # as write_site without tiles
        raise ValueError(f"face_size: {face_size} px faces exceed what phones and many GPUs show "
                         f"({MAX_FACE_SIZE} px per cube face); choose --face-size <= {MAX_FACE_SIZE}")
    tour = load_tour(tour_path)
    folder = check_site_folder(folder, force=force)
    faces = {}
    for sid, s in tour["scenes"].items():
        pano, layout = read_panorama(s["panorama"], layout=s["layout"])
        faces[sid] = _faces(pano, layout, face_size)
    folder.mkdir(parents=True, exist_ok=True)
    scenes = {}
    for sid, s in tour["scenes"].items():
        for name, face in zip(("px", "nx", "py", "ny", "pz", "nz"), faces[sid]):
            write_image(folder / f"scene-{sid}-{name}.png", face)
        scenes[sid] = {"title": s["title"], "faces": f"scene-{sid}-", "yaw": s["yaw"], "pitch": s["pitch"],
                       "fov": s["fov"], "hotspots": s["hotspots"]}
    (folder / "viewer.json").write_text(json.dumps({"stereo": False, "tour": {"first": tour["first"],
                                                                            "scenes": scenes}}, indent=1) + "\n")
    return copy_page(folder)
