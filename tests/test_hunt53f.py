"""Hunt 53f: front kicks done with each leg in turn, from a guard stance whose bent arms and
turned trunk flip with the kicking leg and stay there through the take."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.body import mirrored
from features.joining import Joined, join_repetitions
from features.readers.asfamc import read_asf_amc
from features.repetitions import count_repetitions

TAKES = ("016", "015", "018")
"""Three of HDM05 dg's one-kick takes (the left leg kicks once in each)."""


@pytest.fixture(scope="module")
def kicks(shared_data: Path) -> Joined:
    """The three takes joined, the second mirrored (the same kick with the right leg): three
    kicks, left, right, left, and the count is three by construction (one per take)."""
    folder = shared_data / "hdm05" / "train" / "6"
    takes = [
        read_asf_amc(
            folder / "HDM_dg.asf", folder / f"HDM_dg_kickLFront1Reps_{t}_120.amc"
        ).to_canonical()
        for t in TAKES
    ]
    return join_repetitions(
        [take if i % 2 == 0 else mirrored(take) for i, take in enumerate(takes)]
    )


def test_front_kicks_on_each_side_count_one_per_kick(kicks: Joined) -> None:
    """Before, the side-against-side line was read along the guard's elbows and the trunk's
    twist (they flip with the kicking leg once a take, the quickest change of all): each
    stance stood out as far as a kick, and the third kick reached a sixth as far: 8. Read
    along the angles that go out and come back (the hips), one far point per kick."""
    found = count_repetitions(kicks.seq)
    assert found.alternating
    assert found.count == len(TAKES)
    assert [r.side for r in found.repetitions] == ["left", "right", "left"]
    assert {"left_hip", "right_hip"} <= set(found.moving)
    # each kick's far point in its own take
    bounds = [*kicks.starts.tolist(), kicks.seq.n_frames]
    for i, rep in enumerate(found.repetitions):
        assert bounds[i] <= rep.peak_frame < bounds[i + 1]
