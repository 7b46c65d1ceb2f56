"""Headless Chromium for the web-viewer tests: find it, take a screenshot of a page."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

from ibr.io import read_image


def chromium() -> str | None:
    """Path of a Chromium/Chrome binary, or None (then the browser tests are skipped)."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot(url: str, out: Path, width: int, height: int) -> np.ndarray:
    """(height, width, 3) int16 screenshot of ``url`` (software GL, device scale 1); skips the
    test when this Chromium cannot do WebGL."""
    profile = tempfile.mkdtemp(prefix="ibr-chromium-")
    try:
        cmd = [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               f"--user-data-dir={profile}", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
               "--force-device-scale-factor=1", "--hide-scrollbars", f"--screenshot={out}",
               f"--window-size={width},{height}", "--virtual-time-budget=5000", url]
        subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    if not Path(out).exists():
        pytest.skip("Chromium ran but wrote no screenshot (no WebGL in this environment)")
    return read_image(out)[..., :3].astype(np.int16)
