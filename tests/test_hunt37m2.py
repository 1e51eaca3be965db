"""Hunt 37m2: a judge made for another classifier of the same number of activities, a
non-bool ``absent`` pushed to the live segmenter, and ``--subjects`` no clip has."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.live import LiveSegmenter
from features.errors import InputError


class _Scripted(LiveSegmenter):
    """The live segmenter voting "a" for every window (no classifier behind it)."""

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        return np.eye(2)[0], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only."""


def _scripted() -> _Scripted:
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    return _Scripted(clf, 30.0, judge=SimpleNamespace(), source="robot")


@pytest.mark.parametrize("absent", ["no", "False", 0, 1, None, [False]])
def test_an_absent_that_is_not_true_or_false_is_refused_naming_it(absent: Any) -> None:
    """``push(frame, absent="no")`` was taken as True (the frame counted as no frame in the
    video, "no frames in the video" said of a stretch of it); now InputError naming
    ``absent``, nothing kept; True, False and numpy's bools are taken."""
    live = _scripted()
    with pytest.raises(InputError, match=r"^robot: frame 0: absent must be True or False, got"):
        live.push(np.zeros((33, 3)), absent=absent)
    assert live.n == 0 and live.absent == []
    for ok in (False, True, np.bool_(True), np.bool_(False)):
        live.push(np.zeros((33, 3)), absent=ok)  # type: ignore[arg-type]
    assert live.n == 4 and live.absent == [[1, 3]]
