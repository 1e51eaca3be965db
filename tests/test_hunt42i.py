"""Hunt 42i: the Python API and case-base management as a developer building on posecbr
uses them."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.dad import detect
from features.errors import InputError
from features.fluents import evaluate, state_signals
from features.qmp import qmp_features
from features.repetitions import count_repetitions
from posecbr.cli import main
from tests.badinput import refused, small_case_base, standing_clip

# on one xdist worker: the module's case_base, demo_clips made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt42i")


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_casebase_export_never_replaces_a_pose_file(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase export --out poses/squat.npz`` replaced the recording by the cases'
    features (exit 0, the pose file gone), one of the case base's own training clips as
    readily as any other: a pose file is refused as the export file, named with or without
    its ``.npz``; an earlier export is still replaced, as before."""
    own = sorted((case_base.parent / "train").rglob("*.npz"))[0]  # a case's own recording
    clip = shutil.copy(own, tmp_path / "squat.npz")
    db = shutil.copy(case_base, tmp_path / "cb.sqlite")
    capsys.readouterr()
    export = ["casebase", "export", "--db", str(db), "--out"]
    for out in (clip, tmp_path / "squat"):
        refused([*export, str(out)], tmp_path, capsys,
                "squat.npz: is a pose file: the export would replace that recording")  # fmt: skip
    before = own.read_bytes()
    refused([*export, str(own)], tmp_path, capsys, "is a pose file")
    assert own.read_bytes() == before
    again = tmp_path / "cases.npz"
    for _ in range(2):  # an export over an export: written again
        assert main([*export, str(again)]) == 0
        with np.load(again) as saved:
            assert "problems" in saved.files and "positions" not in saved.files
    capsys.readouterr()


CLIP_READERS: list[tuple[str, Callable[[Any], Any]]] = [
    ("features.fluents.evaluate", evaluate),
    ("features.fluents.state_signals", state_signals),
    ("features.qmp.qmp_features", qmp_features),
    ("cbr.dad.detect", detect),
    ("features.repetitions.count_repetitions", count_repetitions),
]


@pytest.mark.parametrize(("name", "read"), CLIP_READERS, ids=[n for n, _ in CLIP_READERS])
def test_the_functions_reading_one_clip_refuse_an_array_naming_the_argument(
    name: str, read: Callable[[Any], Any]
) -> None:
    """Their docstrings read "``seq`` (positions ``(frames, joints, 3)``)", and an array of
    positions so given raised AttributeError ("'numpy.ndarray' object has no attribute
    'to_canonical'") from inside the computation (``count_repetitions`` alone said what it
    expected): each refuses it, and a list of clips, with the InputError (a ValueError)
    that names ``seq`` and says how to make one."""
    clip = standing_clip(30)
    for given, kind in ((clip.positions, "ndarray"), ([clip], "list")):
        with pytest.raises(InputError) as refusal:
            read(given)
        assert isinstance(refusal.value, ValueError)
        assert str(refusal.value) == (
            f"seq: a PoseSequence is expected, got {kind} (PoseSequence(xyz, names, fps) makes"
            " one of an array)"
        )


@pytest.fixture(scope="module")
def demo_clips() -> tuple[list[Any], list[str]]:
    """Two subjects' deep squats and sit-to-stands of the bundled demo (24 clips)."""
    from features.datasets import load_dataset

    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    clips = load_dataset(demo, subjects={"s01", "s02"}, labels={"deep_squat", "sit_to_stand"})
    return [c.seq for c in clips], [c.label for c in clips]


@pytest.mark.parametrize(
    "params",
    [
        {"length": 16},
        {"angles": False},
        {"velocity": True},
        {"features": "qmp"},
        {"similarity": "dtw"},
    ],  # fmt: skip
    ids=["length", "angles", "velocity", "qmp", "dtw"],
)
def test_fit_described_refuses_clips_described_for_another_estimator(
    demo_clips: tuple[list[Any], list[str]], params: dict[str, Any]
) -> None:
    """The README offers ``fit_described`` "on records made anywhere"; records described once
    with the default plan and fitted with other parameters (a search over them) were read as
    the columns of the other configuration. ``length=16``, ``qmp`` and ``dtw`` fitted
    silently (on 40 demo clips of s01 and s02, every third, ``length=16`` answered 10 of s03's 60
    clips otherwise than ``fit`` of the same clips, its cases of 1,183 columns where
    ``fit``'s have 676); ``angles=False`` and ``velocity=True`` raised ValueError and
    IndexError from inside. Each is refused naming the record and the call that describes it
    right."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import describe, fit_plan

    X, y = demo_clips
    described = [describe(s, fit_plan(CaseBaseClassifier())) for s in X]
    with pytest.raises(InputError, match=r"clips\[0\] was described over other feature columns"):
        CaseBaseClassifier(**params).fit_described(described, y)


def test_fit_described_refuses_clips_without_what_its_side_handling_needs(
    demo_clips: tuple[list[Any], list[str]],
) -> None:
    """Records described without mirror images (``mirror="off"``) given to an estimator that
    adds them as cases, and a clip given undescribed, are refused by name; records of the
    estimator's own plan fit the model ``fit`` fits."""
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import describe, fit_plan

    X, y = demo_clips
    plain = CaseBaseClassifier(mirror="off", feature_weights="none")
    described = [describe(s, fit_plan(plain)) for s in X]
    augment = CaseBaseClassifier(mirror="augment", feature_weights="none")
    with pytest.raises(InputError, match=r"clips\[0\] was described without its mirror image"):
        augment.fit_described(described, y)
    with pytest.raises(InputError, match=r"clips\[1\] is a PoseSequence, not a DescribedClip"):
        plain.fit_described([described[0], X[1]], y[:2])
    ours = plain.fit_described(described, y).case_base_.problems
    np.testing.assert_array_equal(ours, CaseBaseClassifier(**plain.get_params()).fit(X, y)
                                  .case_base_.problems)  # fmt: skip
