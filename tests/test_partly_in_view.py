"""A recording the person is in view for less than half of: followed while they are there
(`reps`, `segment`), not refused whole as "no person in view". An angle takes part when it is
there in half the frames that show the person; frames showing nobody do not count against it.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from features.readers.asfamc import read_asf_amc
from features.repetitions import count_repetitions
from posecbr.cli import main
from tests.badinput import small_case_base, standing_clip

FIXTURE = Path(__file__).parent / "fixtures" / "repetition_counts.json"


def _blank_after(seq: PoseSequence, frames: int) -> PoseSequence:
    """``seq`` followed by ``frames`` frames in which nobody is seen (every joint NaN)."""
    blank = np.full((frames, *seq.positions.shape[1:]), np.nan)
    conf = None
    if seq.confidence is not None:
        conf = np.concatenate([seq.confidence, np.zeros((frames, seq.confidence.shape[1]))])
    return replace(seq, positions=np.concatenate([seq.positions, blank]), confidence=conf)


def _blank_before(seq: PoseSequence, frames: int) -> PoseSequence:
    """``frames`` frames in which nobody is seen, then ``seq``."""
    rev = replace(seq, positions=seq.positions[::-1], confidence=None)
    out = _blank_after(rev, frames)
    return replace(out, positions=out.positions[::-1])


# on one xdist worker: the module's squats made once, not once per worker
pytestmark = pytest.mark.xdist_group("partly_in_view")


@pytest.fixture(scope="module")
def squats(shared_data: Path) -> PoseSequence:
    """CMU subject 13's squats: two by the hand counts of tests/fixtures."""
    clip = next(
        c
        for c in json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
        if c.get("activity") == "Squat" and c["source"].endswith(".amc")
    )
    assert clip["count"] == 2
    rec = read_asf_amc(shared_data / clip["asf"], shared_data / clip["source"])
    return rec.slice_frames(clip["start_frame"], clip["end_frame"])


@pytest.mark.parametrize("blank", [_blank_after, _blank_before])
def test_squats_seen_for_two_fifths_of_the_recording_are_counted(
    squats: PoseSequence, blank: object
) -> None:
    """The two squats, then (or after) 1.5 times as long with nobody in view: the person is
    seen in 40 % of the frames, and the squats are still counted, where the person is."""
    n = squats.n_frames
    seq = blank(squats, int(1.5 * n))  # type: ignore[operator]
    reps = count_repetitions(seq).repetitions
    assert len(reps) == 2
    offset = 0 if blank is _blank_after else int(1.5 * n)
    assert all(offset <= r.start_frame < r.end_frame <= offset + n for r in reps), reps


def test_nobody_at_all_is_still_refused(squats: PoseSequence) -> None:
    from features.errors import DataError

    nobody = replace(squats, positions=np.full_like(squats.positions, np.nan), confidence=None)
    with pytest.raises(DataError, match=r"shows no person \(no frame with a torso\)"):
        count_repetitions(nobody)


def test_segment_follows_a_person_who_leaves_for_most_of_the_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """3 s of a person standing, then 5 s with nobody in view: segmented, the last 5 s as
    "nobody in view" (it was refused whole: "no person in view in enough frames")."""
    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()
    person = standing_clip(90)  # 3 s at 30 fps
    path = save_pose(_blank_after(person, 150), tmp_path / "leaves.npz")
    assert main(["segment", str(path), "--db", str(db), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    segments = doc["segments"]
    assert segments[0]["start_frame"] == 0 and segments[-1]["end_frame"] == 240
    last = segments[-1]
    assert last["label"] is None and last["unknown"] == "nobody in view"
    assert last["start_frame"] == pytest.approx(90, abs=15)  # within 0.5 s of where they left
    assert any(s["unknown"] != "nobody in view" for s in segments)
