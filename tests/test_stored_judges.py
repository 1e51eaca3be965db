"""The unknown judges stored with the fitted model (issue 14): calibrated once when ``train``
stores a model, read back by ``segment`` and ``watch`` instead of scanning the case base at
every start; a case base whose cases change keeps no stale judge; a damaged stored judge is
refused in one line. The case base: ``train --split windows`` on two subjects of the bundled
UI-PRMD Kinect subset, three movements; the recording: the third subject's real repetitions of
two of them and of a movement the case base lacks, joined."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

import cbr.unknown
import cbr.unknown_judges
from casebase_store import NewCase, open_store
from cbr.segmentation import finish, solve_recording
from cbr.stored import load_classifier
from cbr.unknown import (
    AT_FIT,
    STORED,
    Calibrated,
    Margin,
    calibrate_judges,
    judge_of,
    judges_from_dict,
    judges_to_dict,
)
from features.joining import join_repetitions
from features.poses import load_pose, save_pose
from posecbr.cli import main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
SEEN = "deep_squat,standing_shoulder_abduction,side_lunge"

pytestmark = pytest.mark.xdist_group("stored-judges")  # one trained case base for the module


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


def _sql(db: Path, sql: str) -> None:
    con = sqlite3.connect(db)
    con.execute(sql)
    con.commit()
    con.close()


def _model(db: Path) -> dict[str, object]:
    con = sqlite3.connect(db)
    (text,) = con.execute("SELECT model FROM case_bases").fetchone()
    con.close()
    doc: dict[str, object] = json.loads(text)
    return doc


@pytest.fixture(scope="module")
def trained(seen_windows: Path) -> Path:
    """``train --split windows`` on s01 and s02's SEEN (tests/conftest.py, made once)."""
    return seen_windows


@pytest.fixture(scope="module")
def trained_clips(seen_clips: Path) -> Path:
    """As ``trained``, a case per clip: feedback is given to case bases of whole clips
    (tests/conftest.py, made once)."""
    return seen_clips


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Subject s03 (not in the case base): two squats, two side lunges, two hurdle steps (a
    movement the case base lacks), real repetitions joined one after the other."""
    names = [f"m{m}_s03_e0{e}.npz" for m in ("01", "04", "02") for e in (1, 2)]
    joined = join_repetitions([load_pose(DEMO / n) for n in names]).seq
    return save_pose(joined, tmp_path_factory.mktemp("rec") / "s03.npz")


@dataclasses.dataclass(frozen=True)
class _Toy(Calibrated):
    """A judge as another helper might add one: every kind of field, one with a default."""

    limit: float
    count: int
    basis: str
    rate: float = 0.25


def test_a_judge_is_stored_as_a_record_of_its_fields() -> None:
    toy = _Toy(float("inf"), 3, "subject", 0.5)
    record = toy.to_dict()
    assert record == {"limit": "inf", "count": 3, "basis": "subject", "rate": 0.5}
    assert json.loads(json.dumps(record, allow_nan=False)) == record  # plain JSON: no Infinity
    assert _Toy.from_dict(record) == toy
    # a record stored before a field with a default was added takes the default
    assert _Toy.from_dict({"limit": 1, "count": 0, "basis": "time"}) == _Toy(1.0, 0, "time")
    for bad, field in (
        ({"limit": "x", "count": 3, "basis": "b"}, "'limit' must be a number >= 0"),
        ({"limit": float("nan"), "count": 3, "basis": "b"}, "'limit' must be a number >= 0"),
        ({"limit": -1.0, "count": 3, "basis": "b"}, "'limit' must be a number >= 0"),
        ({"limit": 1.0, "count": 2.5, "basis": "b"}, "'count' must be a whole number"),
        ({"limit": 1.0, "count": True, "basis": "b"}, "'count' must be a whole number"),
        ({"limit": 1.0, "count": 3, "basis": ""}, "'basis' must be a non-empty text"),
        ({"limit": 1.0, "basis": "b"}, "field 'count' is missing"),
        ({"limit": 1.0, "count": 3, "basis": "b", "new": 1}, "unknown field 'new'"),
    ):
        with pytest.raises(ValueError, match=field):
            _Toy.from_dict(bad)
    with pytest.raises(ValueError, match="unknown judge 'toy'"):
        judges_from_dict({"toy": record})


def test_the_stored_judges_are_the_ones_calibrated_fresh_on_the_case_base(
    trained: Path,
) -> None:
    store = open_store(trained, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert set(clf.judges_) == set(AT_FIT)  # three activities: the margins calibrate
    for name, judge in clf.judges_.items():
        assert judge == STORED[name].of(clf.case_base_), name
    margin = clf.judges_["margin"]
    assert isinstance(margin, Margin) and margin.basis == "subject"  # two subjects
    again = judges_from_dict(json.loads(json.dumps(judges_to_dict(clf.judges_))))
    assert again == clf.judges_
    # two activities cannot calibrate the margins (a held-out activity leaves one): fit
    # stores the judge that can be calibrated and leaves the others to say why at run time
    cb = clf.case_base_
    two = cb.subset(np.flatnonzero(cb.labels.astype(str) != "side_lunge"))
    assert set(calibrate_judges(two)) == {"activities"}
    assert calibrate_judges(two, AT_FIT) == {}


def _segment(
    capsys: pytest.CaptureFixture[str], rec: Path, db: Path, judge: str
) -> dict[str, object]:
    capsys.readouterr()
    assert main(["segment", str(rec), "--db", str(db), "--unknown", judge, "--json"]) == 0
    doc: dict[str, object] = json.loads(capsys.readouterr().out)
    return doc


def test_segment_answers_the_same_with_the_stored_judge_without_scanning(
    trained: Path,
    recording: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A model stored before judges were (its judges removed) calibrates at run time; the
    stored one answers the same, and segment then scans no held-out case. The default judge
    through the command; the other stored one finishes the same solved windows."""
    old = _copy(trained, tmp_path / "old.sqlite")
    _sql(old, "UPDATE case_bases SET model = json_remove(model, '$.judges')")
    fresh = _segment(capsys, recording, old, "margin")
    store = open_store(old, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert clf.judges_ == {}
    done = solve_recording(clf, load_pose(recording))
    calibrated = {j: finish(clf, done, judge_of(clf, j)).to_dict() for j in AT_FIT}

    def no_scan(*args: object, **kwargs: object) -> None:
        raise AssertionError("calibrated at run time")

    # the judges calibrate themselves in cbr.unknown_judges (their `of`)
    monkeypatch.setattr(cbr.unknown_judges, "held_out_activities", no_scan)
    monkeypatch.setattr(cbr.unknown_judges, "_neighbour_distances", no_scan)
    before = _sha(trained)
    assert _segment(capsys, recording, trained, "margin") == fresh
    assert _sha(trained) == before  # segment writes nothing
    store = open_store(trained, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    for j, doc in calibrated.items():
        assert finish(clf, done, judge_of(clf, j)).to_dict() == doc, j
    labels = [s["label"] for s in fresh["segments"]]  # type: ignore[index]
    assert "deep_squat" in labels and "side_lunge" in labels  # a real segmentation


def _judges_now(db: Path) -> dict[str, Calibrated]:
    store = open_store(db, create=False, readonly=True)
    try:
        stored = load_classifier(store, "default")
    finally:
        store.close()
    judges: dict[str, Calibrated] = stored.classifier.judges_
    return judges


def test_trim_recalibrates_the_stored_judges_on_the_cases_it_keeps(
    trained: Path, tmp_path: Path
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    before = _judges_now(db)
    assert main(["casebase", "trim", "--db", str(db), "--keep", "0.6"]) == 0
    store = open_store(db, create=False, readonly=True)
    try:
        stored = load_classifier(store, "default")
    finally:
        store.close()
    clf = stored.classifier
    assert stored.version == 2 and _model(db)["judges"]["case_base_version"] == 2  # type: ignore[index]
    assert set(clf.judges_) == set(before)
    for name, judge in clf.judges_.items():
        assert judge == STORED[name].of(clf.case_base_), name
    assert clf.judges_["margin"].known < before["margin"].known  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("base", "argv"),
    [
        # a new activity's first clip is always retained
        ("trained_clips",
         ["classify", str(DEMO / "m02_s03_e01.npz"), "--feedback", "hurdle_step", "--new-label"]),
        ("trained", ["train", str(LABELS), "--append", "--subjects", "s03", "--labels",
                     "deep_squat"]),
    ],
    ids=["feedback", "append"],
)  # fmt: skip
def test_a_change_of_the_cases_drops_the_stored_judges_in_its_transaction(
    request: pytest.FixtureRequest, recording: Path, tmp_path: Path, base: str, argv: list[str]
) -> None:
    db = _copy(request.getfixturevalue(base), tmp_path / "cb.sqlite")
    assert "judges" in _model(db)
    assert main([*argv, "--db", str(db)]) == 0
    assert "judges" not in _model(db)
    assert _judges_now(db) == {}
    assert main(["segment", str(recording), "--db", str(db)]) == 0  # calibrated at run time


def test_feedback_to_a_case_base_of_windows_is_refused_and_writes_nothing(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip retained whole among windows would be a case of another kind: refused in one
    line pointing to ``train --append``, which cuts it into windows."""
    db = _copy(trained, tmp_path / "cb.sqlite")
    before = _sha(db)
    capsys.readouterr()
    argv = ["classify", str(DEMO / "m02_s03_e01.npz"), "--feedback", "deep_squat", "--db", str(db)]
    assert main(argv) == 1
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert "case base 'default' holds windows (trained with --split windows)" in err
    assert "posecbr train CLIP --append" in err
    assert _sha(db) == before
    assert main(["classify", str(DEMO / "m02_s03_e01.npz"), "--db", str(db)]) == 0  # no feedback


def test_a_judge_of_another_version_of_the_cases_is_not_read(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A change made past the commands (the store's own API) leaves the judges stored, but
    stamped with the version of the cases they were calibrated on: not read."""
    db = _copy(trained, tmp_path / "cb.sqlite")
    store = open_store(db, create=False)
    try:
        width = len(store.get_case_base("default").feature_names)
        store.add_cases("default", [NewCase("deep_squat", np.zeros(width), source="x")])
    finally:
        store.close()
    assert "judges" in _model(db)
    assert _judges_now(db) == {}
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db), "--json"]) == 0
    judges = json.loads(capsys.readouterr().out)["case_bases"][0]["model"]["unknown_judges"]
    assert judges["current"] is False and set(judges["calibrated"]) == set(AT_FIT)
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert "the cases changed since: calibrated at run time" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("margin.threshold", "'x'", "margin: field 'threshold' must be a number >= 0, got 'x'"),
        # the default judge's budget thresholds for one activity where the case base has several
        ('"activity-margin".budget_thresholds', "json('[0.5]')",
         "field 'budget_thresholds' has 1 values for"),
    ],
)  # fmt: skip
def test_a_damaged_stored_judge_is_one_line_and_the_database_stays(
    trained: Path,
    recording: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    field: str,
    value: str,
    message: str,
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    path = f"'$.judges.calibrated.{field}'"
    _sql(db, f"UPDATE case_bases SET model = json_set(model, {path}, {value})")
    before = _sha(db)
    capsys.readouterr()
    assert main(["segment", str(recording), "--db", str(db), "--json"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("posecbr segment: error: ") and str(db) in err
    assert "case base 'default' has a damaged unknown judge calibration" in err
    assert message in err
    assert _sha(db) == before
