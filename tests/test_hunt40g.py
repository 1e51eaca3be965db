"""Hunt 40g: bad input to the long-recording commands (``segment``, ``reps``, ``watch``,
``train --split``, label files, ``convert --fps``).

A recording shorter than a tenth of a second with a joint missing throughout (a BVH file of
one or two frames without hands, a two-frame pose file whose wrist the pose model never
saw) made ``segment`` exit 70, "a bug in posecbr (ValueError: array of sample points is
empty)": an angle seen in no frame counted as followed, its whole clip being one gap no
longer than the 0.1 s that is filled between an angle's values either side, and there were
no values to fill it from. ``segment`` read the movement before it checked the recording
was as long as one window.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.poses import save_pose
from features.repetitions import movement_signals
from features.skeleton import JOINT_INDEX
from tests.badinput import refused, small_case_base
from tests.bodies import rot_x, rotate, standing, to_sequence


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("hunt40g_cb"))


def _bending(frames: int, fps: float, missing: tuple[str, ...]) -> object:
    """A person bending the right elbow to and fro, the joints ``missing`` NaN throughout."""
    poses = []
    for k in range(frames):
        body = standing()
        turn = rot_x(60.0 * np.sin(k / 5.0))
        poses.append(rotate(body, ("right_wrist",), turn, about=body["right_elbow"]))
    seq = to_sequence(*poses, fps=fps)
    pos = seq.positions.copy()
    for name in missing:
        pos[:, JOINT_INDEX[name]] = np.nan
    return replace(seq, positions=pos, source="")


@pytest.mark.parametrize("frames", [1, 2, 3])
def test_segment_of_a_recording_shorter_than_a_window_with_a_joint_never_seen(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case_base: Path, frames: int
) -> None:
    rec = save_pose(_bending(frames, 30.0, ("left_wrist",)), tmp_path / "short.npz")
    duration = f"{frames / 30.0:.2f} s"
    refused(["segment", str(rec), "--db", str(case_base)], tmp_path, capsys,
            str(rec), f"lasts {duration}, shorter than the shortest window")  # fmt: skip


def test_an_angle_seen_in_no_frame_is_not_followed() -> None:
    # 12 frames at 240 fps (0.05 s): the left wrist never seen, a gap shorter than the 0.1 s
    # (24 frames) filled between an angle's values, but there are none to fill it from
    sig = movement_signals(_bending(12, 240.0, ("left_wrist",)))
    assert "left_elbow" not in sig.names
    assert "right_elbow" in sig.names
    assert np.isfinite(sig.values).all()


def test_no_angle_seen_in_any_frame_is_no_person() -> None:
    with pytest.raises(DataError, match="no person in view"):
        movement_signals(_bending(12, 240.0, tuple(JOINT_INDEX)))
