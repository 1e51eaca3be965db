"""Hunt 38k: training from long recordings in Python as ``posecbr train`` does.

A Python user (README "From your own pose tracker's arrays") had :func:`cbr.training.train`
of whole clips only: nothing cut a clip into the 2-s windows ``segment`` and ``watch``
classify (``train --split windows``, the default for a recording labelled over time) or into
its repetitions (``--split repetitions``), nor a recording into its labelled stretches
(``--frame-labels`` with ``--label-block``). :func:`cbr.training.cut` and
:func:`cbr.training.cut_recording` give the cases the command makes: both call
:func:`features.repetitions.cut_clips`."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.estimator import CaseBaseClassifier
from cbr.stored import load_classifier
from cbr.training import cut, cut_recording, train
from features.datasets import load_clip
from features.errors import InputError
from features.poses import PoseSequence, save_pose
from posecbr.cli import main
from tests.once import made_once
from tests.test_repetitions import _movement
from tests.test_segment import NAMES, _cmu

CODES = dict(line.split(" ", 1) for line in NAMES.splitlines())
SQUATS = "squat/tfjs_pose_squats_pexels4838220.mp4"  # 65 frames at 5 fps, three squats


@pytest.fixture(scope="module")
def recordings(
    shared_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> dict[str, PoseSequence]:
    """CMU 13_29, 13_30 and 13_31, read once in the session (as tests/test_segment.py)."""
    return made_once(tmp_path_factory, "cmu-13-29-31", lambda _: _cmu(shared_data))


def _cases(
    db: Path, name: str = "default"
) -> tuple[list[str], list[tuple[int, int]], bytes, CaseBaseClassifier]:
    with open_store(db, readonly=True) as store:
        clf = load_classifier(store, name).classifier
    cb = clf.case_base_
    labels = [str(v) for v in cb.labels]
    frames = [(int(a), int(b)) for a, b in cb.frames]
    return labels, frames, np.ascontiguousarray(cb.problems).tobytes(), clf


def _windows_of(codes: list[str], n_frames: int) -> list[tuple[str, tuple[int, int]]]:
    """Worked out from the label file alone: 0.1-s blocks of 12 frames at 120 fps, each run
    of one code a stretch (the last to the recording's end); stretches under 0.4 s (48
    frames) left out, one under 2 s (240 frames) kept whole, else a 240-frame window every
    60 frames that fits."""
    out = []
    change = [0] + [i for i in range(1, len(codes)) if codes[i] != codes[i - 1]]
    starts = [12 * i for i in change]
    ends = [*starts[1:], n_frames]
    for i, a, b in zip(change, starts, ends, strict=True):
        name = CODES[codes[i]]
        if b - a < 48:
            continue
        if b - a < 240:
            out.append((name, (a, b)))
            continue
        out += [(name, (s, s + 240)) for s in range(a, b - 240 + 1, 60)]
    return out


def _readme_block(first: str) -> str:
    """The README's ```python block holding the line ``first``, as written."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    at = text.index(first)
    start = text.rindex("```python\n", 0, at) + len("```python\n")
    return text[start : text.index("```", at)]


def test_a_recording_cut_in_python_stores_the_cases_train_stores(
    recordings: dict[str, PoseSequence],
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """CMU 13_29 with its 0.1-s labels: ``posecbr train --frame-labels`` (windows, the
    default) and ``cut_recording`` + ``train(cases="windows")`` store the same cases (count,
    labels, frame spans, problem bytes), those the label file says, as does the README's
    example with the labels per frame in memory, and ``segment`` of 13_30 answers the same
    with either case base."""
    rec = save_pose(recordings["13_29"], tmp_path / "13_29.npz")
    labels = shared_data / "cmu-mocap6" / "truelabels" / "13_29.txt"
    names = tmp_path / "names.txt"
    names.write_text(NAMES, encoding="utf-8")
    by_command, by_python = tmp_path / "command.sqlite", tmp_path / "python.sqlite"
    argv = ["train", str(rec), "--frame-labels", str(labels), "--label-block", "0.1"]
    assert main([*argv, "--label-names", str(names), "--db", str(by_command)]) == 0

    pieces, solutions = cut_recording(load_clip(rec), labels, block_s=0.1, names=names)
    estimator = CaseBaseClassifier(feature_weights="none")  # as train --split windows
    train(by_python, "default", pieces, solutions, estimator, cases="windows")

    expected = _windows_of(labels.read_text().split(), recordings["13_29"].n_frames)
    assert len(expected) == 56  # the command said "cut 6 clips into 56 windows"
    command, python = _cases(by_command), _cases(by_python)
    assert list(zip(command[0], command[1], strict=True)) == expected
    assert python[:3] == command[:3]
    assert python[3].weighting_ == command[3].weighting_ == "none"

    # the label codes given in memory, one per block, cut the same
    codes = labels.read_text().split()
    again = cut_recording(load_clip(rec), [int(c) for c in codes], block_s=0.1,
                          names={int(k): v for k, v in CODES.items()})  # fmt: skip
    assert again[1] == solutions
    assert [p.metadata["frame_offset"] for p in again[0]] == [a for _, (a, _) in expected]

    # the README's example as written, the labels per frame in memory (named already)
    per_frame = [
        CODES[codes[min(f // 12, len(codes) - 1)]] for f in range(recordings["13_29"].n_frames)
    ]
    monkeypatch.chdir(tmp_path)
    names_in: dict[str, object] = {
        "seq": load_clip(rec),
        "per_frame_labels": per_frame,
        "CaseBaseClassifier": CaseBaseClassifier,
        "train": train,
    }
    exec(_readme_block("pieces, piece_labels = cut_recording("), names_in)
    assert _cases(tmp_path / "robot.sqlite", "live")[:3] == command[:3]

    other = save_pose(recordings["13_30"], tmp_path / "13_30.npz")
    docs, tables = [], []
    for db in (by_command, by_python):
        capsys.readouterr()
        assert main(["segment", str(other), "--db", str(db), "--json"]) == 0
        docs.append(json.loads(capsys.readouterr().out))
        assert main(["segment", str(other), "--db", str(db)]) == 0
        tables.append(capsys.readouterr().out)
    assert docs[0] == docs[1] and tables[0] == tables[1]
    assert len(docs[0]["segments"]) > 1


def test_clips_cut_into_repetitions_in_python_store_the_cases_train_stores(
    bundled_poses: Callable[[str], PoseSequence], tmp_path: Path
) -> None:
    """A folder per activity: the squat video's poses (three squats; the session's poses of
    it, as ``extract`` finds them) and arms raised four times (by construction). ``posecbr
    train --split repetitions`` and ``cut`` + ``train(cases="repetitions")`` store the same
    seven cases: 3 squats, 4 raises."""
    data = tmp_path / "data"
    (data / "squat").mkdir(parents=True)
    (data / "raise").mkdir()
    squats = save_pose(bundled_poses(SQUATS), data / "squat" / "squats.npz")
    raises = save_pose(_movement(["both"] * 4), data / "raise" / "raises.npz")
    by_command, by_python = tmp_path / "command.sqlite", tmp_path / "python.sqlite"
    assert main(["train", str(data), "--split", "repetitions", "--db", str(by_command)]) == 0

    clips = [load_clip(raises), load_clip(squats)]
    pieces, labels = cut(clips, ["raise", "squat"], "repetitions")
    assert labels == ["raise"] * 4 + ["squat"] * 3
    train(by_python, "default", pieces, labels, CaseBaseClassifier(), cases="repetitions")

    command, python = _cases(by_command), _cases(by_python)
    assert sorted(command[0]) == ["raise"] * 4 + ["squat"] * 3
    assert python[:3] == command[:3]
    spans = dict(zip(command[1], command[0], strict=True))
    assert len(spans) == 7  # seven distinct stretches, each one repetition


def test_windows_of_whole_clips_keep_the_labels_as_given() -> None:
    """Two clips of 342 frames at 30 fps: floor((342 - 60) / 15) + 1 = 19 windows each, the
    first starting at frames 0, 15, ...; each window labelled with its clip's label, of
    whatever type it was given (a whole number stays one)."""
    clip = _movement(["both"] * 6)
    assert (clip.n_frames, clip.fps) == (342, 30.0)
    pieces, labels = cut([clip, clip], ["up", 7], "windows")
    assert labels == ["up"] * 19 + [7] * 19 and isinstance(labels[-1], int)
    assert [p.metadata.get("frame_offset", 0) for p in pieces[:19]] == list(range(0, 271, 15))
    assert {p.n_frames for p in pieces} == {60}
    whole, same = cut([clip], ["up"], "clips")
    assert same == ["up"] and whole[0] is clip


@pytest.mark.parametrize(
    ("call", "argument"),
    [
        (lambda s: cut(s, ["a"], "window"), "split"),
        (lambda s: cut(s, ["a", "b"], "windows"), "labels"),
        (lambda s: cut(s, [None], "windows"), "labels"),
        (lambda s: cut(s[0], ["a"], "windows"), "clips"),
        (lambda s: cut([s[0].positions], ["a"], "windows"), "clips"),
        (lambda s: cut_recording(s[0].positions, ["a"] * 342), "recording"),
        (lambda s: cut_recording(s[0], ["a"] * 342, "frames"), "split"),
        (lambda s: cut_recording(s[0], ["a"] * 342, block_s=0), "block_s"),
        (lambda s: cut_recording(s[0], ["a"] * 342, block_s=float("nan")), "block_s"),
        (lambda s: cut_recording(s[0], ["a"] * 342, block_s=True), "block_s"),
        (lambda s: cut_recording(s[0], ["a"] * 342, names=3), "names"),
        (lambda s: cut_recording(s[0], ["a"] * 10), "frame_labels"),
        (lambda s: cut_recording(s[0], [1.5] * 342), "frame_labels"),
        (lambda s: cut_recording(s[0], [""] * 342), "frame_labels"),
        (lambda s: cut_recording(s[0], 5), "frame_labels"),
        (lambda s: cut_recording(s[0], ["a"] * 342, names={"b": "B"}), "frame_labels"),
        (lambda s: cut_recording(s[0], ["a", "b"] * 171), "frame_labels"),  # all flicker
    ],
)
def test_bad_arguments_are_input_errors_naming_them(
    call: object, argument: str, tmp_path: Path
) -> None:
    """Each bad argument is an InputError (a ValueError) naming it, before anything is cut:
    nothing reaches a store."""
    db = tmp_path / "cb.sqlite"
    with pytest.raises(InputError) as err:
        pieces, labels = call([_movement(["both"] * 6)])  # type: ignore[operator]
        train(db, "default", pieces, labels, CaseBaseClassifier(), cases="windows")
    assert err.value.source == argument, err.value
    assert str(err.value).startswith(f"{argument}: ")
    assert not db.exists()


def test_labels_in_memory_that_do_not_fit_read_no_file_of_their_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """400 labels for a recording of 342 frames at 30 fps, which needs 342 or 343: the refusal
    gives the count's likely reason from the labels alone. A file named ``frame_labels`` in
    the working folder, 342 lines of which one has a space (the "labels with spaces" reason
    a label FILE gets), is not the caller's labels, and is not read: before, the message
    said "its 342 lines would", of that unrelated file."""
    monkeypatch.chdir(tmp_path)
    Path("frame_labels").write_text("sit down\n" + "a\n" * 341, encoding="utf-8")
    with pytest.raises(InputError) as err:
        cut_recording(_movement(["both"] * 6), ["a"] * 400)
    assert err.value.source == "frame_labels"
    assert "400 labels" in str(err.value) and "need 342 or 343" in str(err.value)
    assert str(err.value).endswith("(another frame rate or label block?)"), err.value
    assert "lines" not in str(err.value)
