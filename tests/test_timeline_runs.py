"""The runs `posecbr describe` lists (features.timeline.state_runs) on confidence tracks made by
hand: what a run's confidence is, and runs asked longer than the clip."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from features.fluents import FluentResult, evaluate
from features.poses import load_pose
from features.timeline import background, state_runs

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def layout() -> FluentResult:
    """A real result's states (names, table), its confidences to be replaced."""
    return evaluate(load_pose(DEMO / "m01_s03_e01.npz"))


def _with(layout: FluentResult, tracks: dict[int, np.ndarray]) -> FluentResult:
    n = len(next(iter(tracks.values())))
    conf = np.zeros((n, len(layout.state_names)))
    for state, track in tracks.items():
        conf[:, state] = track
    return dataclasses.replace(layout, confidence=conf)


def _shown(layout: FluentResult) -> list[int]:
    """Two states that are not background (describe lists them)."""
    return [int(i) for i in np.flatnonzero(~background(layout))[:2]]


def test_a_run_over_filled_flicker_has_the_confidence_of_the_frames_it_held(
    layout: FluentResult,
) -> None:
    """0.9 for 10 frames, 0.5 for 2 (below the 0.8 threshold), 0.9 for 10: a running median
    of 9 frames (--min-run 8) fills the 2-frame dip, one run of 22 frames. Its confidence is
    0.9, the mean where the state held; over the whole span it was (20 * 0.9 + 2 * 0.5) / 22 =
    0.864, and with a deeper dip a state shown below the threshold it was held at."""
    a, _ = _shown(layout)
    track = np.r_[np.full(10, 0.9), np.full(2, 0.5), np.full(10, 0.9)]
    runs = state_runs(_with(layout, {a: track}), 0.8, 8)
    assert [(r.start, r.end) for r in runs] == [(0, 21)]
    assert runs[0].states[0].confidence == pytest.approx(0.9)


def test_runs_asked_longer_than_the_clip_are_those_that_hold_it_whole(
    layout: FluentResult,
) -> None:
    """A 30-frame clip: state a holds throughout, b for frames 0-5. --min-run 30 and 100 alike
    give a alone over 0-29 (100 gave every span, however short, once the clip was shorter)."""
    a, b = _shown(layout)
    tracks = {a: np.full(30, 0.95), b: np.r_[np.full(6, 0.95), np.zeros(24)]}
    result = _with(layout, tracks)
    for min_run in (30, 100):
        runs = state_runs(result, 0.8, min_run)
        assert [(r.start, r.end, [s.name for s in r.states]) for r in runs] == [
            (0, 29, [layout.state_names[a]])
        ], min_run
