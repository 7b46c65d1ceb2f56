"""Headless Chromium for the web-viewer tests: find it, take a screenshot of a page."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import time
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


class DevTools:
    """Chrome DevTools protocol over --remote-debugging-pipe (fd 3 in, fd 4 out; NUL-terminated JSON)."""

    def __init__(self, args):
        a_r, a_w = os.pipe()
        b_r, b_w = os.pipe()

        def fds():
            os.dup2(a_r, 3)
            os.dup2(b_w, 4)

        self.proc = subprocess.Popen(args, preexec_fn=fds, close_fds=False,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(a_r)
        os.close(b_w)
        self.w, self.r = a_w, b_r
        self.buf = b""
        self.next_id = 0
        self.events = []
        self.session = None

    def _read(self, deadline):
        import select

        while b"\0" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("Chromium did not answer")
            ready, _, _ = select.select([self.r], [], [], left)
            if ready:
                chunk = os.read(self.r, 1 << 20)
                if not chunk:
                    raise RuntimeError("Chromium closed the pipe")
                self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, timeout=30, **params):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params}
        if self.session and not method.startswith("Target."):
            msg["sessionId"] = self.session
        os.write(self.w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read(deadline)
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def eval(self, expr, timeout=30):
        r = self.call("Runtime.evaluate", expression=expr, returnByValue=True, awaitPromise=True, timeout=timeout)
        if "exceptionDetails" in r:
            raise RuntimeError(f"page error in {expr!r}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait_for(self, expr, timeout=30):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.eval(expr):
                return
            time.sleep(0.1)
        raise TimeoutError(f"page never satisfied {expr!r}")

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except Exception:  # noqa: BLE001 - closing anyway
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        os.close(self.w)
        os.close(self.r)

    @classmethod
    def start(cls, width: int, height: int, profile: str) -> "DevTools":
        """Headless Chromium (software GL) attached to its first page."""
        dt = cls([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader", "--remote-debugging-pipe", f"--user-data-dir={profile}",
                  "--no-first-run", "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--force-device-scale-factor=1", "--hide-scrollbars",
                  f"--window-size={width},{height}", "about:blank"])
        targets = dt.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        dt.session = dt.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)["sessionId"]
        return dt
