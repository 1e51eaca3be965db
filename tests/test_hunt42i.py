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
