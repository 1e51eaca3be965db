"""Hunt 51t: leftovers of session 51's hunts.

- Messages name the place in the file as the user's editor numbers it: an AMC file with a
  frame number missing said "bone 'root' is listed twice in frame 3" (the bones of the frame
  after it, its number lost, taken for frame 3's); a UI-PRMD file's number that is not finite
  said "contains non-finite numbers" with no line; a row of the wrong width or a word in a
  UI-PRMD file was numbered after blank lines were skipped.
- A label in other Unicode characters than the case base's or the data's ("Plié" typed, é one
  character, and "Plié" from a macOS file name, e and a combining accent) is that label
  everywhere (the rule of ``features.text.spelt_as``): ``train --append`` made it a second
  activity printed the same ("added as new: Plié"), and ``--labels`` typed so kept no clip
  and was refused naming labels that looked the same ("its labels are Plié").
- A recording joined from repetitions (``features.joining.join_repetitions``) is made from
  all of them: its source was the first repetition's file, so two recordings that begin
  with the same repetition were one recording to the case base's held-out checks.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from features.errors import DataError
from features.poses import PoseSequence
from tests.test_bad_input_datasets import ASF, ROW


def _amc_frame(number: int | None) -> str:
    bones = "root 0 0 0 0 0 0\nlfemur 0 0 0\n"
    return bones if number is None else f"{number}\n{bones}"


def _amc_refusal(folder: Path, frames: str) -> str:
    from features.readers.asfamc import read_amc, read_asf

    (folder / "skel.asf").write_text(ASF)
    (folder / "walk.amc").write_text(":FULLY-SPECIFIED\n:DEGREES\n" + frames)
    with pytest.raises(DataError) as err:
        read_amc(folder / "walk.amc", read_asf(folder / "skel.asf"))
    return str(err.value)


def test_an_amc_frame_without_its_number_is_said_to_lack_it(tmp_path: Path) -> None:
    # frames 1-3, then frame 4's bones with the line "4" lost, then frame 5: line 12 is the
    # root of the frame after frame 3 (2 header lines + 3 frames of 3 lines)
    lost = _amc_refusal(tmp_path, "".join(_amc_frame(n) for n in (1, 2, 3, None, 5)))
    assert lost.endswith(
        "walk.amc: line 12: bone 'root' again after every bone of frame 3: the frame number"
        " after frame 3 is missing"
    )
    # frame 2 lists root twice before its lfemur: no frame number can be lost there
    twice = _amc_refusal(tmp_path, _amc_frame(1) + "2\nroot 0 0 0 0 0 0\n" + _amc_frame(None))
    assert twice.endswith("walk.amc: line 8: bone 'root' is listed twice in frame 2")


def _uiprmd_kinect(folder: Path, positions: str, angles: str) -> Path:
    (folder / "m01_s01_e01_angles.txt").write_text(angles)
    path = folder / "m01_s01_e01_positions.txt"
    path.write_text(positions)
    return path


@pytest.mark.parametrize(
    ("positions", "said"),
    [
        # line 1 blank, line 2 a row, line 3 blank, line 4 a row whose 5th number is nan
        (
            "\n" + ROW + "\n" + ROW.replace("1.0", "nan", 5).replace("nan", "1.0", 4),
            "contains non-finite numbers: the first, 'nan', at line 4, column 5",
        ),
        # an inf with a space before it: the first number of line 3
        (
            ROW + ROW + ROW.replace("1.0", " inf", 1),
            "contains non-finite numbers: the first, 'inf', at line 3, column 1",
        ),
        # blank lines before the short row: the file's line 5, not the third row
        (ROW + "\n\n" + ROW + "1,2,3\n", "line 5: expected 66 comma-separated numbers, got 3"),
        (ROW + "\n" + ROW.replace("1.0", "x", 1), "line 3: not a number in 'x,1.0,"),
    ],
    ids=["nan", "inf", "short row", "word"],
)
def test_a_uiprmd_files_bad_number_is_named_by_the_files_own_line(
    tmp_path: Path, positions: str, said: str
) -> None:
    from features.readers.uiprmd import read_uiprmd_kinect_joints

    path = _uiprmd_kinect(tmp_path, positions, ROW * 2)
    with pytest.raises(DataError) as err:
        read_uiprmd_kinect_joints(path)
    assert f"m01_s01_e01_positions.txt: {said}" in str(err.value), str(err.value)


def test_recordings_joined_from_the_same_first_repetition_are_two_recordings() -> None:
    from cbr.estimator import CaseBaseClassifier
    from cbr.unknown import held_out_basis
    from features.joining import join_repetitions
    from tests.bodies import squat_clip

    def joined(*parts: tuple[float, str]) -> PoseSequence:
        return join_repetitions([squat_clip(d, 30, source=name) for d, name in parts]).seq

    deep = [joined((0.95, "a.npz"), (0.9, "b.npz")), joined((0.95, "a.npz"), (0.92, "c.npz"))]
    shallow = [joined((0.4, "d.npz"), (0.45, "e.npz"))]
    assert [s.source for s in deep] == ["a.npz + b.npz", "a.npz + c.npz"]
    clf = CaseBaseClassifier(k=1).fit([*deep, *shallow], ["deep", "deep", "shallow"])
    # deep squats from two recordings: each held out from the other's cases, not by time
    # within one recording named a.npz (which both were)
    basis, groups = held_out_basis(clf.case_base_)
    assert basis == "recording"
    assert len(set(groups.tolist())) == 3


PLIE_TYPED = "Pli\u00e9"  # é one character (NFC), as typed
PLIE_FILE_NAME = "Plie\u0301"  # e and a combining acute accent (NFD), as macOS names files


@pytest.fixture
def plie_clips(tmp_path: Path) -> tuple[Path, dict[str, Path]]:
    """Squats as pose files: deep ones are the activity Plié, spelt as a macOS file name
    gives it, shallow ones squat; and a labels CSV of them."""
    from features.poses import save_pose
    from tests.bodies import squat_clip

    files = {}
    for name, depth in (("a", 0.9), ("b", 0.4), ("c", 0.85), ("d", 0.45)):
        files[name] = tmp_path / f"{name}.npz"
        save_pose(squat_clip(depth, 30, source=name), files[name])
    csv = tmp_path / "labels.csv"
    rows = (("a", PLIE_FILE_NAME), ("b", "squat"), ("c", PLIE_FILE_NAME), ("d", "squat"))
    csv.write_text("path,label\n" + "".join(f"{n}.npz,{lab}\n" for n, lab in rows), "utf-8")
    return csv, files


def test_append_in_other_unicode_characters_adds_to_the_stored_activity(
    tmp_path: Path, plie_clips: tuple[Path, dict[str, Path]]
) -> None:
    from casebase_store import open_store
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import append, train
    from features.poses import load_pose

    _, files = plie_clips
    db = tmp_path / "cb.sqlite"
    seqs = {n: load_pose(f) for n, f in files.items()}
    labels = [PLIE_FILE_NAME, "squat", "squat"]
    train(db, "default", [seqs["a"], seqs["b"], seqs["d"]], labels, CaseBaseClassifier(k=1))
    result = append(db, "default", [seqs["c"]], [PLIE_TYPED])
    assert result.new_labels == []  # was ["Plié"]: a second activity
    store = open_store(db, create=False)
    try:
        counts = store.get_case_base("default").label_counts
    finally:
        store.close()
    assert counts == {PLIE_FILE_NAME: 2, "squat": 2}


def test_labels_typed_in_other_unicode_characters_keep_the_datas_clips(
    plie_clips: tuple[Path, dict[str, Path]],
) -> None:
    from features.datasets import load_dataset
    from posecbr.arguments import check_found

    csv, files = plie_clips
    clips = load_dataset(csv, labels=[PLIE_TYPED])
    assert sorted(c.seq.source for c in clips) == [str(files["a"]), str(files["c"])]
    assert {c.label for c in clips} == {PLIE_FILE_NAME}  # the data's own spelling kept
    # found: not refused as "no clip labelled 'Plié' ...: its labels are Plié and squat"
    check_found([c.label for c in clips], [PLIE_TYPED], "--labels", "labelled", csv)
