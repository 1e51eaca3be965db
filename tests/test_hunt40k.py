"""Hunt 40k: ``classify`` takes ``--asf`` and ``--fps`` as ``train``, ``segment``, ``reps``,
``describe`` and ``dad`` do (an AMC file's skeleton, a recording's frame rate): an AMC file
with no skeleton beside it could not be classified, nor one at another rate than 120 fps,
without converting it first."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import pytest

from cbr.classification import FeedbackSettings
from cbr.estimator import CaseBaseClassifier
from posecbr.cli import build_parser, main
from posecbr.recordings import load_recording
from tests.once import made_once

NAMES = ["1 JumpJack", "2 Jog", "3 Squat", "4 KneeRaise", "5 ArmCircle", "6 Twist"]


def _head(amc: Path, frames: int, out: Path) -> Path:
    """The first ``frames`` frames of the AMC file ``amc`` (its header and each frame's
    number line and bone lines), written to ``out``."""
    kept: list[str] = []
    seen = 0
    for line in amc.read_text().splitlines(keepends=True):
        if line.strip().isdigit():
            seen += 1
            if seen > frames:
                break
        kept.append(line)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("".join(kept))
    return out


def _made(folder: Path, shared: Path) -> tuple[Path, Path, Path]:
    """CMU 13_31's first 1500 frames (no skeleton beside it), the HDM05 skeleton CMU's takes
    are read with, and a case base of 13_30's first 6 s (720 frames at 120 fps, 60 labels
    of 0.1 s: jumping jacks, then twists) trained with ``--asf``."""
    cmu = shared / "cmu-mocap6"
    asf = shared / "hdm05" / "train" / "3" / "HDM_bd.asf"
    train = _head(cmu / "amc" / "13_30.amc", 720, folder / "train" / "13_30.amc")
    labels = (cmu / "truelabels" / "13_30.txt").read_text().split()[:60]
    (folder / "t.txt").write_text(" ".join(labels) + "\n")
    (folder / "names.txt").write_text("\n".join(NAMES) + "\n")
    db = folder / "cb.sqlite"
    argv = ["train", str(train), "--frame-labels", str(folder / "t.txt"), "--label-block",
            "0.1", "--label-names", str(folder / "names.txt"), "--asf", str(asf), "--db",
            str(db)]  # fmt: skip
    assert main(argv) == 0
    rec = _head(cmu / "amc" / "13_31.amc", 1500, folder / "rec" / "13_31.amc")
    return rec, asf, db


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory, shared_data: Path) -> tuple[Path, Path, Path]:
    return made_once(tmp_path_factory, "hunt40k", lambda f: _made(f, shared_data))


def _answer(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, Any]:
    capsys.readouterr()
    assert main(["classify", *argv, "--json"]) == 0
    (record,) = json.loads(capsys.readouterr().out)["results"]
    near = [(n["case_id"], pytest.approx(n["distance"], rel=1e-9)) for n in record["neighbours"]]
    return {"label": record["label"], "confidence": record["confidence"], "near": near}


@pytest.mark.parametrize("fps", [None, "60"])
def test_an_amc_file_is_classified_with_asf_and_fps_as_its_converted_pose_file(
    made: tuple[Path, Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    fps: str | None,
) -> None:
    """The same answer as the pose file ``convert --asf --fps`` makes of it (the way the
    error on a missing skeleton named, before); the rate given is the pose file's."""
    rec, asf, db = made
    rate = [] if fps is None else ["--fps", fps]
    assert main(["convert", str(rec), "--asf", str(asf), "--out", str(tmp_path), *rate]) == 0
    converted = _answer(capsys, str(tmp_path / "13_31.npz"), "--db", str(db))
    given = _answer(capsys, str(rec), "--asf", str(asf), *rate, "--db", str(db))
    assert given["label"] == converted["label"] and given["near"] == converted["near"]
    assert given["confidence"] == pytest.approx(converted["confidence"], rel=1e-9)


@pytest.mark.parametrize(("fps", "seconds"), [(None, "12.5"), ("100", "15.0"), ("240", None)])
def test_fps_sets_the_rate_a_clip_is_timed_at(
    made: tuple[Path, Path, Path],
    capsys: pytest.CaptureFixture[str],
    fps: str | None,
    seconds: str | None,
) -> None:
    """1500 frames last 12.5 s at CMU's 120 fps, 15 s at 100 fps, 6.25 s at 240 fps: the
    note on a clip longer than five 2-s windows comes for the first two alone."""
    rec, asf, db = made
    rate = [] if fps is None else ["--fps", fps]
    assert main(["classify", str(rec), "--asf", str(asf), *rate, "--db", str(db), "-q"]) == 0
    err = capsys.readouterr().err
    if seconds is None:
        assert "longer than" not in err
    else:
        assert f"1 clip lasts longer than 10 s ({seconds} s)" in err


def test_asf_and_fps_are_checked_as_the_other_commands_check_them(
    made: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec, asf, db = made
    cases = [
        (["--fps", "0"], "--fps: must be a frame rate in [0.01, 10000], got 0"),
        (["--asf", str(asf)], "--asf: goes with an AMC recording, not t.txt"),
    ]
    for extra, said in cases:
        clips = [str(rec)] if extra[0] == "--fps" else [str(db.parent / "t.txt")]
        capsys.readouterr()
        assert main(["classify", *clips, "--db", str(db), *extra]) == 1
        assert f"posecbr classify: error: {said}" in capsys.readouterr().err
    # a folder's clips are each read as they are: the rate would be said of none
    capsys.readouterr()
    argv = ["classify", str(rec), str(rec.parent), "--db", str(db), "--fps", "60"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "--fps: goes with clip files, not the folder rec" in err
    assert len(err.strip().splitlines()) == 1


def test_segment_refusing_labels_says_the_rate_an_amc_file_was_read_at_was_assumed(
    made: tuple[Path, Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Hunt 49h: 0.1-s labels made for a recording taken at 60 fps (its 1500 frames 25 s,
    250 labels) do not fit an AMC file, which carries no rate, read at 120 fps (12.5 s: 125
    or 126 labels). The refusal said "1500 frames at 120 fps need 125 or 126 (another frame
    rate or label block?)", the 120 fps taken for the file's; now it says the rate was
    assumed."""
    rec, asf, db = made
    truth = db.parent / "t250.txt"
    truth.write_text(" ".join(["6"] * 250) + "\n")
    names = str(db.parent / "names.txt")
    argv = ["segment", str(rec), "--asf", str(asf), "--db", str(db), "--truth", str(truth),
            "--label-block", "0.1", "--label-names", names, "--unknown", "held-out"]  # fmt: skip
    capsys.readouterr()
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and str(truth) in err and "13_31.amc" in err
    assert "1500 frames at 120 fps (assumed: AMC files carry no rate" in err
    assert "need 125 or 126" in err


def _parsers() -> dict[str, argparse.ArgumentParser]:
    """Every command's parser by its name (``casebase trim`` for a subcommand's)."""
    found: dict[str, argparse.ArgumentParser] = {}

    def walk(name: str, parser: argparse.ArgumentParser) -> None:
        found[name] = parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for child, sub in action.choices.items():
                    walk(f"{name} {child}".strip(), sub)

    walk("", build_parser())
    return found


def test_every_usage_line_fits_an_80_column_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    """segment's and watch's usage lines ran to 120 and 118 columns: ``--unknown`` listed its
    seven rules there; they are named in its help."""
    monkeypatch.setenv("COLUMNS", "80")
    long = {
        name: max(len(line) for line in parser.format_usage().splitlines())
        for name, parser in _parsers().items()
    }
    assert {name: n for name, n in long.items() if n > 80} == {}


def _help(command: str, option: str) -> str:
    (action,) = [a for a in _parsers()[command]._actions if option in a.option_strings]
    return " ".join(str(action.help).split())


@pytest.mark.parametrize(
    ("command", "option", "said"),
    [
        ("classify", "--novelty", f"(default {FeedbackSettings().novelty_threshold:g})"),
        ("classify", "--benefit", f"(default {FeedbackSettings().benefit_threshold:g})"),
        ("train", "--length", f"(default {CaseBaseClassifier().length})"),
        ("train", "--features", f"(default {CaseBaseClassifier().features})"),
        ("casebase trim", "--keep", "(default 0.7)"),
        ("train", "--label-block", "(default: one label per frame)"),
        ("segment", "--label-block", "(default: one label per frame)"),
        ("watch", "--max-frames", "(default: no limit)"),
        ("convert", "--limit", "(default: no limit)"),
        ("classify", "--subjects", "(default all)"),
        ("classify", "--fps", "frames per second"),
        ("segment", "--fps", "the rate its HDM05 name states, else 120"),
        ("compare", "--folds", "(default 5)"),
        ("compare", "--seed", "(default 0)"),
        ("compare", "--explain", "(default 5)"),
    ],
)
def test_an_options_help_says_its_default_and_unit(command: str, option: str, said: str) -> None:
    """The defaults said are the code's own (the estimator's, the feedback settings'; 0.7 is
    what ``casebase trim`` keeps of each activity when ``--keep`` is left out)."""
    assert said in _help(command, option)


def test_an_hdm05_name_states_the_rate_fps_defaults_to(shared_data: Path, tmp_path: Path) -> None:
    """What ``--fps``'s help says of its default: an HDM05 take named ``..._120.amc`` is read
    at 120 fps, the same take named ``..._60.amc`` at 60."""
    take = shared_data / "hdm05" / "train" / "3" / "HDM_bd_grabHighR_001_120.amc"
    asf = take.parent / "HDM_bd.asf"
    renamed = tmp_path / "HDM_bd_grabHighR_001_60.amc"
    renamed.write_bytes(take.read_bytes())
    assert load_recording(take, asf).fps == 120.0
    assert load_recording(renamed, asf).fps == 60.0
