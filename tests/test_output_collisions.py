"""Inputs that would make outputs collide, count a clip twice or run nothing are refused in one
line before any work: two rows of a labels CSV written to one pose file (``extract``) or
listed twice (``classify``), an empty method list (``compare``), results whose values are out
of range or disagree with each other (``report``), an option that would be ignored
(``classify --subjects`` of pose files) and an output in a missing folder."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import cv2
import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_cbr_cli import _write_classes

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _short_video(shared_data: Path, out: Path, frames: int = 20) -> Path:
    """The first ``frames`` frames of a real lunge video."""
    source = sorted((shared_data / "videos" / "lunge").glob("*.mp4"))[0]
    cap = cv2.VideoCapture(str(source))
    writer = None
    for _ in range(frames):
        ok, frame = cap.read()
        assert ok
        if writer is None:
            h, w = frame.shape[:2]
            writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (w, h))
        writer.write(frame)
    cap.release()
    assert writer is not None
    writer.release()
    return out


# ---------------------------------------------------------------------------- extract


@pytest.mark.parametrize(
    ("rows", "needles"),
    [
        (["short.mp4,lunge,p1,0,10", "short.mp4,lunge,p2,0,10"],
         ["frames 0-10 (subject p1) and", "frames 0-10 (subject p2)", "both would be written to",
          "short_0-10.npz"]),
        (["short.mp4,lunge,p1,0,10", "short.mp4,lunge,p1,0,10"],
         ["short.mp4 frames 0-10 (subject p1) is listed twice", "short_0-10.npz"]),
    ],
    ids=["two subjects", "the same row twice"],
)  # fmt: skip
def test_extract_refuses_two_rows_written_to_one_pose_file(
    tmp_path: Path,
    shared_data: Path,
    capsys: pytest.CaptureFixture[str],
    rows: list[str],
    needles: list[str],
) -> None:
    _short_video(shared_data, tmp_path / "short.mp4")
    csv = tmp_path / "coll2.csv"
    csv.write_text("\n".join(["path,label,subject,start,end", *rows]) + "\n")
    refused(["extract", str(csv), "--out", str(tmp_path / "ecoll2")], tmp_path, capsys,
            str(csv), *needles)  # fmt: skip


def test_extract_refuses_a_pose_file_in_a_missing_folder(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = _short_video(shared_data, tmp_path / "short.mp4", frames=2)
    refused(["extract", str(video), "--out", str(tmp_path / "missing" / "dir" / "x.npz")],
            tmp_path, capsys, "the folder of the pose file does not exist",
            str(tmp_path / "missing" / "dir"))  # fmt: skip


# ---------------------------------------------------------------------------- classify


# on one xdist worker: the module's case_base made once, not once per worker
pytestmark = pytest.mark.xdist_group("output_collisions")


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A small case base trained from synthetic arm movements, and clips to classify."""
    base = tmp_path_factory.mktemp("cb")
    data = _write_classes(base / "train", 3, 5)
    db = base / "cb.sqlite"
    code = main(["train", str(data), "--db", str(db), "--mirror", "off",
                 "--feature-weights", "none", "--phases", "0"])  # fmt: skip
    assert code == 0
    return db, _write_classes(base / "test", 1, 6)


def test_classify_refuses_a_clip_listed_twice(
    case_base: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db, test = case_base
    clip = sorted(test.rglob("*.npz"))[0]
    csv = tmp_path / "labels.csv"
    row = f"{clip},{clip.parent.name},s01"
    csv.write_text(f"path,label,subject\n{row}\n{row}\n")
    capsys.readouterr()
    refused(["classify", str(csv), "--db", str(db)], tmp_path, capsys,
            f"{csv}: {clip} frames", "is listed twice: it would be classified and counted twice",
            )  # fmt: skip


def test_classify_refuses_subjects_for_pose_files(
    case_base: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db, test = case_base
    clip = sorted(test.rglob("*.npz"))[0]
    capsys.readouterr()
    refused(["classify", str(clip), "--db", str(db), "--subjects", "s02"], test, capsys,
            "--subjects", "filters the clips of a labels CSV or dataset")  # fmt: skip
    refused(["classify", str(clip.parent), "--db", str(db), "--subjects", "s02"], test, capsys,
            "--subjects")  # fmt: skip


# ---------------------------------------------------------------------------- compare


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--similarities", ","], "--similarities: no similarity given"),
        (["--similarities", ""], "--similarities: no similarity given"),
        (["--features", ","], "--features: no feature level given"),
    ],
)
def test_compare_refuses_an_empty_method_list(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], needle: str
) -> None:
    argv = ["compare", str(DEMO), "--no-dad", "--peers", "none", "--json",
            str(tmp_path / "empty.json"), *flags]  # fmt: skip
    refused(argv, tmp_path, capsys, needle)


# ---------------------------------------------------------------------------- report


def _results() -> dict[str, Any]:
    """A small valid results document: two clips of two classes, one method."""
    clips = [
        {"id": "a.npz", "label": "squat", "subject": "s01", "target": "squat"},
        {"id": "b.npz", "label": "lunge", "subject": "s02", "target": "lunge"},
    ]
    rate = {"n": 1, "recall": 1.0, "ci": [0.2, 1.0]}
    method = {
        "name": "cbr fluents/euclidean", "kind": "cbr", "interpretable": True,
        "params": {"features": "fluents", "similarity": "euclidean", "k": 1, "trim": None},
        "status": "ok", "message": "", "accuracy": 1.0, "accuracy_ci": [0.34, 1.0],
        "macro_f1": 1.0, "macro_f1_ci": [1.0, 1.0],
        "per_class": {"lunge": rate, "squat": rate}, "per_group": {},
        "confusion": [[1, 0], [0, 1]], "unassigned": [0, 0], "fit_s": 0.1, "predict_s": 0.2,
        "predict_ms_per_clip": 100.0, "case_base_size": 1.0, "training_size": 1.0,
        "predictions": ["squat", "lunge"], "correct": [True, True], "fold_notes": [],
    }  # fmt: skip
    return {
        "kind": "posecbr-compare",
        "created_utc": "2026-01-01T00:00:00Z",
        "machine": {"python": "3.11", "platform": "Linux", "cpu_count": 2},
        "dataset": {
            "source": "labels.csv",
            "n_clips": 2,
            "subjects": ["s01", "s02"],
            "classes": ["lunge", "squat"],
            "class_counts": {"lunge": 1, "squat": 1},
            "activities": ["lunge", "squat"],
        },  # fmt: skip
        "settings": {"target": "label", "within": None},
        "cv": {"scheme": "loso", "n_folds": 2, "fold_of_clip": [0, 1]},
        "notes": [],
        "clips": clips,
        "methods": [method],
        "best": "cbr fluents/euclidean",
        "best_interpretable": "cbr fluents/euclidean",
        "explanations": [],
        "pictures": {},
    }


def test_report_of_the_valid_results_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    results = tmp_path / "r.json"
    results.write_text(json.dumps(_results()))
    assert main(["report", str(results), "--out", str(tmp_path / "r.html")]) == 0
    assert (tmp_path / "r.html").is_file()


def _set(path: tuple[Any, ...], value: Any) -> Any:
    def edit(doc: dict[str, Any]) -> None:
        for key in path[:-1]:
            doc = doc[key]
        doc[path[-1]] = value

    return edit


BAD = [
    ("no method", _set(("methods",), []), "key 'methods' lists no method: nothing to report"),
    ("accuracy above 1", _set(("methods", 0, "accuracy"), 7.5),
     "key 'methods[0].accuracy' must be in [0, 1], got 7.5"),
    ("accuracy NaN", _set(("methods", 0, "accuracy"), math.nan),
     "key 'methods[0].accuracy' must be in [0, 1], got nan"),
    ("macro-F1 below 0", _set(("methods", 0, "macro_f1"), -0.5),
     "key 'methods[0].macro_f1' must be in [0, 1], got -0.5"),
    ("recall above 1", _set(("methods", 0, "per_class", "lunge", "recall"), 2),
     "key 'methods[0].per_class.lunge.recall' must be in [0, 1], got 2.0"),
    ("negative fit time", _set(("methods", 0, "fit_s"), -1),
     "key 'methods[0].fit_s' must be a finite number of 0 or more, got -1.0"),
    ("infinite time per clip", _set(("methods", 0, "predict_ms_per_clip"), math.inf),
     "key 'methods[0].predict_ms_per_clip' must be a finite number of 0 or more, got inf"),
    ("ragged confusion", _set(("methods", 0, "confusion"), [[1, 0], [1]]),
     "key 'methods[0].confusion' must be 2 x 2 (the classes), got 2 rows of 1/2"),
    ("confusion of three rows", _set(("methods", 0, "confusion"), [[1, 0], [0, 1], [0, 0]]),
     "key 'methods[0].confusion' must be 2 x 2 (the classes), got 3 rows of 2"),
    ("predictions short", _set(("methods", 0, "predictions"), ["squat"]),
     "key 'methods[0].predictions' must hold one per clip (2), got 1"),
    ("best names no method", _set(("best",), "nobody"),
     "key 'best' names no method of the results, got 'nobody'"),
    ("best interpretable names no method", _set(("best_interpretable",), "x"),
     "key 'best_interpretable' names no method of the results, got 'x'"),
]  # fmt: skip


@pytest.mark.parametrize(("edit", "message"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_report_refuses_values_out_of_range(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], edit: Any, message: str
) -> None:
    doc = _results()
    edit(doc)
    results = tmp_path / "r.json"
    results.write_text(json.dumps(doc))
    line = refused(["report", str(results), "--out", str(tmp_path / "r.html")], tmp_path,
                   capsys, message)  # fmt: skip
    assert line == f"posecbr report: error: {results}: {message}"
