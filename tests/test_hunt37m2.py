"""Hunt 37m2: a judge made for another classifier of the same number of activities, a
non-bool ``absent`` pushed to the live segmenter, and ``--subjects`` no clip has."""

from __future__ import annotations

import csv
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from cbr.segmentation import segment
from cbr.unknown import judge_of
from features.errors import InputError
from features.poses import PoseSequence, load_pose
from features.skeleton import BLAZEPOSE_33
from tests.badinput import good_pose_file, refused


class _Scripted(LiveSegmenter):
    """The live segmenter voting "a" for every window (no classifier behind it)."""

    def _vote(self, n: int) -> tuple[np.ndarray, float]:
        return np.eye(2)[0], 0.0

    def _repetition_windows(self, n: int) -> None:
        """The fixed windows only."""


def _scripted() -> _Scripted:
    labels = np.array(["a", "b"])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    return _Scripted(clf, 30.0, judge=SimpleNamespace(), source="robot")


@pytest.mark.parametrize("absent", ["no", "False", 0, 1, None, [False]])
def test_an_absent_that_is_not_true_or_false_is_refused_naming_it(absent: Any) -> None:
    """``push(frame, absent="no")`` was taken as True (the frame counted as no frame in the
    video, "no frames in the video" said of a stretch of it); now InputError naming
    ``absent``, nothing kept; True, False and numpy's bools are taken."""
    live = _scripted()
    with pytest.raises(InputError, match=r"^robot: frame 0: absent must be True or False, got"):
        live.push(np.zeros((33, 3)), absent=absent)
    assert live.n == 0 and live.absent == []
    for ok in (False, True, np.bool_(True), np.bool_(False)):
        live.push(np.zeros((33, 3)), absent=ok)  # type: ignore[arg-type]
    assert live.n == 4 and live.absent == [[1, 3]]


DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
MINE = ("deep_squat", "hurdle_step", "standing_shoulder_abduction")
THEIRS = ("deep_squat", "inline_lunge", "side_lunge")


def _fitted(activities: tuple[str, ...]) -> CaseBaseClassifier:
    """A classifier of three demo activities, every third clip, as a tracker's arrays."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] in activities][::3]
    X = [PoseSequence(load_pose(DEMO / r["path"]).to_canonical().positions, BLAZEPOSE_33, 30.0)
         for r in rows]  # fmt: skip
    return CaseBaseClassifier(k=3, mirror=False).fit(X, [r["label"] for r in rows])


# on one xdist worker: the module's two made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt37m2")


@pytest.fixture(scope="module")
def two() -> tuple[CaseBaseClassifier, CaseBaseClassifier, PoseSequence]:
    """Two classifiers of three activities each, not the same ones, and 3 s of a squat."""
    squat = load_pose(DEMO / "m01_s01_e01.npz").to_canonical().positions[:90]
    return _fitted(MINE), _fitted(THEIRS), PoseSequence(squat, BLAZEPOSE_33, 30.0)


@pytest.mark.parametrize("name", ["spread-margin", "activity-margin", "spread-far"])
def test_another_classifiers_judge_of_as_many_activities_is_refused_naming_both(
    two: tuple[CaseBaseClassifier, CaseBaseClassifier, PoseSequence], name: str
) -> None:
    """The judge of a classifier of deep_squat, hurdle_step and standing_shoulder_abduction
    given to one of deep_squat, inline_lunge and side_lunge: as many activities, so it was
    taken, hurdle_step's threshold read for inline_lunge's windows; now segment and
    LiveSegmenter refuse it naming both lists, and take the classifier's own judge."""
    mine, theirs, squat = two
    judge = judge_of(mine, name)
    words = (
        r"^judge: the judge was calibrated on the activities deep_squat, hurdle_step,"
        r" standing_shoulder_abduction, the classifier's are deep_squat, inline_lunge,"
        r" side_lunge: another classifier's judge \(judge_of\(clf, name\) makes"
    )
    with pytest.raises(InputError, match=words):
        segment(theirs, squat, judge)
    with pytest.raises(InputError, match=words):
        LiveSegmenter(theirs, 30.0, judge)
    assert judge.activities == MINE  # type: ignore[attr-defined]
    own = judge_of(theirs, name)
    assert own.activities == THEIRS  # type: ignore[attr-defined]
    assert segment(theirs, squat, own).segments
    LiveSegmenter(theirs, 30.0, own)


def test_a_judge_of_the_same_activities_in_another_order_is_refused() -> None:
    """A judge whose thresholds are of "10" then "2" (text labels) given to a classifier of
    labels fitted as numbers, 2 then 10: the same count, each window nearest 2 was judged
    against 10's threshold; now refused naming both orders."""
    from cbr.unknown import ActivityMargin

    labels = np.array([2, 10])
    clf = SimpleNamespace(classes_=labels, case_base_=SimpleNamespace(labels=labels))
    judge = ActivityMargin((0.5, 0.9), 0.7, "subject", 10, activities=("10", "2"))
    with pytest.raises(InputError, match=r"activities 10, 2, the classifier's are 2, 10: "):
        _Scripted(clf, 30.0, judge=judge)
    _Scripted(clf, 30.0, judge=ActivityMargin((0.9, 0.5), 0.7, "subject", 10,
                                              activities=("2", "10")))  # fmt: skip


def test_a_long_activity_list_is_shortened() -> None:
    """Eight activities each side: six named, then "and 2 more"."""
    from cbr.segmentation import check_judge
    from cbr.unknown import ActivityMargin

    names = tuple(f"a{i}" for i in range(8))
    judge = ActivityMargin((0.5,) * 8, 0.7, "subject", 10, activities=names)
    with pytest.raises(InputError) as err:
        check_judge(judge, [f"b{i}" for i in range(8)])
    assert str(err.value.message) == (
        "the judge was calibrated on the activities a0, a1, a2, a3, a4, a5 and 2 more, the"
        " classifier's are b0, b1, b2, b3, b4, b5 and 2 more: another classifier's judge"
        " (judge_of(clf, name) makes this classifier's)"
    )


def test_a_model_stored_with_named_judges_reads_them_back(tmp_path: Path) -> None:
    """A stored model's judges keep their activities' names; a record stored before them
    (no "activities") still loads, is named from the model's own case base by judge_of
    (it was calibrated on it), and segments as the named one does."""
    from cbr.unknown import SpreadMargin, judges_from_dict, judges_to_dict

    clf = _fitted(MINE)
    named = judge_of(clf, "spread-margin")
    record = judges_to_dict({"spread-margin": named})  # type: ignore[dict-item]
    assert record["spread-margin"]["activities"] == list(MINE)
    assert judges_from_dict(record)["spread-margin"] == named
    del record["spread-margin"]["activities"]  # as stored before the names were
    old = judges_from_dict(record)["spread-margin"]
    assert isinstance(old, SpreadMargin) and old.activities == ()
    clf.judges_ = {"spread-margin": old}
    again = judge_of(clf, "spread-margin")
    assert again == named
    squat = load_pose(DEMO / "m01_s01_e01.npz").to_canonical()
    assert segment(clf, squat, old).segments == segment(clf, squat, again).segments


# ``train``/``compare --subjects X`` where no clip is of subject X said "no clip of subject
# 'X' in the data" and no more; now, as for --labels (hunt 37j), the refusal names the data
# and the subjects its clips have, or says the other filters leave that subject out.


def _csv(folder: Path, clips: list[tuple[str, str]]) -> Path:
    rows = ["path,label,subject"]
    for k, (label, subject) in enumerate(clips):
        good_pose_file(folder / f"c{k}.npz", frames=30)
        rows.append(f"c{k}.npz,{label},{subject}")
    csv_path = folder / "labels.csv"
    csv_path.write_text("\n".join(rows) + "\n")
    return csv_path


def test_train_of_a_subject_no_clip_has_names_the_subjects_of_the_data(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo's clips are of s01, s02 and s03; --subjects s09 (none read: refused before
    any clip is described)."""
    argv = ["train", str(DEMO), "--subjects", "s09", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr train: error: --subjects: no clip of subject 's09' in {DEMO}: its subjects"
        " are s01, s02 and s03"
    )


def test_train_of_a_mistyped_subject_beside_a_right_one_names_the_subjects(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """s01 has clips, "s1" none: refused after the clips are read, naming s01 and s02."""
    data = _csv(tmp_path, [("run", "s01"), ("walk", "s01"), ("run", "s02"), ("walk", "s02")])
    argv = ["train", str(data), "--subjects", "s01,s1", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"--subjects: no clip of subject 's1' in {data}: its subjects are s01"
                         " and s02")  # fmt: skip


def test_a_subject_the_labels_leave_out_is_said_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """s02 is a subject of the CSV's clips, but not of a run clip: said as left out by the
    other filters, not as missing from the data."""
    data = _csv(tmp_path, [("run", "s01"), ("run", "s01"), ("walk", "s02"), ("walk", "s02")])
    argv = ["train", str(data), "--labels", "run", "--subjects", "s01,s02", "--db",
            str(tmp_path / "cb.sqlite")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"--subjects: no clip of subject 's02' in {data} passes the other"
                         " filters")  # fmt: skip


def test_a_pose_folder_names_the_subjects_of_its_files_metadata(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Pose files whose metadata holds their subjects (ann, cy), read without decoding."""
    data = tmp_path / "poses"
    for k, subject in enumerate(["cy", "ann", "cy"]):
        good_pose_file(data / f"c{k}.npz", frames=30, label="walk", subject=subject)
    argv = ["train", str(data), "--subjects", "bob", "--db", str(tmp_path / "cb.sqlite")]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"no clip of subject 'bob' in {data}: its subjects are ann and cy")


def test_compare_names_the_subjects_the_data_have(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """compare of the demo's squats, s01 and a mistyped "s9"."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat", "--subjects", "s01,s9", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr compare: error: --subjects: no clip of subject 's9' in {DEMO}: its subjects"
        " are s01, s02 and s03"
    )
