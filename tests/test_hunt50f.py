"""Hunt 50f: posecbr used as a library, as a robotics engineer would.

- the four packages are typed (``py.typed``), so ``mypy --strict`` checks a user's script
  calling them rather than skipping them ("missing library stubs or py.typed marker");
"""

from __future__ import annotations

import tomllib
from importlib.resources import files
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("features", "casebase_store", "cbr", "posecbr")


def test_every_package_is_typed() -> None:
    """PEP 561: a package's type hints are read by a type checker only when it ships a
    ``py.typed`` marker, installed with it."""
    for package in PACKAGES:
        assert files(package).joinpath("py.typed").is_file(), package
    with open(ROOT / "pyproject.toml", "rb") as f:
        package_data = tomllib.load(f)["tool"]["setuptools"]["package-data"]
    assert "py.typed" in package_data["*"]
