"""Video on a canvas: frames from ``cv2.VideoCapture``, one at a time, into the canvas buffer.

Seed 004 plays a 728 x 480, 29 fps video on a plane of the 3-D world by copying every decoded frame
into its virtual canvas; seed 001 (section 7.5) puts movies on a virtual screen the same way and
notes that the display rate is rarely a multiple of the movie's, so frames repeat in a pattern
(24 fps on a 60 Hz display: 3:2 pulldown, frames shown 2, 3, 2, 3, ... times). :func:`frame_schedule`
gives that pattern: display frame k shows video frame ``floor(k * video_fps / display_fps)``.

A frame whose size equals the canvas's is converted straight into the buffer (BGR -> RGBA, one
pass, no allocation); other sizes are resampled once (:func:`ibr.canvas.resample.set_image`).
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from ..base.validate import check_positive
from .plane import Canvas
from .resample import set_image

__all__ = ["VideoSource", "frame_schedule"]


def frame_schedule(n_display: int, display_fps: float, video_fps: float) -> np.ndarray:
    """Video frame index for each of ``n_display`` display frames (seed 001: pulldown).

    ``index[k] = floor(k * video_fps / display_fps)`` (computed exactly for rational rates);
    e.g. 24 fps on 60 Hz gives 0 0 0 1 1 2 2 2 3 3 ... (3:2 pulldown).
    """
    if isinstance(n_display, bool) or int(n_display) != n_display or n_display < 0:
        raise ValueError(f"n_display: expected a non-negative integer, got {n_display!r}")
    d = check_positive("display_fps", display_fps)
    v = check_positive("video_fps", video_fps)
    k = np.arange(int(n_display), dtype=np.float64)
    return np.floor(k * v / d + 1e-9).astype(np.int64)


class VideoSource:
    """Frames of a video file, decoded one at a time with ``cv2.VideoCapture``.

    Parameters
    ----------
    path : str or Path
        A video file OpenCV can decode (mp4, avi, mov, ...).

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        OpenCV cannot open it, or it holds no decodable frame.

    Attributes
    ----------
    fps : float
        Frame rate stored in the file (0 when unknown).
    size : (int, int)
        ``(width, height)`` of the frames.
    frame_count : int
        Number of frames the container reports (may be approximate; -1 if unknown).
    """

    def __init__(self, path):
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"video: file not found: {self.path}")
        cap = cv2.VideoCapture(str(self.path))
        if not cap.isOpened():
            raise ValueError(f"video: OpenCV cannot open {self.path} as a video")
        ok, frame = cap.read()
        if not ok or frame is None:
            cap.release()
            raise ValueError(f"video: {self.path} holds no decodable frame")
        self._cap = cap
        self._first = frame
        self.size = (frame.shape[1], frame.shape[0])
        self.fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        n = cap.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(n) if n and n > 0 else -1

    def read_bgr(self) -> np.ndarray | None:
        """Next frame as OpenCV gives it (H, W, 3) uint8 BGR, or None at the end."""
        if self._cap is None:
            return None
        if self._first is not None:
            frame, self._first = self._first, None
            return frame
        ok, frame = self._cap.read()
        return frame if ok else None

    def read(self) -> np.ndarray | None:
        """Next frame as (H, W, 3) uint8 RGB, or None at the end."""
        f = self.read_bgr()
        return None if f is None else cv2.cvtColor(f, cv2.COLOR_BGR2RGB)

    def read_into(self, canvas: Canvas) -> bool:
        """Decode the next frame into ``canvas.rgba`` (opaque); False at the end of the video."""
        f = self.read_bgr()
        if f is None:
            return False
        put_bgr_frame(canvas, f)
        return True

    def __iter__(self):
        while True:
            f = self.read()
            if f is None:
                return
            yield f

    def close(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None

    def __enter__(self) -> "VideoSource":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):  # pragma: no cover - best effort
        try:
            self.close()
        except Exception:  # noqa: BLE001
            pass


def put_bgr_frame(canvas: Canvas, frame_bgr: np.ndarray) -> None:
    """An OpenCV BGR uint8 frame into the canvas buffer; one ``cvtColor`` pass when the sizes and
    dtype match (the video fast path), else resampled once."""
    h, w = frame_bgr.shape[:2]
    if canvas.rgba.dtype == np.uint8 and canvas.resolution == (w, h) and canvas.rgba.flags.c_contiguous:
        cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2RGBA, dst=canvas.rgba)
    else:
        set_image(canvas, cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2RGB))
