"""``posecbr watch --split repetitions``: each repetition of a live stream judged as it
finishes, as ``classify --split repetitions`` judges it (hunt 52 C).

Real data: a case base of the bundled UI-PRMD Kinect deep squats (three people, correct and
incorrect, ``train --target correct``), and a held-out person's (s08) correct and incorrect
squats joined into one session, streamed through ``watch`` as a camera delivers its frames.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import features.pose_estimation as pose_estimation
from features.pose_estimation import StreamFrame
from features.pose_estimation.tracker import FramePose
from posecbr.cli import main
from tests.once import made_once
from tests.test_hunt52u import SEGMENT_KEYS

BUNDLED = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"
# s08's episodes in the session's order, and whether each is an incorrect one
ORDER = ((1, True), (2, False), (3, True), (3, False))


def _make(folder: Path, shared_data: Path) -> dict[str, Any]:
    """The case base, and s08's session saved as a pose file with its repetitions' true
    frames and verdicts (its skeleton the pose model's, as the stream's frames are: not the
    Kinect's it was converted from, which the case base's cases share)."""
    from features.datasets import clip_target, iter_dataset
    from features.joining import join_repetitions
    from features.poses import CANONICAL_SKELETON, save_pose

    db = folder / "squat.sqlite"
    argv = ["train", str(BUNDLED), "--labels", "deep_squat", "--target", "correct", "--db", str(db)]
    assert main(argv) == 0
    clips = list(iter_dataset(shared_data / "ui-prmd", sensor="kinect", subjects=["s08"],
                              labels=["deep_squat"]))  # fmt: skip
    by = {(int(c.seq.metadata["episode"]), clip_target(c, "correct") == "incorrect"): c
          for c in clips}  # fmt: skip
    order = [by[key] for key in ORDER]
    joined = join_repetitions([c.seq.to_canonical() for c in order])
    seq = dataclasses.replace(joined.seq, skeleton=CANONICAL_SKELETON, source="s08_squats.npz")
    pose = save_pose(seq, folder / "s08_squats.npz")
    spans = [(int(s), int(s) + c.seq.n_frames) for s, c in zip(joined.starts, order, strict=True)]
    truth = ["incorrect" if inc else "correct" for _, inc in ORDER]
    return {"db": str(db), "pose": str(pose), "spans": spans, "truth": truth}


@pytest.fixture(scope="module")
def session(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return made_once(tmp_path_factory, "hunt52c-squat-session", lambda f: _make(f, shared_data))


def _camera(pose: str) -> Any:
    """A stand-in for ``stream_poses``: the pose file's frames as a camera delivers them."""
    from features.poses import load_pose

    seq = load_pose(Path(pose))

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i in range(seq.n_frames):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0
            pose = FramePose(image, seq.positions[i], True, False, 1.0, None)
            yield StreamFrame(i, i / seq.fps, pose, np.zeros((8, 8, 3), np.uint8),
                              time.perf_counter())  # fmt: skip

    return stream, seq.n_frames


@pytest.fixture(scope="module")
def watched(session: dict[str, Any]) -> tuple[list[dict[str, Any]], str, list[dict[str, Any]]]:
    """The watch's lines (stdout) and stderr, and classify --split repetitions' records of
    the same session. Watched with ``--progress 1`` (each line tagged with its ``"event"``,
    :func:`test_with_progress_each_line_says_its_event_the_verdicts_otherwise_unchanged`):
    the 10-s session ends before any segment's label is settled, so no progress line comes
    and the lines are the verdicts and the segment, as without it."""
    import contextlib
    import io

    stream, n = _camera(session["pose"])
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pose_estimation, "stream_poses", stream)
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            argv = ["watch", "0", "--db", session["db"], "--unknown", "held-out", "--split",
                    "repetitions", "--max-frames", str(n), "--progress", "1"]  # fmt: skip
            assert main(argv) == 0, err.getvalue()
    lines = [json.loads(line) for line in out.getvalue().splitlines()]
    got = io.StringIO()
    with contextlib.redirect_stdout(got), contextlib.redirect_stderr(io.StringIO()):
        argv = ["classify", session["pose"], "--db", session["db"], "--split", "repetitions"]
        assert main([*argv, "--json"]) == 0
    return lines, err.getvalue(), json.loads(got.getvalue())["results"]


def test_each_repetition_is_judged_as_classify_judges_it(
    session: dict[str, Any], watched: tuple[list[dict[str, Any]], str, list[dict[str, Any]]]
) -> None:
    """Each of the four squats gets one verdict line, numbered in order and covering it by
    more than half; where watch and classify cut a repetition at the same frames, the
    verdict, its confidence and its explanation are classify's, record for record; the
    verdicts are right at about the rate classify's are (benchmarks.repetition_verdicts:
    80 %), and the end summary lists them. Before, watch had no --split (exit 2)."""
    lines, err, offline = watched
    verdicts = [line for line in lines if "repetition" in line]
    assert [v["repetition"] for v in verdicts] == [1, 2, 3, 4]
    for v, (a, b) in zip(verdicts, session["spans"], strict=True):
        overlap = min(b, v["end_frame"]) - max(a, v["start_frame"])
        assert overlap > (b - a) / 2, (v["start_frame"], v["end_frame"], a, b)
    same = {(r["start_frame"], r["end_frame"]): r for r in offline}
    agreed = [v for v in verdicts if (v["start_frame"], v["end_frame"]) in same]
    assert agreed, "at least one repetition cut as classify cuts it"
    for v in agreed:
        r = same[(v["start_frame"], v["end_frame"])]
        # all but the names of the source (a camera's index here, the file and what it was
        # made from there)
        keys = [k for k in r if k not in ("clip", "made_from")]
        assert {k: v[k] for k in keys} == {k: r[k] for k in keys}
    # each verdict is the one classify gives the piece overlapping it most
    for v in verdicts:
        r = max(offline, key=lambda r: min(v["end_frame"], r["end_frame"])
                - max(v["start_frame"], r["start_frame"]))  # fmt: skip
        assert v["label"] == r["label"]
    # three of the four right, against the dataset's labels (classify --split repetitions:
    # 80.1 % of 1,600, README "A patient's session, repetition by repetition")
    right = [v["label"] == t for v, t in zip(verdicts, session["truth"], strict=True)]
    assert sum(right) >= 3, right
    assert f"\n{len(verdicts)} repetitions judged: " in err
    for v in verdicts:
        head = v["text"].splitlines()[0]
        assert (
            f"repetition {v['repetition']}, frames {v['start_frame']}-{v['end_frame'] - 1} "
        ) in err and head in err


def test_a_verdict_comes_as_its_repetition_finishes_not_at_the_end(
    watched: tuple[list[dict[str, Any]], str, list[dict[str, Any]]],
) -> None:
    """The stream is one segment, given at its end: the verdicts of the squats before the
    last are printed before it, each some frames after its repetition ends (the next one
    counted), not when the stream ends."""
    lines, _, _ = watched
    segments = [i for i, line in enumerate(lines) if "repetition" not in line]
    verdicts = [i for i, line in enumerate(lines) if "repetition" in line]
    assert len(verdicts) == 4
    assert verdicts[:3] == [0, 1, 2] and segments[-1] > 2


def test_a_watch_of_a_repetition_check_without_split_points_to_it(
    session: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch`` of a case base trained ``--target correct`` labels 2-s windows correct or
    incorrect; its note says how each repetition is judged instead (before: that the case
    base holds a case per clip and how to train one of windows, which would not help a
    repetition check), and says nothing once ``--split repetitions`` is given."""
    from posecbr.commands.segment import load_case_base, note_not_windows

    stored = load_case_base(session["db"], None)
    capsys.readouterr()
    note_not_windows(stored, session["db"], "watch")
    err = capsys.readouterr().err
    assert err.startswith("note: case base 'default' of ") and err.count("\n") == 1
    assert (
        "predicts 'correct', not activities: watch labels 2-s windows with it; to judge and"
        " explain each repetition as it finishes: add --split repetitions\n"
    ) in err
    note_not_windows(stored, session["db"], "watch", each=True)
    assert capsys.readouterr().err == ""


def test_with_progress_each_line_says_its_event_the_verdicts_otherwise_unchanged(
    watched: tuple[list[dict[str, Any]], str, list[dict[str, Any]]],
) -> None:
    """``--split repetitions`` with ``--progress``: every line says first what it is, the
    four verdicts ``"event": "repetition"`` and the session's one segment ``"segment"``
    (README "Progress lines"); a verdict's fields are otherwise those without it: its
    number and times, then classify's record's fields in their order (all but
    ``made_from``, the file a pose file was made from: a camera's has none)."""
    lines, _, offline = watched
    assert [line["event"] for line in lines].count("repetition") == 4
    assert [line["event"] for line in lines].count("segment") == 1
    assert {line["event"] for line in lines} == {"repetition", "segment"}
    record = [k for k in offline[0] if k != "made_from"]
    for line in lines:
        if line["event"] == "repetition":
            assert list(line) == ["event", "repetition", "start_s", "end_s", *record]
        else:
            assert list(line) == ["event", *SEGMENT_KEYS]
