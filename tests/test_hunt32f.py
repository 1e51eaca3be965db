"""Case base store faults found by hunt 32 and fixed in hunt 32f: feedback that relabels an
activity's last case, matrices of two case bases whose names make the same file name, a NUL
in a clip's subject refused only after training."""

from __future__ import annotations

import csv
import hashlib
import json
import shutil
from pathlib import Path

import pytest

import cbr.stored as stored_module
from casebase_store import open_store
from cbr.stored import load_classifier, write_matrices
from posecbr.cli import main
from tests.badinput import refused, small_case_base
from tests.test_mapped_case_base import _is_mapped, _matrices

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


def _hash(name: str) -> str:
    return hashlib.sha256(name.encode("utf-8")).hexdigest()[:12]


def test_two_case_base_names_of_one_file_name_keep_their_own_matrices(
    small: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "a b" and "a_b" both wrote "a_b.problems.<uid>-<version>.npy" and the like, and
    # each write removed the other's files as its own older versions: the first case base was
    # read from SQL again (only slower)
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 5)  # "large": the 9 cases
    db = tmp_path / "cb.sqlite"
    data = small.parent / "train"
    for name in ("a b", "a_b"):
        argv = ["train", str(data), "--db", str(db), "--name", name, "--mirror", "off",
                "--feature-weights", "none", "--phases", "0"]  # fmt: skip
        assert main(argv) == 0
    capsys.readouterr()
    with open_store(db, readonly=True) as store:
        keys = {n: f"{store.get_case_base(n).uid}-1" for n in ("a b", "a_b")}
        assert _matrices(db) == sorted(
            f"a_b~{_hash(n)}.{kind}.{keys[n]}.npy"
            for n in ("a b", "a_b")
            for kind in ("problems", "representations")
        )
        for n in ("a b", "a_b"):
            cb = load_classifier(store, n).classifier.case_base_
            assert _is_mapped(cb.problems) and _is_mapped(cb.reps)


def test_matrices_an_older_posecbr_named_are_read_then_replaced(
    small: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # files named without the hash ("a_b.problems.<uid>-<version>.npy", posecbr 0.2) are still
    # mapped when of this very case base and version; the next change writes the new names and
    # removes its old ones, but not an old file of another case base with the same slug
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 5)
    db = tmp_path / "cb.sqlite"
    shutil.copy(small, db)
    name = "default"
    with open_store(db) as store:
        assert write_matrices(store, name)
    folder = db.with_name(db.name + ".matrices")
    for p in folder.iterdir():  # as posecbr 0.2 named them
        p.rename(folder / p.name.replace(f"~{_hash(name)}.", "."))
    # another case base whose name makes the same file name, "default." (small: not mapped),
    # given a file as 0.2 named them (a file of an identity no case base has is stale: removed)
    argv = ["train", str(small.parent / "train"), "--db", str(db), "--name", "default.",
            "--mirror", "off", "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 10**9)
    assert main(argv) == 0
    monkeypatch.setattr(stored_module, "MAPPED_MIN_CASES", 5)
    with open_store(db, readonly=True) as store:
        uid = store.get_case_base(name).uid
        other_uid = store.get_case_base("default.").uid
    other = folder / f"default.problems.{other_uid}-1.npy"
    shutil.copy(folder / f"default.problems.{uid}-1.npy", other)  # another 'default' case base's
    assert _matrices(db) == sorted(
        [other.name, f"default.problems.{uid}-1.npy", f"default.representations.{uid}-1.npy"]
    )
    with open_store(db, readonly=True) as store:
        cb = load_classifier(store, name).classifier.case_base_
        assert _is_mapped(cb.problems) and _is_mapped(cb.reps)
    clip = str(sorted((small.parent / "train" / BOTH).glob("*.npz"))[0])
    argv = ["classify", clip, "--db", str(db), "--name", name, "--feedback", BOTH, "--quiet"]
    assert main(argv) == 0
    assert _matrices(db) == sorted(
        [other.name]
        + [f"default~{_hash(name)}.{kind}.{uid}-2.npy" for kind in ("problems", "representations")]
    )


@pytest.mark.parametrize(
    ("column", "line"), [("subject", 3), ("label", 4)], ids=["subject", "label"]
)
def test_a_nul_in_a_labels_csv_subject_or_label_is_refused_as_the_labels_are_read(
    small: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    column: str,
    line: int,
) -> None:
    # before: the whole training ran (every clip's features, the fit), then the case base
    # refused it: "posecbr train: error: cb.sqlite: subject 's\x001' contains a NUL
    # character", the labels CSV, its row and column not named
    import cbr.training

    def no_features(*args: object, **kwargs: object) -> object:
        raise AssertionError("a clip was read before the labels were checked")

    monkeypatch.setattr(cbr.training, "describe_entry", no_features)
    csv_file = tmp_path / "labels.csv"
    with csv_file.open("w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow(["path", "label", "subject"])
        for i, clip in enumerate(sorted((small.parent / "train").rglob("*.npz"))):
            label, subject = clip.parent.name, f"s{i % 2}"
            if i + 2 == line:  # the CSV's line of this row (the header is line 1)
                label, subject = ("sq\x00uat", subject) if column == "label" else (label, "s\x001")
            out.writerow([str(clip), label, subject])
    value = "'sq\\x00uat'" if column == "label" else "'s\\x001'"
    refused(
        ["train", str(csv_file), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
        f"posecbr train: error: {csv_file}: line {line}: column {column}: {value} contains a "
        "NUL character (a case base cannot store it)",
    )  # fmt: skip


def test_a_nul_in_a_pose_files_subject_is_refused_as_the_clip_is_read(
    small: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "posecbr train: error: cb.sqlite: subject 's\x001' contains a NUL character"
    # after every clip's features and the fit, the pose file not named
    from features.poses import load_pose, save_pose

    data = tmp_path / "data"
    shutil.copytree(small.parent / "train", data)
    bad = sorted(data.rglob("*.npz"))[0]
    save_pose(load_pose(bad).with_metadata(subject="s\x001"), bad)
    refused(
        ["train", str(data), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys,
        f"posecbr train: error: {bad}: subject 's\\x001' contains a NUL character (a case base "
        "cannot store it)",
    )  # fmt: skip
