"""Session 53, task X: a clip whose hips are out of view has its arms stated in the frame of
its shoulders and the world's up, which takes the trunk to be upright (hunt 53g); a person
lying or bent over, whose head shows the trunk is not upright, has them unavailable there,
not stated wrongly with confidence 1."""

from __future__ import annotations

import numpy as np
import pytest

from features.signals import ANGLE_SIGNALS, state_signals
from tests.bodies import HEAD, UPPER_BODY, rot_x, rotate, standing, to_sequence

HIPS = np.array([0.0, 1.0, 0.0])  # where tests.bodies.standing's hips are, between them
NECK = np.array([0.0, 1.5, 0.0])


def _above_the_waist(pitch: float, neck: float) -> dict[str, np.ndarray]:
    """tests.bodies.standing from the shoulders up (arms hanging along the trunk), its head
    bent ``neck`` degrees forward at the neck, then the whole body pitched ``pitch`` degrees
    forward about the hips (-90: lying on the back, 90: bent over, the trunk level)."""
    body = {j: xyz for j, xyz in standing().items() if j in UPPER_BODY}
    body = rotate(body, HEAD, rot_x(neck), NECK)
    return rotate(body, tuple(body), rot_x(pitch), HIPS)


def _angles(pitch: float, neck: float, backend: str) -> dict[str, float]:
    seq = to_sequence(*[_above_the_waist(pitch, neck)] * 3)
    values = np.degrees(state_signals(seq, backend).values[0])
    return dict(zip(ANGLE_SIGNALS, values, strict=False))


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_arms_of_a_person_lying_or_bent_over_without_hips_are_unavailable(backend: str) -> None:
    """Lying on the back or bent over level (pitched -90 or 90 degrees), the arms along the
    trunk: the upright frame would read them raised 90 degrees from its down and straight in
    front (on main's code the armpit angle 90 and the upper arm 0 or 180 degrees from
    forward: "in front 1.00"), where they hang by the sides. The head's line from the neck
    lies level, 90 degrees from the world's up: every angle of that frame is unavailable; the
    elbows, which need no frame, stay straight (180 degrees). Upright with the head bent 50
    degrees forward or back (about as far as a neck bends), the frame stands: the arms
    hanging straight down (armpit 0 degrees, the upper arm 90 degrees from forward in the
    sagittal plane), the head's line 90 - 50 = 40 degrees from forward, or 140."""
    for pitch in (-90.0, 90.0):
        got = _angles(pitch, 0.0, backend)
        for side in ("left", "right"):
            for part in ("armpit", "upper_arm_sagittal", "upper_arm_frontal"):
                assert np.isnan(got[f"{side}_{part}"]), (pitch, side, part)
            assert got[f"{side}_elbow"] == pytest.approx(180.0, abs=1e-6)
        for name in ("neck_sagittal", "neck_frontal", "neck_transverse"):
            assert np.isnan(got[name]), (pitch, name)
    for neck in (-50.0, 50.0):
        got = _angles(0.0, neck, backend)
        assert got["left_armpit"] == pytest.approx(0.0, abs=1e-6)
        assert got["right_upper_arm_sagittal"] == pytest.approx(90.0, abs=1e-6)
        assert got["neck_sagittal"] == pytest.approx(90.0 - neck, abs=1e-6)
