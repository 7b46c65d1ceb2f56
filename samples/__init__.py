"""Bundled sample RGB-D views (``samples/data``) and the code that regenerates them."""

from pathlib import Path

DATA_DIR = Path(__file__).resolve().parent / "data"
