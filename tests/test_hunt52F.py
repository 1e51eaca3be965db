"""Hunt 52F: a jittered drop-out of a live source, and numba's on-disk cache past a file
size limit.

- A live source (``watch``) whose frames stop for a quarter to half a second and resume on
  time (a drop-out), its arrivals jittered, is told from a burst by the frames after the
  pause, not the first alone (:meth:`posecbr.commands.watch.Regrid._burst`): before, a frame
  after the pause that came early and one after it late had the pause taken for a burst's
  (frames held up, read at once), every frame after it placed by its count, as early as the
  pause was long.
- A kernel compiled with ``cache=True`` (``features._fluent_kernels._compiled``) that finds no
  room to save itself to numba's cache (a file size limit, ``ulimit -f``; a full disk) is used
  unsaved: before, numba's failed write ended the command, one that writes no file of its own
  (``posecbr describe`` of a long clip), with "cannot write: ... File too large".
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pytest

from features._fluent_kernels import _compiled
from posecbr.commands.watch import Regrid
from tests.test_hunt49e import _frame
from tests.test_hunt50a import _taken


@pytest.mark.parametrize("fps", [30.0, 15.0])
def test_a_jittered_drop_out_is_not_taken_for_a_burst(
    fps: float, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at ``fps`` for 6 s whose frames taken within 3.0-3.4 s are lost, each frame
    read 0.35 of a frame interval early or late in turn, the first after the pause late (the
    next then comes 0.3 of an interval after it, the one after that 1.7): a drop-out. Grid
    time k (one to a frame, as the frames came at the rate begun with) has the pose of
    k / fps, the grid times strictly inside the pause missing, and the pause said as a stall,
    not a burst. Before, the second frame, 0.3 of an interval after the first, had the pause
    taken for a burst's: the frames after it placed by their count, 0.37-0.4 s early."""
    taken = np.arange(round(6 * fps)) / fps
    lost = (taken > 3.0) & (taken < 3.4)
    kept = np.flatnonzero(~lost)
    first = int(np.flatnonzero(lost)[-1]) + 1  # the first frame after the pause
    came = taken + np.where((np.arange(len(taken)) - first) % 2 == 0, 0.35, -0.35) / fps
    frames = [_frame(j, came[i], taken[i]) for j, i in enumerate(kept)]
    values, _shown = _taken(Regrid(fps, "0"), frames)
    assert len(values) == len(taken)
    np.testing.assert_array_equal(np.isnan(values), lost)
    np.testing.assert_allclose(values[~lost], taken[~lost], atol=1e-9)
    err = capsys.readouterr().err
    assert err.count("the stream stalled") == 1 and "at once" not in err


def _sum_of_squares(n: int) -> int:
    total = 0
    for i in range(n):
        total += i * i
    return total


def test_a_kernel_without_room_in_the_cache_is_used_unsaved(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, file_size_limit: Callable[[int], None]
) -> None:
    """The cache's files of this function are several kB; with 1 kB allowed none fits. Before:
    ``OSError: [Errno 27] File too large`` from numba's save."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernel = _compiled(cache=True)(_sum_of_squares)
    file_size_limit(1 << 10)
    assert kernel(5) == 0 + 1 + 4 + 9 + 16
    # nothing cut at the limit left behind: numba writes a temporary and renames it
    assert [
        p.name for p in tmp_path.rglob("*") if p.is_file() and p.stat().st_size >= 1 << 10
    ] == []
    assert not list(tmp_path.rglob("*.tmp.*"))
