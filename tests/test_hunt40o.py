"""Hunt 40o, leftovers of the last round: an AMC file with no skeleton beside it was told to
be converted by the commands that take ``--asf`` themselves; ``compare --help`` said "(5)"
where every other command says "(default 5)"; ``compare``'s second results.json write (the
one naming the pictures) refused said "the earlier results.json kept", though this run's
was; ``watch`` stopped by Ctrl-C before its first window was blamed on the stream (exit 1);
``reps`` counted a recording with no hips, no shoulders or at micrometre scale that
``segment`` refused as showing no person."""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import features.fileio as fileio
from features.errors import DataError
from features.poses import save_pose
from features.repetitions import count_repetitions
from features.skeleton import JOINT_INDEX
from posecbr.cli import build_parser, main
from tests.badinput import refused, small_case_base
from tests.test_hunt31c import watch_stops_before_its_first_window

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
AMC = ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\n2\nroot 0 0 0 0 0 0\n"


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


# ---- 1. an AMC file with no skeleton beside it ----------------------------------------------


def _lonely_amc(folder: Path) -> Path:
    """A CMU-named take with no .asf file beside it."""
    folder.mkdir(parents=True, exist_ok=True)
    amc = folder / "13_31.amc"
    amc.write_text(AMC, encoding="utf-8")
    return amc


@pytest.mark.parametrize(
    "command", ["reps", "segment", "describe", "dad", "classify", "train --frame-labels"]
)
def test_a_command_taking_asf_names_asf_for_an_amc_file_with_no_skeleton(
    command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each of these commands reads the skeleton given with ``--asf``: the refusal said to
    run ``posecbr convert FILE.amc --asf SKELETON.asf`` first."""
    amc = _lonely_amc(tmp_path / "rec")
    labels = tmp_path / "rec" / "labels.txt"
    labels.write_text("a a b b\n", encoding="utf-8")
    argv = {
        "reps": ["reps", str(amc)],
        "segment": ["segment", str(amc), "--db", str(case_base)],
        "describe": ["describe", str(amc)],
        "dad": ["dad", str(amc)],
        "classify": ["classify", str(amc), "--db", str(case_base)],
        "train --frame-labels": ["train", str(amc), "--frame-labels", str(labels),
                                 "--label-block", "0.5", "--db", str(tmp_path / "new.sqlite")],
    }[command]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"{amc}: no .asf skeleton file beside it (put the subject's .asf there, or give it:"
        " --asf FILE.asf)"
    ), line
    assert "convert" not in line


def test_a_dataset_folder_of_amc_files_with_no_skeleton_still_names_convert(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A dataset folder takes no ``--asf`` (``train`` refuses it there): ``convert`` of the
    file alone is the way to give the take a skeleton."""
    amc = _lonely_amc(tmp_path / "data" / "jog")
    line = refused(["train", str(tmp_path / "data"), "--db", str(tmp_path / "cb.sqlite")],
                   tmp_path, capsys)  # fmt: skip
    assert line.endswith(
        f"{amc}: no .asf skeleton file beside it (put the subject's .asf there, or convert the"
        " file alone: posecbr convert FILE.amc --asf SKELETON.asf)"
    ), line


# ---- 2. compare --help's defaults -----------------------------------------------------------


@pytest.mark.parametrize(
    ("option", "dest", "value"), [("--folds", "folds", 5), ("--seed", "seed", 0),
                                  ("--explain", "explain", 5)]
)  # fmt: skip
def test_compare_help_says_default_as_every_command_does(
    option: str, dest: str, value: int
) -> None:
    """The default said is the one taken when the option is left out (``--folds``: the
    settings' folds, the option itself left unset so that ``--cv loso`` can refuse it given)."""
    from posecbr.commands.compare import _settings

    parser = build_parser()
    args = parser.parse_args(["compare", "data"])
    assert getattr(_settings(args) if dest == "folds" else args, dest) == value
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    compare = sub.choices["compare"]  # type: ignore[index]
    (action,) = [a for a in compare._actions if option in a.option_strings]
    assert f"(default {value})" in " ".join(str(action.help).split())


# ---- 3. compare: the second results.json write refused --------------------------------------

COMPARE = ["compare", str(DEMO), "--subjects", "s01", "--labels", "deep_squat,sit_to_stand",
           "--folds", "3", "--similarities", "euclidean", "--features", "fluents", "--no-dad",
           "--peers", "none", "--explain", "0"]  # fmt: skip


def test_compare_second_results_json_refused_says_this_runs_file_is_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """results.json is written before the pictures, then again naming them; the disk full
    the second time left this run's first results.json (naming no picture), which the line
    called "the earlier results.json"."""
    real, made = fileio.temporary_file, []

    def temporary_file(dest: str | Path, suffix: str = ".tmp") -> Path:
        if Path(dest).name == "results.json":
            made.append(dest)
            if len(made) == 2:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(dest, suffix)

    monkeypatch.setattr(fileio, "temporary_file", temporary_file)
    out = tmp_path / "o"
    capsys.readouterr()
    assert main([*COMPARE, "--out", str(out)]) == 1
    pictures = sorted(p.name for p in out.glob("*.png"))
    assert len(pictures) >= 2  # a confusion matrix and a timeline at least
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"posecbr compare: error: {out / 'results.json'}: cannot write: the disk is full (No"
        " space left on device): free some space and run again; not written (this run's"
        " results.json kept as it was); no results file names"
        f" the {len(pictures)} pictures drawn into {out}"
    )
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert doc["dataset"]["classes"] == ["deep_squat", "sit_to_stand"]
    assert not any(doc["pictures"].values())
    assert sorted(p.name for p in out.iterdir()) == sorted([*pictures, "results.csv",
                                                            "results.json"])  # fmt: skip


# ---- 4. watch stopped before its first window ------------------------------------------------


@pytest.mark.parametrize(
    ("signum", "status", "said"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated (SIGTERM)")],
)
def test_watch_stopped_by_a_signal_before_its_first_window_says_so(
    signum: int,
    status: int,
    said: str,
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The signal itself, sent as the watch starts (through the command's own handler): it
    exited 1, "the stream ended after 0 frames ..., no segment to give", as if the video had
    been cut short; now as every command stopped so (the shell's 128 + signal)."""
    import posecbr.commands.watch as watch

    real = watch.stop_on_interrupt

    @contextmanager
    def signalled(also: Any = None) -> Iterator[Any]:
        with real(also) as stop:
            os.kill(os.getpid(), signum)
            assert stop.wait(10)
            yield stop

    monkeypatch.setattr(watch, "stop_on_interrupt", signalled)
    watch_stops_before_its_first_window(case_base, tmp_path / "in", capsys, status, said, [])


# ---- 5. reps and segment: one check of the person --------------------------------------------


def _spoiled(kind: str, folder: Path) -> Path:
    """UI-PRMD's deep squat (a real recording, one repetition) with its hips or shoulders
    missing in every frame, or in micrometres."""
    from features.datasets import load_clip

    seq = load_clip(DEMO / "m01_s01_e01.npz").to_canonical()
    p = seq.positions.copy()
    if kind == "micrometres":
        p *= 1e-6
    else:
        for side in ("left", "right"):
            p[:, JOINT_INDEX[f"{side}_{kind[3:-1]}"]] = np.nan
    folder.mkdir(parents=True, exist_ok=True)
    return save_pose(dataclasses.replace(seq, positions=p), folder / f"{kind}.npz")


REASONS = {
    "no_shoulders": "shows no torso (no frame shows its left shoulder, right shoulder)",
    "micrometres": "shows no person (its shoulders or hips lie within 1 µm of each other in"
    " every frame: positions must be metres)",
}


@pytest.mark.parametrize("kind", ["no_shoulders", "micrometres"])
def test_reps_refuses_what_segment_finds_shows_no_person(
    kind: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """README: "the person" is the torso, both shoulders and both hips, without which no
    angle or position has a body frame. ``reps`` counted 1 repetition of each (from the right
    elbow, the knees, the hips' height) where ``segment`` said it shows no person. Since
    session 52 a clip whose hips are seen in no frame but whose shoulders and arms are has
    its arms' repetitions counted, and says so (tests/test_hunt52g.py); since session 53
    ``segment`` labels it from its arms too (tests/test_hunt53g.py)."""
    rec = _spoiled(kind, tmp_path / "rec")
    reason = REASONS[kind]
    refused(["segment", str(rec), "--db", str(case_base)], tmp_path, capsys,
            f"{rec}: {reason}: nothing to segment")  # fmt: skip
    refused(["reps", str(rec)], tmp_path, capsys, f"{rec}: {reason}: nothing to count")
    from features.datasets import load_clip

    with pytest.raises(DataError, match=r"shows no (person|torso) .*: nothing to count"):
        count_repetitions(load_clip(rec))


def test_reps_still_counts_the_whole_recording() -> None:
    """The check refuses nothing that shows the torso: the squat itself is counted."""
    from features.datasets import load_clip

    assert count_repetitions(load_clip(DEMO / "m01_s01_e01.npz")).count == 1
