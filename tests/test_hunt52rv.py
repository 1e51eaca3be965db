"""compare's refusals from the listing (hunt 52x) refuse only what the clips read are refused:
a ``-k`` the listing's folds cannot take but the read's can (a class of two, one of them left
out by the read, caps the listing's folds at two), and a ``--target`` naming the label in
another case (a read clip's metadata holds its label under any case)."""

from __future__ import annotations

import pytest

from cbr.evaluation.folds import check_listed
from cbr.evaluation.settings import CompareSettings
from features.clips import ListedClip
from features.errors import ConfigError
from features.targets import clip_target_of


def _listed(counts: dict[str, int]) -> list[ListedClip]:
    """Pose files of no subject, ``counts[label]`` of each label, as the listing tells them."""
    return [
        ListedClip(f"{label}{i}.npz", label, None, {}, adds=frozenset())
        for label, n in counts.items()
        for i in range(n)
    ]


def test_k_the_clips_read_can_take_is_left_to_them() -> None:
    # a: 2 clips, b and c 6 each. Listed, the class of two caps k-fold at 2 folds of 7 clips:
    # each trains on 7. Read with one of a's left out (too short, no person), a is a single
    # clip and goes: 12 clips in 5 folds of at most 3, each training on at least 9.
    listed = _listed({"a": 2, "b": 6, "c": 6})
    assert check_listed(listed, CompareSettings(cv="kfold", k=9), "data") is True
    # above what any read could train on (14 clips in 5 folds: at most 14 - 3 = 11), the
    # listing's own figure is said, as before
    with pytest.raises(ConfigError, match=r"must be at most 7, the training clips"):
        check_listed(listed, CompareSettings(cv="kfold", k=12), "data")


def test_target_naming_the_label_in_another_case_is_the_label() -> None:
    assert clip_target_of("squat", "s1", {}, "Label") == "squat"
    assert clip_target_of("squat", "s1", {}, " SUBJECT") == "s1"
    # a column of that name in the extras is still the column's value
    assert clip_target_of("squat", "s1", {"Label": "deep"}, "Label") == "deep"
    listed = _listed({"a": 3, "b": 3})
    assert check_listed(listed, CompareSettings(cv="kfold", target="Label", k=2), "d") is True
