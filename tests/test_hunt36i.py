"""Hunt 36i: ``segment``'s per-segment repetitions against ``reps``' whole-clip count and the
hand counts (tests/fixtures/repetition_counts.json) on the bundled videos."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.segmentation import counted_segments
from features.poses import PoseSequence, save_pose
from features.repetitions import movement_signals
from posecbr.cli import main
from tests.test_repetitions import _arms_raised_and_held
from tests.test_video_gaps import _drawn_words, lunge_frames
from tests.test_video_vfr import _write
from tests.test_watch import case_base  # noqa: F401 (a fixture)

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"


def _hand(name: str) -> dict[str, Any]:
    clips = json.loads(FIXTURE.read_text())["clips"]
    return next(c for c in clips if c["source"].endswith(name))


def _video(bundled_poses: Callable[[str], PoseSequence], name: str) -> PoseSequence:
    """The poses of the bundled video ``name`` (estimated once in the session), canonical."""
    return bundled_poses(name).to_canonical()


def _segment_counts(seq: PoseSequence, cuts_s: list[float]) -> list[int]:
    """The repetitions of each segment of ``seq`` cut at ``cuts_s`` seconds, as ``segment``
    counts them (:func:`cbr.segmentation.counted_segments`)."""
    edges = [0, *(int(round(t * seq.fps)) for t in cuts_s), seq.n_frames]
    bounds = list(zip(edges[:-1], edges[1:], strict=True))
    return [len(r) for r in counted_segments(movement_signals(seq), bounds, seq.n_frames)]


@pytest.mark.parametrize("cut_s", [3.0, 4.5])
def test_a_posture_held_across_a_cut_is_no_repetition(cut_s: float) -> None:
    """Arms raised once and held still to the end (no repetition by construction), cut into
    two segments inside the hold: neither counts one, as the whole clip counts none. Before,
    the first segment counted the way up as a repetition (its end was a cut, so the
    posture-held rule was not applied)."""
    assert _segment_counts(_arms_raised_and_held(), [cut_s]) == [0, 0]


def test_the_side_plank_video_has_no_repetition_in_its_segments(
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """The bundled side plank (held from 1.4 s to the end: 0 by hand), cut where ``segment``
    with the README's workout case base cut it (6.20 s): 0 and 0. Before: 1 in the first
    segment (frames 48-69, the way into the plank), where ``reps`` says 0."""
    name = "side_plank/fit_side_plank_pexels6023266.mp4"
    seq = _video(bundled_poses, name)
    counts = _segment_counts(seq, [6.2])
    assert sum(counts) == _hand(name)["count"] == 0, counts


def test_reps_gives_no_period_when_nothing_repeated(
    side_plank_reps: tuple[str, str],
    bundled_poses: Callable[[str], PoseSequence],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The side plank, 0 repetitions by hand: ``reps`` said "0 repetitions (period 0.40 s;
    moving left armpit)", and ``--json`` gave ``"period_s": 0.4, "periodicity": 0.29``, a
    period of nothing counted (read from the jitter of the hold). Now neither gives one; the
    squats of the 5-fps video (3 by hand) keep theirs (``reps`` of its poses as extract
    finds them, the session's: what ``reps`` of the video gives but for the path, checked)."""
    text, as_json = side_plank_reps  # reps VIDEO, reps VIDEO --json (conftest.py)
    line = text.strip()
    assert line.endswith("0 repetitions (moving left armpit)"), line
    assert "period" not in line
    doc = json.loads(as_json)
    assert (doc["count"], doc["period_s"], doc["periodicity"]) == (
        _hand("fit_side_plank_pexels6023266.mp4")["count"],
        None,
        None,
    )
    name = "squat/tfjs_pose_squats_pexels4838220.mp4"
    squats = save_pose(bundled_poses(name), tmp_path / "tfjs_pose_squats_pexels4838220.npz")
    assert main(["reps", str(squats)]) == 0
    assert " 3 repetitions (period " in capsys.readouterr().out


# on one xdist worker: the module's lunge_nobody made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt36i")


@pytest.fixture(scope="module")
def lunge_nobody(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reverse lunge's first 150 frames at a quarter size, lossless (FFV1 in Matroska: the
    same poses each run), frames 50 to 99 (2.0 to 3.96 s) grey: nobody in view there."""
    frames = lunge_frames(shared_data, 150)
    for k in range(50, 100):
        frames[k] = np.full_like(frames[k], 128)
    folder = tmp_path_factory.mktemp("nobody_mkv")
    return _write(folder / "lunge_nobody.mkv", [40 * k for k in range(150)], frames, codec="ffv1")


def test_segment_and_watch_draw_nobody_in_view_on_one_line(
    case_base: Path,  # noqa: F811
    lunge_nobody: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The frames with nobody in view (50 to 99, grey by construction): ``segment --overlay``
    drew two lines saying the same, "no person" (the stick figure's absence) and "nobody in
    view" (the segment's name), where ``watch --out`` drew "no person" alone. Both draw the
    same one line now, then the count."""
    drawn = _drawn_words(monkeypatch)
    out = tmp_path / "segment.mp4"
    argv = ["segment", str(lunge_nobody), "--db", str(case_base), "--json", "--overlay"]
    assert main([*argv, str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    nobody = [s for s in doc["segments"] if s["unknown"] == "nobody in view"]
    assert [(s["start_frame"], s["end_frame"]) for s in nobody] == [(50, 100)]
    assert len(drawn) == doc["frames"] == 150 and out.is_file()
    segment_rows = drawn[50:100]
    drawn.clear()
    out = tmp_path / "watch.mp4"
    argv = ["watch", str(lunge_nobody), "--db", str(case_base), "--speed", "0", "--out"]
    assert main([*argv, str(out)]) == 0
    assert len(drawn) == 150 and out.is_file()
    # watch learns of nobody in view as the frames come: from its first second on, it says so
    watch_rows = drawn[50:100]
    for seg, live in zip(segment_rows, watch_rows, strict=True):
        assert seg[:2] == ["no person", "repetitions: 0"], seg
        assert "nobody in view" not in seg
        assert live[0] == "no person" and "nobody in view" not in live, live
