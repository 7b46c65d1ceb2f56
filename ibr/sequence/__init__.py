"""RGB-D sequences and batches: many frames in, up-converted video and stereo out, on a pool or a cluster.

In: sequence files (a JSON manifest of view files in time order, or a folder of
``<prefix>_<NNNN>.json`` views) and batch files (a list of ``ibr`` command lines). Out: frames
rendered over whole sequences, temporal-stability scores, and batch reports.
:mod:`~ibr.sequence.files` (sequence manifests and folders), :mod:`~ibr.sequence.frame_rate`
(frame-rate up-conversion: each key's mesh serves both of its segments, previous-frame fill
across segments), :mod:`~ibr.sequence.stereo` (stereo pairs with one interaxial for the whole
sequence), :mod:`~ibr.sequence.metrics` (PSNR, flicker in static regions),
:mod:`~ibr.sequence.jobs` (idempotent jobs: checksums, staging, records) and
:mod:`~ibr.sequence.batch` (running jobs on a ``concurrent.futures`` process pool or a Dask
cluster). Imports :mod:`ibr.base`, :mod:`ibr.mesh`, :mod:`ibr.render`, :mod:`ibr.stereo` and,
being a runner over files, :mod:`ibr.io`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "SEQUENCE_FORMAT": "files",
    "Sequence": "files",
    "is_sequence": "files",
    "iter_views": "files",
    "load_sequence": "files",
    "referenced_files": "files",
    "save_sequence": "files",
    "SequenceFrame": "frame_rate",
    "frame_count": "frame_rate",
    "frame_schedule": "frame_rate",
    "upconvert": "frame_rate",
    "sequence_stereo_params": "stereo",
    "stereo_sequence": "stereo",
    "FlickerReport": "metrics",
    "flicker": "metrics",
    "psnr": "metrics",
    "static_masks_from_motion": "metrics",
    "static_masks_from_truth": "metrics",
    "Job": "jobs",
    "load_jobs": "jobs",
    "run_job": "jobs",
    "BatchReport": "batch",
    "run_batch": "batch",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
