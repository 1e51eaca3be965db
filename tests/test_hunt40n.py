"""``segment`` at a very low frame rate (``--fps 0.01``: a user typing a frame time for a
rate): a window every 0.5 s over frames 100 s apart, 200 windows of the same two frames a
frame; each was solved on its own (60 frames: 12,000 windows, 13 s CPU and 0.4 GB)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import cbr.segmentation as segmentation
from cbr.estimator import CaseBaseClassifier
from cbr.segmentation import activity_distances, solve_recording
from features.datasets import Clip
from features.repetitions import split_windows
from tests.moves import clip

# on one xdist worker: the module's classifier made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt40n")


@pytest.fixture(scope="module")
def classifier() -> CaseBaseClassifier:
    """2-s windows of squats and jumping jacks at 30 fps, as ``train --split windows`` cuts."""
    clips = [Clip(clip(n).with_metadata(label=n, subject="s"), n, "s", {})
             for n in ("squat", "jumping_jack")]  # fmt: skip
    windows = split_windows(clips).clips
    return CaseBaseClassifier(feature_weights="none").fit(
        [c.seq for c in windows], [c.label for c in windows]
    )


def test_windows_of_the_same_frames_are_solved_once(
    classifier: CaseBaseClassifier, monkeypatch: pytest.MonkeyPatch
) -> None:
    """12 frames at 0.01 fps last 1,200 s: 2,400 windows every 0.5 s, each of two frames
    (a 2-s window holds 0.02 frames, at least two are taken), so at most 11 distinct ones
    ([i, i + 2) for i = 0..10). Every window's frames are solved once (before: 2,400 clips
    solved), and a window shares the answer its frames give solved on their own."""
    rec = dataclasses.replace(clip("squat", 0.4), fps=0.01)
    assert rec.n_frames == 12
    cut: dict[int, tuple[int, int]] = {}  # id of a clip cut from the recording: its frames
    solved: list[tuple[int, int]] = []
    real_stretch, real_solve = segmentation.stretch, classifier.solve

    def stretch(seq: Any, start: int, stop: int) -> Any:
        part = real_stretch(seq, start, stop)
        cut[id(part)] = (start, stop)
        return part

    def solve(clips: list[Any], flag: bool = True) -> Any:
        solved.extend(cut[id(c)] for c in clips)
        return real_solve(clips, flag=flag)

    monkeypatch.setattr(segmentation, "stretch", stretch)
    monkeypatch.setattr(classifier, "solve", solve)
    done = solve_recording(classifier, rec, chunk_frames=0)
    fixed = [w for w in done.windows if not w.repetition]
    assert len(fixed) == 2400
    assert all(w.stop - w.start == 2 for w in fixed)
    assert len(solved) == len(set(solved)) <= 11
    assert set(solved) == {(w.start, w.stop) for w in done.windows}
    monkeypatch.undo()
    codes = segmentation.activity_codes(classifier.case_base_.labels, classifier.classes_)
    canonical = rec.to_canonical()
    for w in done.windows[::97]:
        alone = classifier.solve([canonical.slice_frames(w.start, w.stop)], flag=False)[0]
        assert np.allclose(w.nearest, activity_distances(classifier, alone, codes)), w
