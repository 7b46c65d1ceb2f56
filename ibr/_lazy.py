"""Lazy re-exports for package ``__init__`` files: ``import ibr`` and ``import ibr.render`` stay fast
(no numba, OpenCV or OpenImageIO until a name that needs them is used)."""

from __future__ import annotations

import importlib


def lazy_exports(package: str, exports: dict[str, str]):
    """``(__getattr__, __dir__, __all__)`` (``__all__`` without the module aliases) for a package whose public names live in submodules.

    ``exports`` maps a public name to the module (relative to ``package``, e.g. ``"base.camera"``)
    that defines it; a name whose module is given with a trailing ``"."`` *is* that module
    (``{"lens": "stereo.lens."}`` makes ``pkg.lens`` the module ``pkg.stereo.lens``).
    """
    names = sorted(exports)
    public = sorted(k for k, v in exports.items() if not v.endswith("."))

    def __getattr__(name: str):
        where = exports.get(name)
        if where is None:  # a subpackage or submodule not imported yet (``ibr.synth``)
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as exc:
                if exc.name != f"{package}.{name}":
                    raise
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if where.endswith("."):
            value = importlib.import_module(f"{package}.{where[:-1]}")
        else:
            value = getattr(importlib.import_module(f"{package}.{where}"), name)
        importlib.import_module(package).__dict__[name] = value
        return value

    def __dir__():
        return names

    return __getattr__, __dir__, public
