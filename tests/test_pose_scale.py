"""A pose whose shoulders or hips lie under a micrometre apart (a skeleton in the wrong unit,
every joint at one point) has no body frame: no frame shows the torso, and the refusal says
why, not "no person" alone."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cbr.dad.classifier import DADClassifier
from features.body import no_person, torso_seen, torso_share
from features.errors import DataError
from tests.bodies import standing, to_sequence


def _torso(shoulder_gap: float, hip_gap: float) -> np.ndarray:
    """Left and right shoulders ``shoulder_gap`` apart at 1.4 m, hips ``hip_gap`` apart at
    0.9 m (metres, y up)."""
    return np.array([[shoulder_gap / 2, 1.4, 0], [-shoulder_gap / 2, 1.4, 0],
                     [hip_gap / 2, 0.9, 0], [-hip_gap / 2, 0.9, 0]])  # fmt: skip


def test_shoulders_or_hips_under_a_micrometre_apart_show_no_torso() -> None:
    """The body frame needs links of at least features.geometry.MIN_LINK_M (1 µm): a torso
    whose shoulders (or hips) are closer was counted as seen while no angle of it existed."""
    assert torso_seen(_torso(0.4, 0.3))
    assert torso_seen(_torso(2e-6, 2e-6))
    assert not torso_seen(_torso(0.5e-6, 0.3))
    assert not torso_seen(_torso(0.4, 0.5e-6))
    assert not torso_seen(_torso(0.0, 0.0))


def test_no_person_says_whether_joints_are_missing_or_at_micrometre_scale() -> None:
    seq = to_sequence(*[standing()] * 6)
    assert torso_share(seq) == 1.0
    tiny = replace(seq, positions=seq.positions * 1e-6)
    assert torso_share(tiny) == 0.0
    assert "positions must be metres" in no_person(tiny)
    blank = replace(seq, positions=np.full_like(seq.positions, np.nan))
    assert no_person(blank) == "shows no person (no frame with a torso)"


def test_classifying_a_micrometre_skeleton_names_the_unit() -> None:
    """DAD's judging refuses it (it needs a body frame) with the reason, not "no person"
    alone."""
    seq = to_sequence(*[standing()] * 6)
    fitted = DADClassifier().fit([seq, seq], ["a", "b"])
    tiny = replace(seq, positions=seq.positions * 1e-6, source="tiny.npz")
    with pytest.raises(DataError, match="positions must be metres"):
        fitted.predict([tiny])
