"""Hunt 39m: ``segment`` and ``watch`` against a case base of whole clips say so.

Found by hunt 39h: ``posecbr segment`` (and ``watch``) against a case base trained with a
case per clip (``train`` without ``--split``) or per repetition (``--split repetitions``)
said nothing of it, though they classify 2-s windows and README measures a case base of
windows segmenting far better (CMU subject 13: 33-61 % of a recording's 0.1-s blocks right
with a case per labelled stretch, 94-99 % with a case per window). The model has recorded
what its cases are since ``train --split`` (``"cases"``: ``"clips"``, ``"repetitions"``,
``"windows"``); now one note on stderr, once per command however many recordings, names
the case base, what its cases are, what to expect (no dataset's figure since hunt 52R) and the
command that trains windows. A case base of
windows, or one stored before the record (no ``"cases"``), says nothing; ``--json``'s
stdout is the same either way.
"""

from __future__ import annotations

import json
import shutil
import sqlite3
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
from tests.badinput import refused

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
SEEN = "deep_squat,side_lunge,standing_shoulder_abduction"
#: two bundled clips of subject s03, whom the case bases hold no case of
RECORDINGS = [DEMO / "m01_s03_e01.npz", DEMO / "m02_s03_e01.npz"]

pytestmark = pytest.mark.xdist_group("hunt39m")  # the case bases trained once for the module


def _train(db: Path, name: str, *split: str) -> None:
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(db), "--name", name,
            "--subjects", "s01,s02", "--labels", SEEN, *split]  # fmt: skip
    assert main(argv) == 0


@pytest.fixture(scope="module")
def stores(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One store per kind of case: ``clips`` (``train`` without ``--split``),
    ``repetitions``, ``windows``, and ``unrecorded``: the clips' store with ``"cases"``
    taken out of its model, as a posecbr before ``train --split`` stored it."""
    folder = tmp_path_factory.mktemp("hunt39m")
    out = {}
    for kind, split in [("clips", ()), ("repetitions", ("--split", "repetitions")),
                        ("windows", ("--split", "windows"))]:  # fmt: skip
        out[kind] = folder / f"{kind}.sqlite"
        _train(out[kind], kind, *split)
    out["unrecorded"] = folder / "unrecorded.sqlite"
    shutil.copyfile(out["clips"], out["unrecorded"])
    con = sqlite3.connect(out["unrecorded"])
    (text,) = con.execute("SELECT model FROM case_bases").fetchone()
    model = json.loads(text)
    assert model["cases"] == "clips"  # what train recorded
    del model["cases"]
    con.execute("UPDATE case_bases SET model = ?", (json.dumps(model),))
    con.commit()
    con.close()
    return out


def _cases(db: Path) -> str | None:
    con = sqlite3.connect(db)
    (text,) = con.execute("SELECT model FROM case_bases").fetchone()
    con.close()
    cases: str | None = json.loads(text).get("cases")
    return cases


def _notes(err: str) -> list[str]:
    return [line for line in err.splitlines() if "--split windows" in line]


def test_the_stores_record_what_their_cases_are(stores: dict[str, Path]) -> None:
    assert {kind: _cases(db) for kind, db in stores.items()} == {
        "clips": "clips",
        "repetitions": "repetitions",
        "windows": "windows",
        "unrecorded": None,
    }


def test_segment_of_two_recordings_against_whole_clips_notes_it_once(
    stores: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    db = stores["clips"]
    capsys.readouterr()
    assert main(["segment", *map(str, RECORDINGS), "--db", str(db)]) == 0
    captured = capsys.readouterr()
    assert _notes(captured.err) == [
        f"note: case base 'clips' of {db} holds a case per clip: segment classifies 2-s "
        "windows of a recording, not whole clips (a clip of many repetitions is one case, far "
        "from any window of it: expect far fewer windows labelled right than with a case per "
        'window; README, "Training from long recordings"); to train a case base of windows: '
        f"posecbr train DATA --db {db} --name NAME --split windows"
    ]
    for path in RECORDINGS:  # both recordings segmented, the note said for neither alone
        assert f"{path}: " in captured.out
    assert "split" not in captured.out


def test_segment_against_repetitions_notes_it_once(
    stores: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    db = stores["repetitions"]
    capsys.readouterr()
    assert main(["segment", *map(str, RECORDINGS), "--db", str(db)]) == 0
    notes = _notes(capsys.readouterr().err)
    assert len(notes) == 1
    assert notes[0].startswith(
        f"note: case base 'repetitions' of {db} holds a case per repetition: segment "
        "classifies 2-s windows of a recording, not whole repetitions (a repetition is one "
        "case from rest to rest, where a window starts anywhere in a movement: expect fewer "
        'windows labelled right than with a case per window; README, "Training from long '
        'recordings"); '
    )


@pytest.mark.parametrize("kind", ["windows", "unrecorded"])
def test_segment_against_windows_or_a_case_base_stored_before_says_nothing(
    stores: dict[str, Path], kind: str, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    assert main(["segment", *map(str, RECORDINGS), "--db", str(stores[kind])]) == 0
    err = capsys.readouterr().err
    assert "case per" not in err and "--split" not in err


def test_segment_json_is_the_same_with_the_note(
    stores: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """The same cases with and without the record: the same JSON on stdout, the note on
    stderr alone."""
    out = {}
    for kind in ("clips", "unrecorded"):
        capsys.readouterr()
        assert main(["segment", *map(str, RECORDINGS), "--db", str(stores[kind]), "--json"]) == 0
        captured = capsys.readouterr()
        out[kind] = captured.out
        assert len(_notes(captured.err)) == (kind == "clips")
    assert out["clips"] == out["unrecorded"]
    assert [d["recording"] for d in json.loads(out["clips"])] == [str(p) for p in RECORDINGS]


def _nobody_stream(n: int, fps: float = 30.0) -> Any:
    """A stand-in for ``stream_poses``: ``n`` frames of a camera with nobody in view."""

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i in range(n):
            image = np.full((33, 5), np.nan)
            pose = FramePose(image, np.full((33, 3), np.nan), False, False, 0.0, None)
            rgb = np.zeros((48, 64, 3), dtype=np.uint8)
            yield StreamFrame(i, i / fps, pose, rgb, time.perf_counter())

    return stream


@pytest.mark.parametrize(
    ("kind", "notes"), [("clips", 1), ("repetitions", 1), ("windows", 0), ("unrecorded", 0)]
)
def test_watch_notes_a_case_base_of_whole_clips_once(
    stores: dict[str, Path],
    kind: str,
    notes: int,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(pose_estimation, "stream_poses", _nobody_stream(90))
    db = stores[kind]
    capsys.readouterr()
    assert main(["watch", "0", "--db", str(db), "--max-frames", "90"]) == 0
    captured = capsys.readouterr()
    got = _notes(captured.err)
    assert len(got) == notes, captured.err
    if notes:
        each = "clip" if kind == "clips" else "repetition"
        assert got[0].startswith(
            f"note: case base {kind!r} of {db} holds a case per {each}: watch classifies "
            f"2-s windows of the stream, not whole {kind} ("
        )
        assert got[0].endswith(f"posecbr train DATA --db {db} --name NAME --split windows")
        # what the user should expect, in general terms: no dataset's measured figure
        assert "labelled right than with a case per window" in got[0]
        assert "%" not in got[0]
    lines = [json.loads(line) for line in captured.out.splitlines()]
    assert [(d["start_frame"], d["end_frame"], d["label"]) for d in lines] == [(0, 90, None)]


def test_watch_of_a_source_that_gives_no_frame_is_refused_in_one_line(
    stores: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The note is said once the work is done: a camera that cannot be opened against a case
    base of whole clips is the one line of its refusal, as against windows."""
    refused(["watch", "2147483648", "--db", str(stores["clips"])], tmp_path, capsys,
            "2147483648: cannot open camera: none at this index")  # fmt: skip
