"""Hunt 38d: a model stored by this posecbr, read by an older one.

Hunt 37m made the judges with a threshold per activity store the activities they were
calibrated on (field ``activities``) in their records. posecbr at 9e02354, before that,
refused such a model whole: ``classify``, ``segment``, anything that loads it, said
"case base 'default' has a damaged unknown judge calibration (activity-margin: unknown field
'activities')" -- two machines of one lab running different versions against one PostgreSQL
case base. That reader refuses a judge record with a field it does not know, but reads of
the model document only the keys it names (``model.get``) and of its ``judges`` only
``case_base_version`` and ``calibrated``: the activities are now stored there, in
``added_fields``, apart from the records.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any

import pytest

from casebase_store import open_store
from cbr.stored import load_classifier
from cbr.unknown import (
    STORED,
    ActivityMargin,
    SpreadMargin,
    judge_of,
    judges_from_dict,
)
from posecbr.cli import main
from tests.badinput import refused

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
SEEN = "standing_shoulder_abduction,deep_squat,side_lunge"
ACTIVITIES = ["deep_squat", "side_lunge", "standing_shoulder_abduction"]  # sorted as text

#: The fields 9e02354 reads of each stored judge's record (listed in the test below).
_ACTIVITY = {"thresholds", "pooled", "basis", "known", "false_unknown", "prior", "rate",
             "budget_thresholds", "floor", "reach"}  # fmt: skip
OLD_FIELDS = {
    "margin": {"threshold", "basis", "known", "novel", "false_unknown", "floor", "reach"},
    "margin-distance": {"margin", "joint_margin", "joint_distance", "basis", "known",
                        "false_unknown"},
    "activity-margin": _ACTIVITY,
    "spread-margin": _ACTIVITY | {"spreads", "power"},
    "spread-far": _ACTIVITY | {"spreads", "power", "far"},
}  # fmt: skip
#: What 9e02354's cbr/stored.py reads of the model document's ``judges``
#: (``stored["case_base_version"]``, ``stored["calibrated"]``); any other key is ignored.
OLD_JUDGES_KEYS = {"case_base_version", "calibrated"}


@pytest.fixture(scope="module")
def trained(seen_clips: Path) -> Path:
    """Whole clips of SEEN's three movements of s01 and s02 (tests/conftest.py's seen_clips,
    made once in the session)."""
    return seen_clips


def _model(db: Path) -> dict[str, Any]:
    con = sqlite3.connect(db)
    (text,) = con.execute("SELECT model FROM case_bases").fetchone()
    con.close()
    doc: dict[str, Any] = json.loads(text)
    return doc


def _set_model(db: Path, model: dict[str, Any]) -> None:
    con = sqlite3.connect(db)
    con.execute("UPDATE case_bases SET model = ?", (json.dumps(model),))
    con.commit()
    con.close()


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


def _judges(db: Path) -> dict[str, Any]:
    store = open_store(db, create=False, readonly=True)
    try:
        return dict(load_classifier(store, "default").classifier.judges_)
    finally:
        store.close()


def test_the_stored_judges_have_only_the_fields_an_older_posecbr_reads(trained: Path) -> None:
    """Each stored judge's record has exactly the fields posecbr at 9e02354 accepted, listed
    by hand from its cbr/unknown.py (the dataclass fields of each class in STORED;
    Calibrated.from_dict refuses any other, "unknown field ..."):

    - margin (Margin): threshold, basis, known, novel, false_unknown, floor, reach;
    - margin-distance (MarginDistance): margin, joint_margin, joint_distance, basis, known,
      false_unknown;
    - activity-margin (ActivityMargin): thresholds, pooled, basis, known, false_unknown,
      prior, rate, budget_thresholds, floor, reach;
    - spread-margin (SpreadMargin): those of ActivityMargin, spreads, power;
    - spread-far (SpreadFar): those of SpreadMargin, far.

    Of the model's ``judges`` its cbr/stored.py reads ``case_base_version`` and
    ``calibrated`` (``stored[...]``), nothing else; of the model itself only the keys it
    names (``model.get``). The judges' document holds beside those two keys only
    ``added_fields``, with the activities in the classifier's class order (sorted as
    text)."""
    judges = _model(trained)["judges"]
    assert set(judges) == OLD_JUDGES_KEYS | {"added_fields"}
    records = judges["calibrated"]
    assert set(records) == set(OLD_FIELDS)
    for name, record in records.items():
        assert set(record) == OLD_FIELDS[name], name
    per_activity = {"activity-margin", "spread-margin", "spread-far"}
    assert judges["added_fields"] == {n: {"activities": ACTIVITIES} for n in per_activity}


def test_the_stored_judges_read_back_with_their_activities(
    trained: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Read back, each judge is the one calibrated fresh on the stored case base, the
    activities included; ``casebase info --json`` shows them among each judge's fields."""
    store = open_store(trained, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    for name, judge in clf.judges_.items():
        assert judge == STORED[name].of(clf.case_base_), name
    spread = clf.judges_["spread-margin"]
    assert isinstance(spread, SpreadMargin) and spread.activities == tuple(ACTIVITIES)
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(trained), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)["case_bases"][0]["model"]["unknown_judges"]
    assert shown["calibrated"]["spread-far"]["activities"] == ACTIVITIES
    assert "activities" not in shown["calibrated"]["margin"]


def test_models_stored_before_read_as_they_did(trained: Path, tmp_path: Path) -> None:
    """A model stored by hunt 37m's posecbr (the activities in each record, no
    ``added_fields``) reads the same judges; one stored before 37m (no activities at all)
    reads judges without names, which judge_of names from the model's own case base."""
    now = _judges(trained)
    model = _model(trained)
    judges = model["judges"]
    inline = {
        n: {**r, **judges["added_fields"].get(n, {})} for n, r in judges["calibrated"].items()
    }
    db = _copy(trained, tmp_path / "37m.sqlite")
    _set_model(db, {**model, "judges": {"case_base_version": judges["case_base_version"],
                                        "calibrated": inline}})  # fmt: skip
    assert _judges(db) == now
    before = {k: v for k, v in judges.items() if k != "added_fields"}
    _set_model(db, {**model, "judges": before})
    unnamed = _judges(db)
    margin = unnamed["activity-margin"]
    assert isinstance(margin, ActivityMargin) and margin.activities == ()
    store = open_store(db, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert judge_of(clf, "activity-margin") == now["activity-margin"]


def test_a_field_a_newer_posecbr_stores_apart_is_ignored(trained: Path, tmp_path: Path) -> None:
    """What a later posecbr adds to ``added_fields`` (a field this one does not know, the
    fields of a judge it does not store where this one reads judges) is left out, as 9e02354
    leaves out ``added_fields`` itself; the fields this one knows are read."""
    model = _model(trained)
    model["judges"]["added_fields"]["spread-margin"]["coming"] = [1, 2, 3]
    model["judges"]["added_fields"]["a-later-judge"] = {"activities": ["x"]}
    db = _copy(trained, tmp_path / "cb.sqlite")
    _set_model(db, model)
    assert _judges(db) == _judges(trained)


@pytest.mark.parametrize(
    ("added", "message"),
    [
        (3, "the judges' fields stored apart must be a record by name, got 3"),
        ({"spread-margin": {"activities": 1}},
         "spread-margin: field 'activities' must be a list of texts, got 1"),
        ({"spread-margin": {"thresholds": [0.5, 0.5, 0.5]}},
         "spread-margin: field 'thresholds' is stored twice (in the record and apart)"),
        ({"spread-margin": {"activities": ["a", "b"]}},
         "spread-margin: field 'activities' has 2 values for 3 activities"),
    ],
)  # fmt: skip
def test_damaged_fields_stored_apart_are_refused_in_one_line(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    added: Any,
    message: str,
) -> None:
    model = _model(trained)
    model["judges"]["added_fields"] = added
    root = tmp_path / "db"
    root.mkdir()
    db = _copy(trained, root / "cb.sqlite")
    _set_model(db, model)
    clip = str(DEMO / "m01_s03_e01.npz")
    damaged = "case base 'default' has a damaged unknown judge calibration"
    refused(["classify", clip, "--db", str(db)], root, capsys, str(db), damaged, message)


def test_judges_apart_and_back() -> None:
    """:func:`judges_apart` moves the fields marked as added out of each record (and leaves
    out a judge with none); :func:`judges_from_dict` joins them back; a field marked as kept
    in the record is refused when found apart."""
    from cbr.unknown import judges_apart  # added by this hunt: the other tests run on before

    judge = ActivityMargin((0.5, 0.6), 0.7, "subject", 10, activities=("a", "b"))
    records, apart = judges_apart({"activity-margin": judge})
    assert "activities" not in records["activity-margin"]
    assert apart == {"activity-margin": {"activities": ["a", "b"]}}
    assert judges_from_dict(records, apart) == {"activity-margin": judge}
    unnamed = ActivityMargin((0.5, 0.6), 0.7, "subject", 10)
    assert judges_apart({"activity-margin": unnamed})[1] == {"activity-margin": {"activities": []}}
    without = {k: v for k, v in records["activity-margin"].items() if k != "pooled"}
    with pytest.raises(ValueError, match="field 'pooled' is stored apart, where it is not kept"):
        judges_from_dict({"activity-margin": without}, {"activity-margin": {"pooled": 0.7}})


# ``train --trim 0.5 --editor cnn`` took --trim and ignored it (the share kept is
# novelty-benefit's: CNN, RENN and ICF decide how many cases they keep), where ``casebase
# trim --keep`` with those editors is refused; and a CNN that kept fewer cases than k was
# refused advising "keep more with --trim", which changes nothing for it.


def test_train_refuses_trim_with_an_editor_that_decides_how_many_it_keeps(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(tmp_path / "cb.sqlite"),
            "--editor", "cnn", "--trim", "0.5"]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line == (
        "posecbr train: error: --trim: goes with --editor novelty-benefit; cnn decides how"
        " many cases it keeps"
    )


def test_fit_refuses_trim_with_another_editor_and_a_stored_model_with_both_loads(
    trained: Path, tmp_path: Path
) -> None:
    """In Python the same at fit (before any clip is read); a model stored with both (they
    were taken) still loads, its parameters as they were."""
    from cbr.estimator import CaseBaseClassifier
    from features.errors import ConfigError
    from features.poses import load_pose

    X = [load_pose(DEMO / f"m0{m}_s01_e01.npz") for m in (1, 4, 6)]
    with pytest.raises(ConfigError) as err:
        CaseBaseClassifier(trim=0.5, editor="renn").fit(X, ["a", "b", "c"])
    assert str(err.value) == (
        "trim: goes with editor='novelty-benefit' (the share of each activity it keeps);"
        " editor='renn' decides how many cases it keeps, got trim=0.5"
    )
    model = _model(trained)
    model["params"] = {**model["params"], "trim": 0.5, "editor": "cnn"}
    db = _copy(trained, tmp_path / "cb.sqlite")
    _set_model(db, model)
    store = open_store(db, create=False, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    assert (clf.trim, clf.editor) == (0.5, "cnn")


def test_an_editor_that_keeps_fewer_than_k_is_refused_naming_what_helps(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """CNN on the demo's squats, side lunges and shoulder abductions of s01 and s02 keeps
    3 cases, fewer than k = 5."""
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(tmp_path / "cb.sqlite"),
            "--subjects", "s01,s02", "--labels", SEEN, "--editor", "cnn"]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line == (
        "posecbr train: error: training set: trimming would leave 3 cases, fewer than the 5"
        " the case base votes with (k): nothing stored (another --editor than cnn, or give a"
        " smaller -k)"
    )


# The model document carries a format (MODEL_FORMAT) that nothing read: a model a later
# posecbr stores in a format whose meaning changed would have been read as this one's.


def test_a_model_of_a_later_format_is_refused_saying_so(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from cbr.stored import MODEL_FORMAT

    assert _model(trained)["format"] == MODEL_FORMAT == 1
    root = tmp_path / "db"
    root.mkdir()
    db = _copy(trained, root / "cb.sqlite")
    _set_model(db, {**_model(trained), "format": 2})
    clip = str(DEMO / "m01_s03_e01.npz")
    line = refused(["classify", clip, "--db", str(db)], root, capsys)
    assert line == (
        f"posecbr classify: error: {db}: case base 'default' was stored by a newer posecbr"
        " (model format 2); this one reads up to format 1: upgrade posecbr to read it"
    )
    # without a format (stored before it was written) or of this one: read
    for model in ({k: v for k, v in _model(trained).items() if k != "format"}, _model(trained)):
        _set_model(db, model)
        assert _judges(db) == _judges(trained)
