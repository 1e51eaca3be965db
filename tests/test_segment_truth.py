"""``posecbr segment --truth``: a segmentation scored against the recording's own label file,
as ``benchmarks.segment`` scores it (CMU 13_30 segmented with a case base of 13_29 and 13_31,
the case base of tests/test_segment.py), the figures worked out here again by hand from the
``--json`` segments and the label file; and the label files it refuses."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.badinput import refused
from tests.test_segment import NAMES, case_base, names, recordings  # noqa: F401 (fixtures)

CODES = dict(line.split(" ", 1) for line in NAMES.splitlines())


def _labels(path: Path) -> list[str]:
    """The codes of a cmu-mocap6 label file, read by hand."""
    return path.read_text(encoding="utf-8").split()


def _block_labels(segments: list[dict[str, Any]], n_blocks: int) -> list[object]:
    """The label of every 0.1-s block at 120 fps (12 frames): that of the segment holding its
    first frame (None: unknown)."""
    out: list[object] = []
    for b in range(n_blocks):
        frame = 12 * b
        out.append(next(s["label"] for s in segments if s["start_frame"] <= frame < s["end_frame"]))
    return out


def _by_hand(
    segments: list[dict[str, Any]], truth: list[str], known: set[str]
) -> tuple[int, int, int, int, list[float]]:
    """Seen blocks and those right, unseen blocks and those called unknown, and each change's
    distance to the nearest segment start after the first, in seconds."""
    pred = _block_labels(segments, len(truth))
    seen = [t in known for t in truth]
    right = sum(p == t for p, t, s in zip(pred, truth, seen, strict=True) if s)
    unseen_unknown = sum(p is None for p, s in zip(pred, seen, strict=True) if not s)
    starts = np.array([s["start_frame"] / 120.0 for s in segments[1:]])
    changes = [0.1 * i for i in range(1, len(truth)) if truth[i] != truth[i - 1]]
    errors = [float(np.min(np.abs(starts - c))) for c in changes]
    return sum(seen), right, len(truth) - sum(seen), unseen_unknown, errors


KNOWN = {"JumpJack", "Jog", "Squat", "KneeRaise", "ArmCircle", "Twist", "ToeTouchOneHand"}


def test_segment_scores_13_30_against_its_label_file(
    recordings: dict[str, PoseSequence],  # noqa: F811
    case_base: Path,  # noqa: F811
    names: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """13_30's label codes per 0.1 s through the names file: every exercise is in the case
    base; the --json scores are the shares and distances worked out from its segments."""
    rec = save_pose(recordings["13_30"], tmp_path / "13_30.npz")
    truth_file = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    capsys.readouterr()
    argv = ["segment", str(rec), "--db", str(case_base), "--truth", str(truth_file)]
    argv += ["--label-block", "0.1", "--label-names", str(names)]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    codes = _labels(truth_file)
    n_blocks = -(-2465 // 12)  # 206 blocks of 12 frames, the last partial
    truth = [CODES[c] for c in codes[:n_blocks]]
    seen, right, unseen, unseen_unknown, errors = _by_hand(doc["segments"], truth, KNOWN)
    scores = doc["scores"]
    assert scores["truth"] == str(truth_file)
    assert (scores["blocks"], scores["block_s"]) == (n_blocks, 0.1)
    assert (scores["seen_blocks"], scores["seen_right"]) == (seen, right) == (n_blocks, right)
    assert scores["seen_accuracy"] == pytest.approx(right / n_blocks)
    assert right / n_blocks > 0.9  # 99.0 % when written: a sanity bound, not the figure
    assert (scores["unseen_labels"], scores["unseen_blocks"]) == ([], 0)
    assert scores["unseen_unknown_share"] is None
    assert len(errors) == 4  # Jump Jack, Twist, Knee Raise, Squat, Jog: four changes
    assert scores["boundary_errors_s"] == pytest.approx(errors)
    assert scores["median_boundary_error_s"] == pytest.approx(float(np.median(errors)))
    # the text: the same figures under the segments
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert f"against {truth_file}: {n_blocks} blocks of 0.1 s" in text
    share = f"{right} of {n_blocks} blocks labelled right ({100 * right / n_blocks:.1f} %)"
    assert f"labels the case base has: {share}" in text
    assert "labels it lacks: none in the truth" in text
    assert (
        f"labelled changes: 4, the nearest segment boundary a median {np.median(errors):.2f} s"
        f" away (at most {max(errors):.2f} s)"
    ) in text


def test_segment_scores_a_label_the_case_base_lacks_per_frame(
    recordings: dict[str, PoseSequence],  # noqa: F811
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """One label per frame, by name (no names file), Jog renamed Skipping: its blocks are of a
    label the case base lacks and score as called unknown or not; the others as before."""
    rec = save_pose(recordings["13_30"], tmp_path / "13_30.npz")
    codes = _labels(shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt")
    per_frame = [codes[f // 12] for f in range(2465)]
    renamed = ["Skipping" if CODES[c] == "Jog" else CODES[c] for c in per_frame]
    truth_file = tmp_path / "truth.txt"
    truth_file.write_text("\n".join(renamed) + "\n", encoding="utf-8")
    capsys.readouterr()
    argv = ["segment", str(rec), "--db", str(case_base), "--truth", str(truth_file), "--json"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert "note:" not in captured.err  # the case base has six of its labels (hunt 38z)
    scores = doc["scores"]
    assert main(argv[:-1]) == 0
    text = capsys.readouterr().out
    truth = [renamed[12 * b] for b in range(206)]  # each block's first frame
    seen, right, unseen, unseen_unknown, errors = _by_hand(doc["segments"], truth, KNOWN)
    assert unseen == truth.count("Skipping") > 0
    assert (scores["seen_blocks"], scores["seen_right"]) == (seen, right)
    assert (scores["unseen_labels"], scores["unseen_blocks"]) == (["Skipping"], unseen)
    assert scores["unseen_called_unknown"] == unseen_unknown
    assert scores["boundary_errors_s"] == pytest.approx(errors)
    line = next(ln for ln in text.splitlines() if "labels it lacks" in ln)
    assert line.strip() == (
        f"labels it lacks (Skipping): {unseen_unknown} of {unseen} blocks called unknown"
        f" ({100 * unseen_unknown / unseen:.1f} %)"
    )


ACTIVITIES = "ArmCircle, Jog, JumpJack, KneeRaise, Squat, ToeTouchOneHand and Twist"  # KNOWN


def test_segment_truth_of_codes_without_names_is_noted(
    recordings: dict[str, PoseSequence],  # noqa: F811
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """13_30's label file read without ``--label-names`` holds codes 1, 2, 3, 4 and 6, none
    an activity of the case base: every block was scored as a label the case base lacks
    without a word. One note on stderr now names the case base's activities and, the labels
    being whole numbers, ``--label-names``; the scores are what they were (worked out by
    hand: no block seen, every one of a label it lacks)."""
    rec = save_pose(recordings["13_30"], tmp_path / "13_30.npz")
    truth_file = shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt"
    capsys.readouterr()
    argv = ["segment", str(rec), "--db", str(case_base), "--truth", str(truth_file)]
    argv += ["--label-block", "0.1"]
    assert main([*argv, "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    codes = _labels(truth_file)
    assert len(codes) == 206
    seen, _, unseen, unseen_unknown, errors = _by_hand(doc["segments"], codes, KNOWN)
    scores = doc["scores"]
    assert (seen, unseen) == (0, 206)
    assert (scores["seen_blocks"], scores["seen_right"], scores["seen_accuracy"]) == (0, 0, None)
    assert (scores["unseen_labels"], scores["unseen_blocks"]) == (["1", "2", "3", "4", "6"], 206)
    assert scores["unseen_called_unknown"] == unseen_unknown
    assert scores["boundary_errors_s"] == pytest.approx(errors)
    note = (
        f"note: {truth_file}: none of its labels (1, 2, 3, 4 and 6) is an activity of the case"
        f" base ({ACTIVITIES}): every block is scored as a label it lacks; if they are codes,"
        " --label-names FILE names them"
    )
    assert captured.err.splitlines() == [note]
    assert main(argv) == 0  # the text: the same note
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [note]
    assert "labels the case base has: none in the truth" in captured.out
    # labels by name, none the case base's: noted, without --label-names
    words = tmp_path / "walk.txt"
    words.write_text("Walk\n" * 1233 + "Run\n" * 1232, encoding="utf-8")  # one per frame
    assert main(["segment", str(rec), "--db", str(case_base), "--truth", str(words)]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"note: {words}: none of its labels (Run and Walk) is an activity of the case base"
        f" ({ACTIVITIES}): every block is scored as a label it lacks"
    ]


def _setup(recs: dict[str, PoseSequence], shared_data: Path, root: Path) -> tuple[Path, Path]:
    root.mkdir()
    rec = save_pose(recs["13_30"], root / "13_30.npz")
    truth = root / "13_30.txt"
    truth.write_bytes((shared_data / "cmu-mocap6" / "truelabels" / "13_30.txt").read_bytes())
    return rec, truth


def test_segment_truth_refuses_a_count_that_does_not_fit_writing_nothing(
    recordings: dict[str, PoseSequence],  # noqa: F811
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """206 labels per 0.1 s read as one per frame (2465 frames need 2465 or 2466), and as
    0.2-s blocks (103 need): one line naming the label file, no picture."""
    root = tmp_path / "in"
    rec, truth = _setup(recordings, shared_data, root)
    plot = root / "timeline.png"
    base = ["segment", str(rec), "--db", str(case_base), "--truth", str(truth), "--json"]
    line = refused([*base, "--plot", str(plot)], root, capsys, str(truth), "206 labels")
    assert "do not fit the recording" in line and "2465 frames" in line
    refused([*base, "--label-block", "0.2"], root, capsys, str(truth), "need 103")


def test_segment_truth_refuses_bad_options_and_files(
    recordings: dict[str, PoseSequence],  # noqa: F811
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    root = tmp_path / "in"
    rec, truth = _setup(recordings, shared_data, root)
    seg = ["segment", str(rec), "--db", str(case_base)]
    refused([*seg, "--label-block", "0.1"], root, capsys, "--label-block", "goes with --truth")
    refused([*seg, "--label-names", str(truth)], root, capsys, "--label-names", "--truth")
    refused([*seg, "--truth", str(truth), "--label-block", "0"], root, capsys, "--label-block")
    # one label file for two recordings, and two for one
    two = ["segment", str(rec), str(rec), "--db", str(case_base), "--truth", str(truth)]
    refused(two, root, capsys, "--truth", "1 label file for 2 recordings")
    line = refused([*seg, "--truth", str(truth), str(truth)], root, capsys, "--truth")
    assert re.search(r"2 label files for 1 recording\b", line), line
    # a label file as a spreadsheet saves it, and a code the names file does not name
    bad = root / "semicolons.txt"
    bad.write_text("1;1;6;6\n", encoding="utf-8")
    refused([*seg, "--truth", str(bad)], root, capsys, str(bad), "';'")
    few = root / "few.txt"
    few.write_text("1 JumpJack\n", encoding="utf-8")
    refused(
        [*seg, "--truth", str(truth), "--label-block", "0.1", "--label-names", str(few)],
        root,
        capsys,
        str(truth),
        "not in the label names",
    )
    refused([*seg, "--truth", str(root / "none.txt")], root, capsys, "no such label file")
    # the picture may not be written over the label file
    refused([*seg, "--truth", str(truth), "--plot", str(truth)], root, capsys, str(truth))
