"""Where the URDF robots of the PyPI package example-robot-data are (a test and benchmark dependency)."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path


def robots_dir() -> Path:
    """The folder holding example-robot-data's `<robot>_description/` folders.

    Raises importlib.metadata.PackageNotFoundError when the package is not installed."""
    dist = importlib.metadata.distribution("example-robot-data")
    return Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
