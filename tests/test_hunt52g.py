"""Session 52, task G: arm exercises filmed close up, the hips and legs out of the picture (a
physiotherapist's phone, a patient seated): the repetitions counted from the arms alone, and
the user told so, where such a clip was refused as showing no person."""

from __future__ import annotations

import argparse
import dataclasses
import json
import threading
import types
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_clip
from features.errors import DataError
from features.poses import PoseSequence, save_pose
from features.repetitions import count_repetitions
from features.skeleton import JOINT_INDEX
from posecbr.cli import main
from posecbr.commands.extract import out_of_view
from posecbr.commands.watch import Watcher

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
FIXTURE = ROOT / "tests" / "fixtures" / "repetition_counts.json"
TWO_PEOPLE = "edge/jumping_jack_two_people_pexels8402086.mp4"
BELOW_THE_WAIST = [
    i for n, i in JOINT_INDEX.items() if n.split("_", 1)[-1] in {"hip", "knee", "ankle", "heel"}
] + [JOINT_INDEX[f"{s}_foot_index"] for s in ("left", "right")]


def _hips_out(seq: PoseSequence) -> PoseSequence:
    """``seq`` (canonical) with the hips and everything below them missing in every frame, as
    ``extract`` stores joints the pose model places below a frame's bottom edge."""
    p = seq.positions.copy()
    p[:, BELOW_THE_WAIST] = np.nan
    return dataclasses.replace(seq, positions=p)


def test_shoulder_abductions_with_the_hips_out_of_view_are_counted() -> None:
    """UI-PRMD's standing shoulder abduction (one file, one repetition: the dataset's own
    cut), three of subject 1 in a row with the hips and legs missing: 3, from the arms (the
    upper arm's angle from straight down; the arm stays straight, so the elbow tells
    nothing). It was refused: "shows no person (no frame with a torso)"."""
    clips = [load_clip(DEMO / f"m07_s01_e0{e}.npz").to_canonical() for e in (1, 2, 3)]
    joined = dataclasses.replace(clips[0], positions=np.concatenate([c.positions for c in clips]))
    result = count_repetitions(_hips_out(joined))
    assert result.count == 3
    # the armpit angles of a clip without hips are read from the frame of the shoulders and the
    # world's up (hunt 53g): the same angle as the arm raise's, from straight down
    arms = {f"{s}_{a}" for s in ("left", "right") for a in ("arm_raise", "armpit", "elbow")}
    assert set(result.moving) <= arms
    # each repetition lies within its own file's frames
    ends = np.cumsum([c.n_frames for c in clips])
    starts = ends - [c.n_frames for c in clips]
    for r, a, b in zip(result.repetitions, starts, ends, strict=True):
        assert a <= r.peak_frame < b


@pytest.fixture(scope="module")
def jumping_jacks(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The two-people jumping-jack video's tracked person, as extract finds her (estimated
    once in the session, other files read it), then with the hips and legs out of view."""
    return _hips_out(bundled_poses(TWO_PEOPLE).to_canonical())


def _hand_count() -> dict[str, object]:
    clips = json.loads(FIXTURE.read_text(encoding="utf-8"))["clips"]
    return next(c for c in clips if c["source"].endswith(TWO_PEOPLE.split("/")[-1]))


def test_jumping_jacks_with_the_hips_out_of_view_match_the_hand_count(
    jumping_jacks: PoseSequence,
) -> None:
    """Six by hand (arms up at 1.25, 2.9, 4.65, 6.35, 8.2 and 9.9 s), counted from the arms."""
    hand = _hand_count()
    result = count_repetitions(jumping_jacks)
    assert result.count == hand["count"] == 6
    ups = [r.peak_frame / jumping_jacks.fps for r in result.repetitions]
    np.testing.assert_allclose(ups, [1.25, 2.9, 4.65, 6.35, 8.2, 9.9], atol=0.4)


def test_reps_says_once_that_it_counted_the_arms_alone(
    bundled_poses: Callable[[str], PoseSequence],
    jumping_jacks: PoseSequence,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Said on stderr, once, for the clip without hips; not for the whole-body one."""
    poses = save_pose(jumping_jacks, tmp_path / "close_up.npz")
    assert main(["reps", str(poses), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["count"] == 6
    notes = [line for line in err.splitlines() if "hips" in line]
    assert notes == [
        f"note: {poses}: the hips are seen in no frame (out of view): counted from the arms alone"
    ]
    whole = save_pose(bundled_poses(TWO_PEOPLE), tmp_path / "whole.npz")
    assert main(["reps", str(whole)]) == 0
    out, err = capsys.readouterr()
    assert out.startswith(f"{whole}: 6 repetitions")
    assert "hips" not in err


def _watcher(fps: float) -> Watcher:
    """A ``watch`` of a video file, its segmenter stood in for by its frame rate alone."""
    w = Watcher(None, None, argparse.Namespace(source="close_up.mp4", max_frames=None, k=None), fps)
    w.live = types.SimpleNamespace(fps=fps)
    w.is_file = True
    return w


def test_watch_says_once_when_the_hips_go_out_of_view(
    bundled_poses: Callable[[str], PoseSequence],
    jumping_jacks: PoseSequence,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Frame by frame as ``watch`` pushes them: the whole video's first 2 s (the hips seen:
    nothing said), then the jumping jacks without hips: said once, when the shoulders have
    been seen without the hips for a second (25 frames at 25 fps), from 2.00 s: labelled from
    the arms alone (hunt 53h; before, "no activity is labelled without the torso"). With one
    hip seen there is no torso and no arms alone (:func:`features.body.arms_alone`): the
    stretch is nobody in view, as before, and the note says so."""
    assert jumping_jacks.fps == 25.0
    whole = bundled_poses(TWO_PEOPLE).to_canonical().positions[:50]
    one_hip = jumping_jacks.positions.copy()
    one_hip[:, JOINT_INDEX["left_hip"]] = whole[-1, JOINT_INDEX["left_hip"]]
    for then, said in [
        (jumping_jacks.positions, "labelled from the arms alone while they are"),
        (one_hip, "no activity is labelled without the torso, and a stretch without it is"
                  " given as nobody in view"),
    ]:  # fmt: skip
        w = _watcher(jumping_jacks.fps)
        for frame in [*whole, *then]:
            w._hips(frame)
            w.n += 1
            if w.n in (50, 74):  # the hips seen; then one frame short of a second without them
                assert capsys.readouterr().err == ""
        assert capsys.readouterr().err.splitlines() == [
            "note: close_up.mp4: the hips are out of view from 2.00 s (the shoulders are seen):"
            f" {said}"
        ]


def test_watch_names_the_hips_when_no_frame_showed_the_torso() -> None:
    """A video watched to its end, every segment nobody in view: with the shoulders seen and
    the hips not, the refusal says so; with nobody at all, as before."""
    for no_hips, said in [
        (True, "with no torso in any of them (the hips out of view): no activity to label"),
        (False, "with nobody in view in any of them: no activity to label"),
    ]:
        w = _watcher(25.0)
        w.live, w.emitted, w.n, w.no_hips = None, 1, 250, no_hips
        with pytest.raises(DataError) as caught:
            w.close(threading.Event())
        assert str(caught.value).endswith(
            f"close_up.mp4: the stream ended after 250 frames (10.00 s) {said}"
        ), str(caught.value)


def test_extract_says_which_parts_were_out_of_view(
    bundled_poses: Callable[[str], PoseSequence], jumping_jacks: PoseSequence
) -> None:
    """``extract``'s line: the parts missing in the frames that show the person, with their
    share of those frames. The whole video's tracked person is seen whole in every frame:
    nothing said; with the hips and legs out of view in all 250 and a wrist in the first 50
    as well: 100 % each and 50 / 250 = 20 %."""
    whole = bundled_poses(TWO_PEOPLE).to_canonical()
    nobody = np.isnan(whole.positions).all(axis=(1, 2))
    assert not nobody.any() and not np.isnan(whole.positions).any()
    assert out_of_view(whole, nobody) == ""
    p = jumping_jacks.positions.copy()
    p[:50, JOINT_INDEX["left_wrist"]] = np.nan
    close_up = dataclasses.replace(jumping_jacks, positions=p)
    assert out_of_view(close_up, nobody) == (
        "; out of view in the frames with a person: wrists 20 %, hips 100 %, knees 100 %,"
        " ankles 100 %, feet 100 %"
    )
    # frames with nobody in view are not counted: the wrist's 50 frames among them, none
    assert out_of_view(close_up, np.arange(250) < 50).startswith(
        "; out of view in the frames with a person: hips 100 %"
    )
