"""Hunt 49h: a new user's afternoon with long recordings. A label file that does not fit a
recording whose frame rate was assumed (an AMC file carries none: read at CMU's and HDM05's
120 fps) says the rate was assumed, where it said only "at 120 fps", as though the file had
stated it: `train --frame-labels` of such a file, and a pose file `convert` made of it
(its metadata keeps where the rate came from), refused before it is read."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.datasets import check_fits_before_read, split_by_labels
from features.errors import DataError
from features.poses import save_pose
from features.readers.asfamc import read_asf_amc
from tests.test_hunt40k import _head

ASSUMED = "at 120 fps (assumed: AMC files carry no rate, CMU and HDM05 record at 120) need"


@pytest.fixture(scope="module")
def amc(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """CMU 13_31's first 240 frames (2 s at 120 fps; taken at 60 fps, 4 s) and the skeleton
    CMU's takes are read with."""
    folder = tmp_path_factory.mktemp("hunt49h")
    rec = _head(shared_data / "cmu-mocap6" / "amc" / "13_31.amc", 240, folder / "13_31.amc")
    return rec, shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"


def test_a_recording_cut_by_its_labels_says_the_amc_rate_was_assumed(
    amc: tuple[Path, Path], tmp_path: Path
) -> None:
    """40 labels of 0.1 s (the 4 s of 240 frames at 60 fps) do not fit 240 frames at 120 fps
    (2 s: 20 or 21 labels), as `train --frame-labels` and a labels CSV's recordings cut it;
    the rate given is not said to be assumed."""
    rec, asf = amc
    with pytest.raises(DataError) as err:
        split_by_labels(read_asf_amc(asf, rec), ["Twist"] * 40, 0.1, tmp_path / "t.txt")
    assert f"the recording 13_31.amc: 240 frames {ASSUMED} 20 or 21" in str(err.value)
    with pytest.raises(DataError) as err:
        split_by_labels(read_asf_amc(asf, rec, fps=60.0), ["Twist"] * 80, 0.1, "t.txt")
    assert "240 frames at 60 fps need 40 or 41" in str(err.value)


def test_a_pose_file_converted_from_amc_says_its_rate_was_assumed_before_it_is_read(
    amc: tuple[Path, Path], tmp_path: Path
) -> None:
    rec, asf = amc
    pose = save_pose(read_asf_amc(asf, rec), tmp_path / "13_31.npz")
    with pytest.raises(DataError) as err:
        check_fits_before_read(pose, 40, 0.1, tmp_path / "t.txt", "13_31.npz")
    assert f"240 frames {ASSUMED} 20 or 21" in str(err.value)
    with pytest.raises(DataError) as err:  # the rate given: not assumed
        check_fits_before_read(pose, 80, 0.1, tmp_path / "t.txt", "13_31.npz", fps=60.0)
    assert "240 frames at 60 fps need 40 or 41" in str(err.value)
