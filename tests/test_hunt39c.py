"""Hunt 39c: the command line. ``watch -k`` (the neighbours a window votes with, as
``segment -k``); ``segment --truth`` that swallowed the recordings after it; an internal error
said as a bug with its own exit status; options named alike across the commands."""

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
from features.poses import save_pose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows

FPS = 30.0


def _13_30(shared_data: Path) -> Any:
    """CMU 13_30 (another take of the exercises the case base holds), every 4th frame of its
    120 fps: 30 fps, as a camera would deliver it."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    return dataclasses.replace(seq, positions=seq.positions[::4], fps=FPS, confidence=None)


def _camera(world: np.ndarray) -> Any:
    """A stand-in for ``stream_poses``: the frames ``world`` as a camera delivers them."""

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i, joints in enumerate(world):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap)
            pose = FramePose(image, joints, True, False, 1.0, None)
            rgb = np.zeros((48, 64, 3), dtype=np.uint8)
            yield StreamFrame(i, i / FPS, pose, rgb, time.perf_counter())

    return stream


def _no_stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
    raise AssertionError("the stream was opened: the option was not refused before")


def test_watch_k_votes_as_segment_k_does(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``watch -k 5`` lets a window's 5 nearest cases vote (weighted by distance), as
    ``segment -k 5`` does: the same activities, in the same order, as ``segment`` finds in
    the same poses with the same k; and k is heard (the first segment, jumping jacks, is less
    sure with 5 voters than with its nearest case alone, in both). ``watch`` had no -k:
    "unrecognized arguments"."""
    seq = _13_30(shared_data)
    pose = save_pose(seq, tmp_path / "13_30.npz")
    monkeypatch.setattr(pose_estimation, "stream_poses", _camera(seq.positions))
    found: dict[tuple[str, int], list[dict[str, Any]]] = {}
    capsys.readouterr()
    for k in (1, 5):
        assert main(["segment", str(pose), "--db", str(case_base), "-k", str(k), "--json"]) == 0
        found["segment", k] = json.loads(capsys.readouterr().out)["segments"]
        argv = ["watch", "0", "--db", str(case_base), "-k", str(k), "--max-frames", "617"]
        assert main(argv) == 0, capsys.readouterr().err
        found["watch", k] = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    # the exercises of 13_30 in its order (its label file: jumping jacks, twists, knee
    # raises, squats), then a stretch like no activity of 13_29's
    expected = ["JumpJack", "Twist", "KneeRaise", "Squat", "KneeRaise", None]
    for (command, k), segments in found.items():
        assert [s["label"] for s in segments] == expected, (command, k, segments)
        assert segments[-1]["end_frame"] == 617
    for command in ("segment", "watch"):
        one, five = found[command, 1][0]["confidence"], found[command, 5][0]["confidence"]
        assert five < one - 0.05, (command, one, five)


@pytest.mark.parametrize(
    ("k", "said"),
    [
        ("0", "-k: must be >= 1, got 0"),
        ("6", "-k: must be from 1 to the case base's k (5, the nearest cases a window retrieves)"),
    ],
)
def test_watch_refuses_a_k_as_segment_does(
    case_base: Path,  # noqa: F811
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    k: str,
    said: str,
) -> None:
    """A k below 1 or past the case base's own (5) is refused by ``watch`` in the words
    ``segment`` refuses it, before the stream is opened."""
    monkeypatch.setattr(pose_estimation, "stream_poses", _no_stream)
    pose = tmp_path / "p.npz"
    pose.write_bytes(b"")
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(case_base), "-k", k]) == 1
    err = capsys.readouterr().err
    assert err.startswith("posecbr watch: error: ") and err.count("\n") == 1, err
    assert said in err, err
    assert main(["segment", str(pose), "--db", str(case_base), "-k", k]) == 1
    assert said in capsys.readouterr().err


def _13_31(shared_data: Path) -> Any:
    """CMU 13_31 as :func:`_13_30` gives 13_30: 30 fps."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_31.amc",
    )
    return dataclasses.replace(seq, positions=seq.positions[::4], fps=FPS, confidence=None)


def _scored(argv: list[str], capsys: pytest.CaptureFixture[str]) -> Any:
    capsys.readouterr()
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out)


def test_segment_truth_takes_no_recording_after_it(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``segment --truth L.txt REC.npz --db CB`` read REC.npz as a second label file (argparse
    then found no recording: exit 2), and ``segment A --truth LA B --truth LB`` refused "3
    label files for 1 recording". A file named as a recording after ``--truth`` is a
    recording: each form gives what the README's forms give (``REC --truth L``, ``A B
    --truth LA LB``), scores and all."""
    a = save_pose(_13_30(shared_data), tmp_path / "13_30.npz")
    b = save_pose(_13_31(shared_data), tmp_path / "13_31.npz")
    la, lb = (shared_data / "cmu-mocap6" / "truelabels" / f"{r}.txt" for r in ("13_30", "13_31"))
    names = tmp_path / "names.txt"
    names.write_text("1 JumpJack\n2 Jog\n3 Squat\n4 KneeRaise\n5 ArmCircle\n6 Twist\n10 ToeTouch\n")
    tail = ["--db", str(case_base), "--label-block", "0.1", "--label-names", str(names), "--json"]
    one = _scored(["segment", str(a), "--truth", str(la), *tail], capsys)
    assert one["scores"]["truth"] == str(la) and one["scores"]["blocks"] == 206
    assert _scored(["segment", "--truth", str(la), str(a), *tail], capsys) == one
    both = _scored(["segment", str(a), str(b), "--truth", str(la), str(lb), *tail], capsys)
    assert [d["recording"] for d in both] == [str(a), str(b)]
    assert [d["scores"]["truth"] for d in both] == [str(la), str(lb)]
    assert both[0] == one
    alike = ["segment", str(a), "--truth", str(la), str(b), "--truth", str(lb), *tail]
    assert _scored(alike, capsys) == both


def test_segment_truth_of_a_recording_alone_is_refused_as_unreadable(
    case_base: Path,  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--truth REC.npz`` names no label file, and a command line whose every file is a
    label file names no recording: each one line, exit 2 (a command line that cannot be
    read), nothing read or written."""
    rec = tmp_path / "rec.npz"
    rec.write_bytes(b"")
    labels = tmp_path / "labels.txt"
    labels.write_text("1\n")
    for argv, said in (
        (["--truth", str(rec)], f"argument --truth: {rec} is named as a recording, not a label"),
        (["--truth", str(labels)], "the following arguments are required: RECORDING"),
    ):
        capsys.readouterr()
        with pytest.raises(SystemExit) as exit_:
            main(["segment", *argv, "--db", str(case_base)])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and err.count("\n") == 1, err
        assert err.startswith("posecbr segment: error: ") and said in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["labels.txt", "rec.npz"]


def _boom(*args: Any, **kwargs: Any) -> None:
    raise RuntimeError("boom deep inside")


def test_an_internal_error_is_said_as_a_bug_with_its_own_status_writing_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A bug deep inside ``train`` (the store's log, the last write of its transaction,
    raising): exit 70 (sysexits' EX_SOFTWARE; it was 1, as a problem with the input, with a
    raw traceback), one line saying it is a bug in posecbr and naming the file the traceback
    was written to, and the case base as it was (the transaction rolled back)."""
    import tempfile

    import casebase_store.store
    from tests.badinput import small_case_base, snapshot

    db = small_case_base(tmp_path)
    data = tmp_path / "train"
    before = snapshot(tmp_path)
    crashes = tmp_path / "tmp"
    crashes.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(crashes))
    monkeypatch.delenv("POSECBR_DEBUG", raising=False)
    monkeypatch.setattr(casebase_store.store.StoreTransaction, "log", _boom)
    capsys.readouterr()
    argv = ["train", str(data), "--db", str(db), "--name", "second", "--mirror", "off",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    assert main(argv) == 70
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err, captured.err
    line = captured.err.strip()
    assert line.startswith("posecbr train: internal error, a bug in posecbr (RuntimeError: boom")
    (written,) = crashes.iterdir()
    assert f"traceback in {written};" in line and "POSECBR_DEBUG=1 prints it" in line, line
    text = written.read_text()
    assert "Traceback (most recent call last)" in text and "RuntimeError: boom deep inside" in text
    assert "in _boom" in text
    monkeypatch.undo()  # the store as it was: one case base, not "second"
    assert [k for k in snapshot(tmp_path) if not k.startswith("tmp")] == list(before)
    assert main(["casebase", "info", "--db", str(db)]) == 0
    names = [line.split(":")[0] for line in capsys.readouterr().out.splitlines()]
    assert "default" in names and "second" not in names, names


def test_posecbr_debug_prints_the_traceback(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``POSECBR_DEBUG=1``: the traceback on stderr, then the line; no file written."""
    import tempfile

    import features.fluents
    from tests.badinput import good_pose_file

    pose = good_pose_file(tmp_path / "clip.npz")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("POSECBR_DEBUG", "1")
    monkeypatch.setattr(features.fluents, "evaluate", _boom)
    capsys.readouterr()
    assert main(["describe", str(pose)]) == 70
    err = capsys.readouterr().err
    assert err.startswith("Traceback (most recent call last)"), err
    assert err.strip().splitlines()[-1] == (
        "posecbr describe: internal error, a bug in posecbr (RuntimeError: boom deep inside)"
    )
    assert [p.name for p in tmp_path.iterdir()] == ["clip.npz"]


def test_an_internal_error_in_a_process_exits_70(tmp_path: Path) -> None:
    """The same in a real process (``sys.exit(main())``, as the console script runs it)."""
    import os
    import subprocess
    import sys

    from tests.badinput import ROOT, good_pose_file

    pose = good_pose_file(tmp_path / "clip.npz")
    code = (
        "import sys, features.fluents as f\n"
        "def boom(*a, **k): raise ZeroDivisionError('deep')\n"
        "f.evaluate = boom\n"
        "from posecbr.cli import main\n"
        f"sys.exit(main(['describe', {str(pose)!r}]))\n"
    )
    env = {**os.environ, "TMPDIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    env.pop("POSECBR_DEBUG", None)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 70, proc.stderr
    assert proc.stdout == "" and proc.stderr.count("\n") == 1, proc.stderr
    assert "internal error, a bug in posecbr (ZeroDivisionError: deep)" in proc.stderr
    (written,) = tmp_path.glob("posecbr-bug-*.txt")
    assert "ZeroDivisionError: deep" in written.read_text()


def test_the_exit_statuses_are_listed_alike_in_help_and_readme(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``posecbr --help`` and the README name 70, the status of an internal error."""
    from tests.badinput import ROOT

    with pytest.raises(SystemExit):
        main(["--help"])
    said = " ".join(capsys.readouterr().out.split())
    assert "70 an internal error, a bug in posecbr" in said, said
    assert "POSECBR_DEBUG=1" in said
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert "70 an internal error, a bug in posecbr" in readme


@pytest.mark.parametrize(
    ("error", "status", "said"),
    [
        (OSError(28, "No space left on device", "out.png"), 1, "out.png: cannot write: the disk"),
        (PermissionError(13, "Permission denied", "cb.sqlite"), 1, "error: cb.sqlite: Permission"),
        (MemoryError(), 1, "error: out of memory"),
        (OSError(9, "Bad file descriptor"), 70, "a bug in posecbr (OSError: [Errno 9] Bad file"),
    ],
)
def test_the_system_failing_is_no_bug(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    error: BaseException,
    status: int,
    said: str,
) -> None:
    """A full disk, a file posecbr may not write, memory run out: the system's refusal, said
    in one line, exit 1 (they were raw tracebacks); another OSError is a bug (exit 70)."""
    import tempfile

    import features.fluents
    from tests.badinput import good_pose_file

    pose = good_pose_file(tmp_path / "clip.npz")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.delenv("POSECBR_DEBUG", raising=False)

    def fail(*args: Any, **kwargs: Any) -> None:
        raise error

    monkeypatch.setattr(features.fluents, "evaluate", fail)
    capsys.readouterr()
    assert main(["describe", str(pose)]) == status
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("posecbr describe: "), err
    assert said in err, err


def test_thresholds_takes_the_file_by_describes_name_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``describe --thresholds FILE`` takes the overrides that ``thresholds --from FILE``
    checks: ``thresholds --thresholds FILE`` was "unrecognized arguments", as was ``thresholds
    --json`` (its table is JSON: taken, changing nothing)."""
    overrides = tmp_path / "mine.json"
    overrides.write_text('{"epsilon": 0.002}\n')
    capsys.readouterr()
    assert main(["thresholds", "--from", str(overrides)]) == 0
    table = json.loads(capsys.readouterr().out)
    assert table["epsilon"] == 0.002
    assert main(["thresholds", "--thresholds", str(overrides)]) == 0
    assert json.loads(capsys.readouterr().out) == table
    assert main(["thresholds", "--json", "--thresholds", str(overrides)]) == 0
    assert json.loads(capsys.readouterr().out) == table


def test_watch_takes_json_as_segment_does(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``watch --json`` (as ``segment --json``): its JSON lines, as without it; it was
    "unrecognized arguments: --json"."""
    world = _13_30(shared_data).positions[:120]
    monkeypatch.setattr(pose_estimation, "stream_poses", _camera(world))
    lines = {}
    for extra in ([], ["--json"]):
        capsys.readouterr()
        assert main(["watch", "0", "--db", str(case_base), "--max-frames", "120", *extra]) == 0
        lines[bool(extra)] = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert lines[True] == lines[False] and lines[True][-1]["end_frame"] == 120


def test_every_option_of_every_command_is_in_the_readme() -> None:
    """Each option ``posecbr COMMAND --help`` lists is named in the README (by one of its
    spellings): eleven were not (``classify --novelty``/``--benefit``, ``compare
    --folds``/``--similarities``, ``convert --float32``, ``demo --data``, ``describe
    --min-confidence``, ``extract --detect-every-frame``, ``train --no-summary``, ``watch
    --show``/``--max-frames``)."""
    import argparse
    import re

    from posecbr.cli import build_parser
    from tests.badinput import ROOT

    readme = (ROOT / "README.md").read_text()
    missing = []

    def walk(name: str, parser: argparse.ArgumentParser) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for child, sub in action.choices.items():
                    walk(f"{name} {child}", sub)
            elif action.option_strings and "--help" not in action.option_strings:
                named = [
                    re.search(re.escape(o) + r"(?![\w-])", readme) for o in action.option_strings
                ]
                if not any(named):
                    missing.append(f"{name} {'/'.join(action.option_strings)}")

    walk("posecbr", build_parser())
    assert missing == [], missing
