"""The machine and library versions, recorded with every comparison and every benchmark."""

from __future__ import annotations

import importlib.metadata
import os
import platform
from typing import Any

PACKAGES = (
    "posecbr",
    "numpy",
    "scipy",
    "scikit-learn",
    "tslearn",
    "iisignature",
    "pysindy",
    "numba",
    "sktime",
    "aeon",
    "matplotlib",
)


def _version(package: str) -> str | None:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None


def machine_info(extra_packages: tuple[str, ...] = ()) -> dict[str, Any]:
    """Python, platform, processor, CPU count and the versions of the libraries that shape the
    figures (``extra_packages`` first; None for one not installed)."""
    packages = dict.fromkeys(extra_packages + PACKAGES)  # ordered, no repeats
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
        "versions": {p: _version(p) for p in packages},
    }
