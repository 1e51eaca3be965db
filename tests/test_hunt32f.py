"""Case base store faults found by hunt 32 and fixed in hunt 32f: feedback that relabels an
activity's last case, matrices of two case bases whose names make the same file name, a NUL
in a clip's subject refused only after training."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from casebase_store import open_store
from posecbr.cli import main
from tests.badinput import small_case_base

#: the small case base's activities (three clips each: tests/badinput.small_case_base)
BOTH = "l'avant – both arms"
RIGHT = "右腕 raise"
LEFT = 'left arm "raise"'


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("small"))


def _labels(db: Path) -> dict[str, int]:
    with open_store(db, readonly=True) as store:
        return dict(store.get_case_base("default").label_counts)


def test_feedback_that_relabels_an_activitys_last_case_says_so(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: each of the three "both arms" clips lies on its own case (distance 0), so
    # feedback calling them "右腕 raise" relabelled the three cases one by one, and the case
    # base was left without "both arms" in silence (casebase trim keeps an activity's last
    # case); the correction stands (it is the user's data), but a note now names the activity
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    clips = [str(p) for p in sorted((small.parent / "train" / BOTH).glob("*.npz"))]
    assert len(clips) == 3
    capsys.readouterr()
    assert main(["classify", *clips, "--db", str(db), "--feedback", RIGHT, "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert [r["revision"]["action"] for r in doc["results"]] == ["relabelled"] * 3
    assert doc["left_without_cases"] == [BOTH]
    assert err.splitlines() == [
        f"note: case base 'default' no longer has any case of the activity \"{BOTH}\": the "
        "feedback relabelled its last case, so it is no longer predicted (to add it again: "
        "--feedback LABEL --new-label)"
    ]
    assert _labels(db) == {LEFT: 3, RIGHT: 6}  # the user's correction stands


def test_feedback_that_leaves_every_activity_a_case_has_no_note(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    clips = [str(p) for p in sorted((small.parent / "train" / BOTH).glob("*.npz"))][:2]
    capsys.readouterr()
    assert main(["classify", *clips, "--db", str(db), "--feedback", RIGHT, "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["left_without_cases"] == [] and err == ""
    assert _labels(db) == {BOTH: 1, LEFT: 3, RIGHT: 5}
    assert main(["classify", *clips, "--db", str(db), "--quiet"]) == 0  # without feedback
    out, err = capsys.readouterr()
    assert "left_without_cases" not in out and err == ""
