"""DAD matches a dataset's class names to the ADD's labels as a user reads them: case, spaces,
underscores and hyphens ignored (CMU's "Squat" is the ADD's "squat"), two classes it cannot
tell apart refused. Before, the names were compared exactly: on CMU subject 13 no class was
the ADD's, ``compare`` skipped DAD ("the ADD describes none of this dataset's activities") and
``DADClassifier`` scored every class -1, answering its first class for every clip."""

from __future__ import annotations

from pathlib import Path

import pytest

from cbr.dad import DADClassifier, class_of_activity, detect, label_key
from features.datasets import Clip
from features.errors import InputError
from features.poses import PoseSequence
from features.qmp.add import load_add
from features.readers.asfamc import read_asf_amc
from tests.once import made_once

# cmu-mocap6/README.md: the codes 1-12 of truelabels, in order
CMU_NAMES = ("JumpJack Jog Squat KneeRaise ArmCircle Twist SideReach Box UpDown ToeTouchOneHand "
             "SideBend ToeTouchTwoHands").split()  # fmt: skip
BLOCK_FRAMES = 12  # 0.1-s label blocks at 120 fps


def _stretches(rec: PoseSequence, codes: list[int]) -> list[tuple[PoseSequence, str]]:
    """The labelled stretches of ``rec``: runs of one code in its 0.1-s label blocks."""
    out, start = [], 0
    for i in range(1, len(codes) + 1):
        if i == len(codes) or codes[i] != codes[start]:
            seq = rec.slice_frames(start * BLOCK_FRAMES, min(rec.n_frames, i * BLOCK_FRAMES))
            out.append((seq, CMU_NAMES[codes[start] - 1]))
            start = i
    return out


@pytest.fixture(scope="module")
def cmu_squats_and_jacks(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> list[Clip]:
    """CMU 13_29's and 13_30's squat and jumping-jack stretches (two of each), labelled with
    CMU's own names: read once in the run (the tests only read them)."""
    return made_once(tmp_path_factory, "dad-names-cmu", lambda _: _squats_and_jacks(shared_data))


def _squats_and_jacks(shared_data: Path) -> list[Clip]:
    asf = shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"
    clips = []
    for take in ("13_29", "13_30"):
        rec = read_asf_amc(asf, shared_data / "cmu-mocap6" / "amc" / f"{take}.amc")
        text = (shared_data / "cmu-mocap6" / "truelabels" / f"{take}.txt").read_text()
        for seq, label in _stretches(rec, [int(v) for v in text.split()]):
            if label in ("Squat", "JumpJack"):
                clips.append(Clip(seq, label, None))
    assert sorted(c.label for c in clips) == ["JumpJack", "JumpJack", "Squat", "Squat"]
    return clips


def test_names_are_matched_ignoring_case_spaces_underscores_and_hyphens() -> None:
    keys = {label_key(n) for n in ("Jumping Jack", "jumping_jack", "JUMPING-JACK", "jumpingjack")}
    assert keys == {"jumpingjack"}
    assert label_key("Squat") == label_key("squat") != label_key("deep_squat")
    add = load_add()
    assert class_of_activity(add, ["Jumping Jack", "Squat", "Twist"]) == {
        "jumping_jack": 0,
        "squat": 1,
    }
    assert class_of_activity(add, ["JumpJack"]) == {"jumping_jack": 0}  # CMU's own name
    assert class_of_activity(add, ["Twist", "Box"]) == {}


@pytest.mark.parametrize(
    ("classes", "named"),
    [
        (["Squat", "squat"], "'Squat' and 'squat'"),
        (["Jumping Jack", "jumping_jack", "Jog"], "'Jumping Jack' and 'jumping_jack'"),
    ],
)
def test_two_classes_dad_cannot_tell_apart_are_refused(
    classes: list[str], named: str, cmu_squats_and_jacks: list[Clip]
) -> None:
    with pytest.raises(InputError) as err:
        class_of_activity(load_add(), classes)
    assert named in err.value.message and "cannot tell them apart" in err.value.message
    X = [c.seq for c in cmu_squats_and_jacks[: len(classes)]]
    with pytest.raises(InputError, match="cannot tell them apart"):
        DADClassifier().fit(X, classes)
    # compare leaves DAD out with that reason rather than failing in every fold
    from cbr.evaluation.methods import Method, why_unavailable

    why = why_unavailable(Method("dad", "dad", True), classes, "label")
    assert why is not None and named in why


def test_dad_recognises_cmu_squats_and_jumping_jacks_by_cmu_names(
    cmu_squats_and_jacks: list[Clip],
) -> None:
    X = [c.seq for c in cmu_squats_and_jacks]
    y = [c.label for c in cmu_squats_and_jacks]
    clf = DADClassifier().fit(X, y)
    # before: neither class was the ADD's, every score -1 and every answer "JumpJack"
    scores = clf.decision_function(X)
    assert (scores > -1).all()
    assert clf.predict(X).tolist() == y
    squat = detect(cmu_squats_and_jacks[y.index("Squat")].seq)
    found = squat.activity_for("Squat")  # the ADD's "squat"
    assert found is not None and found.activity == "squat"


def test_compare_runs_dad_on_cmu_names(cmu_squats_and_jacks: list[Clip]) -> None:
    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.settings import CompareSettings

    settings = CompareSettings(
        similarities=("euclidean",), features=("fluents",), peers=(), explain=0, k=1
    )
    results = run_compare(cmu_squats_and_jacks, settings, source="cmu").results.to_dict()
    dad = next(m for m in results["methods"] if m["name"] == "dad")
    assert dad["status"] == "ok", dad  # before: skipped, "the ADD describes none ..."
    assert dad["accuracy"] == pytest.approx(1.0)  # 4 of 4 stretches
    assert not any("ADD has no activity" in n for n in results["notes"])
