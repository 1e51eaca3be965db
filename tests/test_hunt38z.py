"""Hunt 38z: three consistency defects left by this session's hunts.

``classify DATA --subjects s99`` (a subject no clip has) was refused without the subjects
the data have ("no clip of subject 's99' in the clips given"), where ``train`` and
``compare`` name them ("in DATA: its subjects are s01, s02 and s03"). It now says what they
say, from the one check they share (posecbr.arguments.check_each_found).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused, small_case_base

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
#: the demo's labels.csv, by hand: 10 activities, each of s01, s02 and s03
DEMO_LABELS = (
    "deep_squat, hurdle_step, inline_lunge, side_lunge, sit_to_stand, "
    "standing_active_straight_leg_raise, standing_shoulder_abduction, "
    "standing_shoulder_extension, standing_shoulder_internal_external_rotation and "
    "standing_shoulder_scaption"
)


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


@pytest.mark.parametrize("command", ["classify", "train", "compare"])
def test_a_subject_the_data_lack_is_refused_naming_those_they_have(
    command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same line from the three commands that take ``--subjects`` of a dataset."""
    out = {
        "classify": ["--db", str(case_base)],
        "train": ["--db", str(tmp_path / "new.sqlite")],
        "compare": ["--json", str(tmp_path / "r.json")],
    }[command]
    capsys.readouterr()
    line = refused([command, str(DEMO), *out, "--subjects", "s99"], tmp_path, capsys)
    assert line.endswith(
        f"--subjects: no clip of subject 's99' in {DEMO}: its subjects are s01, s02 and s03"
    )


def test_classify_names_the_labels_the_data_have(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    argv = ["classify", str(DEMO), "--db", str(case_base), "--labels", "deep_squt"]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(f"--labels: no clip labelled 'deep_squt' in {DEMO}: its labels are "
                         + DEMO_LABELS)  # fmt: skip


def test_classify_names_a_subject_the_data_lack_not_the_label_as_compare_does(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """s99 left no clip of deep_squat: the subject is named, with the data's subjects."""
    capsys.readouterr()
    argv = ["classify", str(DEMO), "--db", str(case_base), "--labels", "deep_squat",
            "--subjects", "s99"]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"--subjects: no clip of subject 's99' in {DEMO}: its subjects are s01, s02 and s03"
    )


def test_classify_of_two_datasets_names_the_subjects_of_both(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV of s01's and s04's clips beside one of s03's: the subjects of both."""
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    clip = DEMO / "m01_s01_e01.npz"
    first.write_text(
        f"path,label,subject\n{clip},deep_squat,s01\n{DEMO / 'm01_s01_e02.npz'},side_lunge,s04\n"
    )
    second.write_text(f"path,label,subject\n{clip},deep_squat,s03\n")
    capsys.readouterr()
    argv = ["classify", str(first), str(second), "--db", str(case_base), "--subjects", "s1"]
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        "--subjects: no clip of subject 's1' in the clips given: its subjects are s01, s03 and s04"
    )
    # there, but --labels leaves it out: said so, as train and compare say it
    argv = ["classify", str(first), "--db", str(case_base), "--subjects", "s04",
            "--labels", "deep_squat"]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"--subjects: no clip of subject 's04' in {first} passes the other filters"
    )


# `posecbr train RECORDING --frame-labels FILE` stored every stretch with no subject, though
# the pose file named its person (metadata subject), where `cbr.training.cut_recording` and
# a labels CSV's label_file row keep it: the command called recording_clips without one (an
# omission of 84ea090, which refuses --subjects because the stretches are "one person's").
# Both paths now store the recording's subject.


def test_train_frame_labels_keeps_the_subject_the_pose_file_names(tmp_path: Path) -> None:
    """Four arm raises at 30 fps (0.6 s rest, then 1.2 s up and down and 0.6 s rest each: 234
    frames), the first 120 frames "raise_a", the other 114 "raise_b", in a pose file of
    subject p07: both paths store the 2-s windows (60 frames) every 0.5 s (15) that fit in
    each stretch, 5 and 4, and each of p07."""
    from casebase_store import open_store
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import cut_recording, train
    from features.datasets import load_clip
    from features.poses import save_pose
    from posecbr.cli import main
    from tests.test_repetitions import _movement

    seq = _movement(["both"] * 4)
    assert seq.n_frames == 234
    rec = save_pose(seq.with_metadata(subject="p07"), tmp_path / "rec.npz")
    labels = tmp_path / "labels.txt"
    labels.write_text("\n".join(["raise_a"] * 120 + ["raise_b"] * 114) + "\n")
    by_command, by_python = tmp_path / "command.sqlite", tmp_path / "python.sqlite"
    assert main(["train", str(rec), "--frame-labels", str(labels), "--db", str(by_command)]) == 0
    pieces, solutions = cut_recording(load_clip(rec), labels)
    train(by_python, "default", pieces, solutions, CaseBaseClassifier(feature_weights="none"),
          cases="windows")  # fmt: skip
    stored, problems = [], []
    for db in (by_command, by_python):
        with open_store(db, readonly=True) as store:
            cases = store.load_cases("default")
        stored.append((list(cases.labels), list(cases.frame_ranges), list(cases.subjects)))
        problems.append(cases.features.tobytes())
    assert stored[0] == stored[1] and problems[0] == problems[1]
    windows = [(a, a + 60) for a in range(0, 61, 15)] + [(a, a + 60) for a in range(120, 175, 15)]
    assert stored[0] == (["raise_a"] * 5 + ["raise_b"] * 4, windows, ["p07"] * 9)
