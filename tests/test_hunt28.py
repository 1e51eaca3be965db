"""Left by hunt 28b and fixed in session 28. Each test says what happened before its fix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cbr.similarity import get_measure
from features.errors import ConfigError, InputError
from tests.badinput import refused


@pytest.mark.parametrize(
    ("measure", "param", "value"),
    [
        ("dtw", "radius", 2.5),
        ("dtw", "segment", 1.5),
        ("dtw", "radius", True),
        ("signature", "depth", 2.7),
        ("euclidean", "prune_dims", 8.5),
    ],
)
def test_a_count_parameter_that_is_not_whole_is_refused(
    measure: str, param: str, value: object
) -> None:
    """A band radius of 2.5 frames was used as 2, a signature depth of 2.7 as 2, without a
    word."""
    with pytest.raises(ConfigError, match=f"{param} must be a whole number"):
        get_measure(measure, **{param: value})


def test_whole_valued_parameters_are_taken_as_their_number() -> None:
    # 3.0 (a number a JSON file or a --param may carry) is three frames; None is the default
    assert get_measure("dtw", radius=3.0).radius_for(32) == 3
    assert get_measure("dtw", radius=None, band=0.25).radius_for(32) == 8  # round(0.25 x 32)


def test_train_refuses_a_band_radius_that_is_not_whole(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.test_cbr_cli import _write_classes

    data = _write_classes(tmp_path / "train", 3, 5)
    argv = ["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--similarity", "dtw",
            "--param", "radius=2.5"]  # fmt: skip
    refused(argv, tmp_path, capsys, "radius must be a whole number, got 2.5")


def test_a_signature_of_missing_values_is_refused_by_its_own_name() -> None:
    """A problem holding NaN was refused by the Euclidean search of the signatures, so the
    message named "euclidean" for a case base whose similarity is "signature"."""
    problems = np.zeros((2, 5, 2))
    problems[1, 3, 0] = np.nan
    with pytest.raises(InputError, match="^signature: the problems hold NaN or inf"):
        get_measure("signature").represent(problems)


def test_a_picture_inside_a_file_says_the_file_is_no_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--plot notes.txt/t.png`` said "the folder of the picture does not exist" of a file
    that exists."""
    from tests.badinput import good_pose_file

    clip = good_pose_file(tmp_path / "clip.npz")
    notes = tmp_path / "notes.txt"
    notes.write_text("mine\n")
    line = refused(["describe", str(clip), "--plot", str(notes / "t.png")], tmp_path, capsys,
                   "it is a file, not a folder")  # fmt: skip
    assert str(notes) in line and "does not exist" not in line
