"""Web viewer quality (issue #18): mipmapped minification against a box-filtered reference, in
headless Chromium."""

from __future__ import annotations

import numpy as np
import pytest

import panorama as P
from ibr.io import read_image
from panorama.directions import equirect_directions
from panorama.viewer import serve, site_url, write_site

from test_stitch_viewer import H, W, _chromium, _screenshot


def _psnr(a, b) -> float:
    d = a.astype(np.float64) - b.astype(np.float64)
    return float(10 * np.log10(255.0**2 / np.mean(d * d)))


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_mipmaps_filter_fine_texture_seen_at_a_wide_field_of_view(tmp_path):
    """Fine stripes on 512-px faces seen at 120 degrees over 320 px (about 2-4 face pixels per
    screen pixel): the mipmapped page is close to the view of box-filtered faces, the plain
    bilinear page (``?mipmaps=0``) aliases."""
    d = equirect_directions(2048, 1024)
    lon = np.arctan2(d[..., 0], d[..., 2])
    stripes = 0.5 + 0.45 * np.sin(130 * lon + 90 * d[..., 1])
    eq = np.stack([stripes, 0.3 + 0.4 * stripes, 1 - stripes], -1).astype(np.float32)
    site = tmp_path / "site"
    write_site(site, eq)
    faces = [read_image(site / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    assert faces[0].shape[0] == 1024  # power of two >= 2048 / pi
    view = dict(yaw_deg=20.0, pitch_deg=10.0, roll_deg=0.0, fov_deg=120.0)
    # reference: panorama.perspective, which box-filters (area prefilter) the faces to the view's
    # sampling rate before sampling them
    ref = P.perspective(faces, width=W, height=H, **view)
    server = serve(site)
    try:
        mip = _screenshot(site_url(server, hud=False, **view), tmp_path / "mip.png")
        plain = _screenshot(site_url(server, hud=False, **view) + "&mipmaps=0", tmp_path / "plain.png")
    finally:
        server.shutdown()
        server.server_close()
    assert _psnr(mip, ref) > 26 and _psnr(mip, ref) > _psnr(plain, ref) + 3  # measured 28.1 vs 24.0 dB
