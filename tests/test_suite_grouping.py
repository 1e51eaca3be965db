"""The suite's own set-up: tests marked with one ``xdist_group`` run on one worker.

Costly module fixtures (a fitted model, a built wheel, a compare run) rely on it: without it
each worker makes its own, and the suite takes minutes longer. pytest-xdist marks a grouped
test by appending ``@group`` to its node id; under pytest 9.2 that stopped taking effect
(pytest-dev/pytest-xdist#1386) without any test failing, hence this one.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytestmark = pytest.mark.xdist_group("suite-grouping")


def test_a_grouped_test_is_scheduled_by_its_group(request: pytest.FixtureRequest) -> None:
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        pytest.skip("not run under pytest-xdist (pytest -n 0): there are no groups to check")
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("pytest-xdist runs without --dist loadgroup: groups are not asked for")
    assert request.node.nodeid.endswith("@suite-grouping"), (
        "pytest-xdist did not group this test (is pytest at a version it does not support?)"
    )


def test_made_once_makes_once_and_a_failed_make_is_tried_again(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """``made_once`` (tests/once.py): the second ask reads what the first made (an equal copy,
    ``make`` not run again); a ``make`` that raised left nothing, and the next ask makes it."""

    from tests.once import made_once

    name = f"suite-grouping-{os.getpid()}"
    calls: list[Path] = []

    def make(folder: Path) -> dict[str, object]:
        calls.append(folder)
        (folder / "made.txt").write_text("made")
        return {"path": folder / "made.txt", "n": [1, 2]}

    first = made_once(tmp_path_factory, name, make)
    second = made_once(tmp_path_factory, name, make)
    assert len(calls) == 1 and second == first and second is not first
    assert first["path"].read_text() == "made"

    def broken(folder: Path) -> int:
        (folder / "half.txt").write_text("half")
        raise RuntimeError("make failed")

    with pytest.raises(RuntimeError, match="make failed"):
        made_once(tmp_path_factory, name + "-broken", broken)
    assert (
        made_once(tmp_path_factory, name + "-broken", lambda folder: len(list(folder.iterdir())))
        == 0
    )


def test_the_suite_and_the_processes_it_starts_write_compiled_modules(tmp_path: Path) -> None:
    """PYTHONDONTWRITEBYTECODE (set on the machine CI runs on) no longer reaches the suite's
    processes: a command a test starts writes the ``.pyc`` of a module it imports (beside
    it, in ``__pycache__``), and this process writes them too."""
    import subprocess
    import sys

    assert "PYTHONDONTWRITEBYTECODE" not in os.environ and not sys.dont_write_bytecode
    (tmp_path / "probe_module.py").write_text("X = 1\n", encoding="utf-8")
    subprocess.run([sys.executable, "-c", "import probe_module"], cwd=tmp_path, check=True)
    assert [p.name.split(".")[0] for p in (tmp_path / "__pycache__").iterdir()] == ["probe_module"]
