"""spread-margin is the default unknown judge (issue 14): ``segment``, ``watch`` and the Python
API use it when no judge is named, ``train`` calibrates it and stores it with the model, and a
model stored before (its judges without it) calibrates it when asked. Its thresholds for every
rate and prior at once (:func:`cbr.unknown.threshold_grid`) are
:func:`cbr.unknown.activity_thresholds`' numbers. The case base: ``train --split windows`` on
two subjects of the bundled UI-PRMD Kinect subset, three movements; the recording: the third
subject's real repetitions of two of them and of a movement the case base lacks, joined."""

from __future__ import annotations

import json
import math
import sqlite3
from pathlib import Path

import numpy as np
import pytest

import cbr.unknown
import cbr.unknown_judges
from casebase_store import open_store
from cbr.live import LiveSegmenter
from cbr.stored import load_classifier
from cbr.unknown import JUDGES, SpreadMargin, activity_thresholds, judge_of
from features.joining import join_repetitions
from features.poses import load_pose, save_pose
from posecbr.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def trained(seen_windows: Path) -> Path:
    """``train --split windows`` on s01 and s02's deep squat, standing shoulder abduction and
    side lunge (tests/conftest.py's seen_windows, made once in the session)."""
    return seen_windows


def _load(db: Path) -> object:
    store = open_store(db, create=False, readonly=True)
    try:
        return load_classifier(store, "default").classifier
    finally:
        store.close()


def test_spread_margin_is_the_default_judge_of_the_commands_and_the_api() -> None:
    assert JUDGES[0] == "spread-margin" and "activity-margin" in JUDGES
    parser = build_parser()
    for name in ("segment", "watch"):
        args = parser.parse_args([name, "x.npz", "--db", "cb.sqlite"])
        assert args.unknown == "spread-margin", name


def test_train_stores_spread_margin_and_an_older_model_calibrates_it_when_asked(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Stored at train (two subjects: held out by person, a spread per activity); a model
    stored before spread-margin was (its record removed from the stored judges, the others
    kept) calibrates the same judge at run time, and segment with no --unknown answers the
    same from either; with it stored, segment and the live segmenter scan no held-out case.
    The recording: subject s03's squat, side lunge and hurdle step (not in the case base)."""
    clf = _load(trained)
    stored = clf.judges_["spread-margin"]  # type: ignore[attr-defined]
    assert isinstance(stored, SpreadMargin) and stored.basis == "subject"
    assert len(stored.spreads) == 3 and stored.power in cbr.unknown.SPREAD_POWERS
    assert stored == SpreadMargin.of(clf.case_base_)  # type: ignore[attr-defined]

    older = tmp_path / "older.sqlite"
    older.write_bytes(trained.read_bytes())
    con = sqlite3.connect(older)
    con.execute(
        "UPDATE case_bases SET model = json_remove(model, '$.judges.calibrated.\"spread-margin\"')"
    )
    con.commit()
    con.close()
    old = _load(older)
    assert "spread-margin" not in old.judges_ and "activity-margin" in old.judges_  # type: ignore[attr-defined]
    assert judge_of(old, "spread-margin") == stored

    names = [f"m{m}_s03_e01.npz" for m in ("01", "04", "02")]
    joined = join_repetitions([load_pose(DEMO / n) for n in names]).seq
    rec = save_pose(joined, tmp_path / "s03.npz")

    def segmented(db: Path, *extra: str) -> object:
        capsys.readouterr()
        assert main(["segment", str(rec), "--db", str(db), "--json", *extra]) == 0
        return json.loads(capsys.readouterr().out)["segments"]

    calibrated_now = segmented(older)

    def no_scan(*args: object, **kwargs: object) -> None:
        raise AssertionError("calibrated at run time")

    monkeypatch.setattr(cbr.unknown_judges, "held_out_activities", no_scan)
    assert segmented(trained) == calibrated_now
    assert LiveSegmenter(clf, 30.0).judge == stored


def test_threshold_grid_by_hand_and_as_activity_thresholds() -> None:
    """Activity a's margins 0.1-0.4, b's 0.5 and 0.9, c none. At rate 0.25 the pooled
    threshold is the 5th of six sorted (ceil(6 * 0.75) = 5): 0.5; a's own the 3rd of four:
    0.3; b's own the 2nd of two: 0.9. Prior 2: a (4 * 0.3 + 2 * 0.5) / 6 = 11/30, b (2 * 0.9
    + 2 * 0.5) / 4 = 0.7, c the pooled; prior inf: the pooled for all. At rate 0 the pooled
    is the largest, 0.9 (b's own too), a's 0.4: (4 * 0.4 + 2 * 0.9) / 6 = 17/30."""
    from cbr.unknown import threshold_grid  # new with it

    margins = np.array([0.4, 0.9, 0.1, 0.3, 0.5, 0.2])
    codes = np.array([0, 1, 0, 0, 1, 0])
    weights = [(0.25, 0.0), (0.25, 2.0), (0.25, math.inf), (0.0, 2.0)]
    expected = [[0.3, 0.9, 0.5], [11 / 30, 0.7, 0.5], [0.5, 0.5, 0.5], [17 / 30, 0.9, 0.9]]
    np.testing.assert_allclose(threshold_grid(margins, codes, 3, weights), expected)
    # the same numbers as one (rate, prior) at a time, ties and inf scores included
    rng = np.random.default_rng(3)
    grid = [(0.05 * s, p) for s in (1.0, 0.6, 0.2) for p in (0.0, 5.0, 80.0, math.inf)]
    for _ in range(20):
        n = int(rng.integers(1, 40))
        values = rng.choice([0.0, 0.25, 0.5, 0.75, 1.0, 3.0, math.inf], n)
        acts = rng.integers(0, 4, n)
        got = threshold_grid(values, acts, 5, grid)
        for row, (rate, prior) in zip(got, grid, strict=True):
            with np.errstate(invalid="ignore"):
                want, _ = activity_thresholds(values, acts, 5, rate, prior)
            np.testing.assert_array_equal(row, want)
