"""Conversions between equirectangular images, cubemaps and perspective views.

Conventions (written once in :mod:`panorama.directions`): frame x right, y down, z forward;
equirect longitude 0 = +z at the image centre, growing toward +x (right), latitude positive up
(-y); pixel centres at integer coordinates, e.g. in a 4096 x 2048 equirect +z is at
(u, v) = (2047.5, 1023.5). Faces +x -x +y -y +z -z (+y is the floor) in the orientation table
``WORLD_FROM_FACE``; layouts in :mod:`panorama.layouts`.

Sampling: bilinear (``interpolation="linear"``, default for color) or nearest (default for
depth, so that no depth is invented between a foreground and a background surface), with
seam-free padding on both the equirect and the cube side, and ``cv2.INTER_AREA`` pre-filtering
of the source when the output is more than 1.5x coarser than it (color only).

Depth (``depth=True``): equirect images hold range along the ray, cube faces hold planar z for
their own face, perspective views planar z for the view; every conversion converts exactly at
the sample (see :mod:`panorama.depth`).
"""

from __future__ import annotations

import math

import numpy as np

from ibr.base.validate import check_choice, check_finite_scalar, check_image, check_image_size

from . import maps as _maps
from .depth import face_ray_lengths, planar_from_range, range_from_planar
from .layouts import DICE_EMPTY_MAX_SPREAD, LAYOUTS, canonical_layout, dice_unused_spread, layout_faces, \
    unpack_faces
from .sampling import INTERPOLATIONS, area_prefilter, pad_equirect, pad_faces, remap

__all__ = ["cubemap_to_equirect", "equirect_to_cubemap", "perspective", "detect_layout",
           "check_equirect"]


def _check_size(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


def check_equirect(name: str, image, *, depth: bool = False) -> np.ndarray:
    """Check an equirectangular image: exactly 2:1 (W = 2H); a 2-D float map for depth."""
    img = check_image(name, image)
    h, w = img.shape[:2]
    if w != 2 * h:
        raise ValueError(
            f"{name}: an equirectangular image must be 2:1 (width = 2 x height), "
            f"got {w} x {h} (shape {img.shape})"
        )
    if depth:
        img = _depth_array(name, img)
    return img


def _depth_array(name: str, img: np.ndarray) -> np.ndarray:
    if img.ndim == 3:
        if img.shape[2] != 1:
            raise ValueError(f"{name}: depth must have one channel, got shape {img.shape}")
        img = img[..., 0]
    if img.dtype.kind != "f":
        raise ValueError(f"{name}: depth must be float (range or planar z), got dtype {img.dtype}")
    with np.errstate(invalid="ignore"):
        negative = img < 0
    if negative.any():  # (#12) would become negative planar z in the faces
        raise ValueError(f"{name}: depth must be positive (NaN = no depth), got {int(negative.sum())} negative "
                         f"value(s), min {float(np.min(img[negative])):.6g}")
    out = img.astype(np.float32, copy=True)
    with np.errstate(invalid="ignore"):  # 0 and inf are no depth, as in a View (they came out as depth)
        out[~((out > 0) & (out < np.inf))] = np.nan
    return out


def _interp(interpolation, depth: bool) -> str:
    if interpolation is None:
        return "nearest" if depth else "linear"
    return check_choice("interpolation", interpolation, INTERPOLATIONS)


def equirect_to_cubemap(image, face_size: int, *, layout: str = "dict", depth: bool = False,
                        interpolation: str | None = None):
    """Cube faces of an equirectangular image.

    Parameters
    ----------
    image : (H, 2H[, C]) array
        Equirect image (uint8, uint16 or float); with ``depth=True`` a (H, 2H) float range map.
        Pixel (u, v) centre at integers; lon = ((u + 0.5) / W - 0.5) * 360 deg, so for W = 4096
        column 2048's centre looks 0.044 deg right of +z.
    face_size : int
        Face edge S in pixels; face pixel (i, j) looks along right*a + down*b + forward with
        a = 2 (i + 0.5) / S - 1 (e.g. S = 512: i = 0 is a = -0.998).
    layout : {'dict', 'list', 'horizon', 'vstrip', 'dice'}
        Output arrangement (:mod:`panorama.layouts`).
    depth : bool
        Input is range along the ray; output faces hold planar z of each face.
    interpolation : {'linear', 'nearest'}, optional
        Default 'linear' for color, 'nearest' for depth.

    Returns
    -------
    Faces in ``layout`` with the input's dtype (float32 for depth).
    """
    img = check_equirect("image", image, depth=depth)
    s = _check_size("face_size", face_size)
    check_image_size("face_size", s, 6 * s, channels=4)  # six faces, before allocating (#12)
    layout = canonical_layout(layout)
    interp = _interp(interpolation, depth)
    out_dtype = np.float32 if depth else img.dtype
    h, w = img.shape[:2]
    if not depth:
        img = area_prefilter(img, w / (math.pi * s))  # face-centre texel 2/S vs 2 pi / W
        h, w = img.shape[:2]
    baked = layout in ("horizon", "vstrip") and not depth
    smap = _maps.cube_face_map(layout if baked else "list", s, h, w)
    src = pad_equirect(img) if smap.pad else img
    out = remap(src, smap, interpolation=interp, out_dtype=out_dtype)
    if baked:
        return out
    stack = out.reshape((6, s, s) + out.shape[2:])
    if depth:
        stack = planar_from_range(stack, face_ray_lengths(s))
    return layout_faces(stack, layout)


def cubemap_to_equirect(cube, width: int, height: int, *, layout: str = "dict",
                        depth: bool = False, interpolation: str | None = None) -> np.ndarray:
    """Equirectangular image (height, width = 2 height) from cube faces.

    ``cube`` is in ``layout`` (see :func:`equirect_to_cubemap`); with ``depth=True`` faces hold
    planar z and the result holds range. Bilinear samples near a face edge or corner blend
    texels of the neighbouring faces (padded atlas), so there is no seam. Output pixel (u, v)
    centre at integers: for width 4096, u = 3071 looks 0.044 deg left of +x.
    """
    faces = unpack_faces(cube, layout)
    width = _check_size("width", width)
    height = _check_size("height", height)
    if width != 2 * height:
        raise ValueError(f"width, height: an equirectangular image must be 2:1 (width = 2 x "
                         f"height), got {width} x {height}")
    check_image_size("width, height", width, height, channels=4)  # before allocating (#12)
    interp = _interp(interpolation, depth)
    s = faces[0].shape[0]
    out_dtype = faces[0].dtype
    if depth:
        lengths = face_ray_lengths(s)
        faces = [range_from_planar(_depth_array(f"cube face {i}", f), lengths[i])
                 for i, f in enumerate(faces)]
        out_dtype = np.float32
    else:
        ratio = math.pi * s / width  # equator texel 2 pi / W vs face-centre texel 2 / S
        faces = [area_prefilter(f, ratio) for f in faces]
        s = faces[0].shape[0]
    atlas = pad_faces(faces, interpolation=interp, dtype=np.float32 if depth else None)
    smap = _maps.equirect_map(width, height, "cube", s)
    return remap(atlas, smap, interpolation=interp, out_dtype=out_dtype)


def detect_layout(pano) -> str:
    """'equirect' or a cube layout from the type and shape of ``pano``.

    Parameters
    ----------
    pano : array, list or dict
        list -> 'list', dict -> 'dict'; arrays: 2:1 -> 'equirect', 6:1 -> 'horizon',
        1:6 -> 'vstrip', 4:3 -> 'dice' when its six unused cells are empty (one uniform colour,
        :func:`panorama.layouts.dice_unused_spread` at most ``DICE_EMPTY_MAX_SPREAD``): a 4:3
        photo of 512 x 384 is refused, the project's own dice images are not.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        No layout fits the shape, or a 4:3 image has picture content in the unused cells (the
        message says how to force ``layout='dice'``).
    """
    if isinstance(pano, (list, tuple)):
        return "list"
    if isinstance(pano, dict):
        return "dict"
    img = check_image("pano", pano)
    h, w = img.shape[:2]
    for name, ok in (("equirect", w == 2 * h), ("horizon", w == 6 * h), ("vstrip", h == 6 * w),
                     ("dice", 3 * w == 4 * h)):
        if ok:
            if name == "dice":
                _check_dice_cells_empty(img)
            return name
    raise ValueError(
        f"pano: cannot tell the layout of a {w} x {h} image; expected 2:1 (equirect), 6:1 "
        f"(horizon), 1:6 (vstrip) or 4:3 (dice), or pass layout="
    )


def _check_dice_cells_empty(img: np.ndarray) -> None:
    """Refuse a 4:3 image whose unused dice cells hold picture content (an ordinary photo)."""
    h, w = img.shape[:2]
    spread = dice_unused_spread(img)  # 3 w = 4 h: h is a multiple of 3
    if spread > DICE_EMPTY_MAX_SPREAD:
        raise ValueError(
            f"pano: a {w} x {h} (4:3) image is read as a dice cubemap only when its six unused cells are "
            f"empty (one uniform colour); here they vary {spread:.2f} times as much as the faces (at most {DICE_EMPTY_MAX_SPREAD:g}), so it "
            f"looks like an ordinary picture. To read it as a dice anyway, give the layout: layout='dice' "
            f"(ibr cubemap --input-layout dice, ibr view --layout dice)")


def perspective(pano, *, yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0,
                fov_deg: float, width: int, height: int, layout: str | None = None,
                depth: bool = False, interpolation: str | None = None) -> np.ndarray:
    """Pinhole view of an equirect image or a cubemap.

    Parameters
    ----------
    pano : array, list or dict
        Equirect image (2:1) or cubemap in any layout (auto-detected from the shape unless
        ``layout`` is given; ``layout='equirect'`` forces equirect).
    yaw_deg, pitch_deg, roll_deg : float
        View direction: yaw = longitude of the view centre (90 looks at +x), pitch = latitude
        (+90 looks up, at -y), roll turns the camera clockwise about its axis
        (:func:`panorama.directions.world_from_view`).
    fov_deg : float
        Horizontal field of view spanning the full width, 0 < fov < 180 (``Camera.from_fov``:
        fx = width / (2 tan(fov/2)); 90 deg at width 1920 gives fx = 960, cx = 959.5).
    width, height : int
        Output size in pixels.
    depth : bool
        ``pano`` holds range (equirect) or planar z per face (cube); the result is planar z
        of the view (float32).
    """
    width = _check_size("width", width)
    height = _check_size("height", height)
    check_image_size("width, height", width, height, channels=4)  # before allocating (#12)
    fov = check_finite_scalar("fov_deg", fov_deg)
    if not 0 < fov < 180:
        raise ValueError(f"fov_deg: expected 0 < fov_deg < 180, got {fov_deg!r}")
    yaw, pitch, roll = (check_finite_scalar(n, v) for n, v in
                        (("yaw_deg", yaw_deg), ("pitch_deg", pitch_deg), ("roll_deg", roll_deg)))
    source = detect_layout(pano) if layout is None else layout
    if source != "equirect":
        source = canonical_layout(source)
    check_choice("layout", source, ("equirect",) + LAYOUTS)
    interp = _interp(interpolation, depth)
    f = width / (2 * math.tan(math.radians(fov) / 2))  # texel angle at the view centre: 1/f
    if source == "equirect":
        img = check_equirect("pano", pano, depth=depth)
        out_dtype = np.float32 if depth else img.dtype
        if not depth:
            img = area_prefilter(img, img.shape[1] / (2 * math.pi * f))
        h, w = img.shape[:2]
        smap = _maps.perspective_map(yaw, pitch, roll, fov, width, height, "equirect", h, w)
        src = pad_equirect(img) if smap.pad else img
    else:
        faces = unpack_faces(pano, source)
        s = faces[0].shape[0]
        out_dtype = np.float32 if depth else faces[0].dtype
        if depth:
            lengths = face_ray_lengths(s)
            faces = [range_from_planar(_depth_array(f"pano face {i}", fc), lengths[i])
                     for i, fc in enumerate(faces)]
        else:
            faces = [area_prefilter(fc, s / (2 * f)) for fc in faces]
            s = faces[0].shape[0]
        src = pad_faces(faces, interpolation=interp, dtype=np.float32 if depth else None)
        smap = _maps.perspective_map(yaw, pitch, roll, fov, width, height, "cube", s, s)
    out = remap(src, smap, interpolation=interp, out_dtype=out_dtype)
    if depth:
        rays = _maps.perspective_rays(yaw, pitch, roll, fov, width, height)
        out = planar_from_range(out, np.linalg.norm(rays, axis=-1))
    return out
