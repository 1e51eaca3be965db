"""Bug hunt 31b: the mocap path with another person's recordings (CMU-style ASF/AMC files
and label files as real ones vary), converted, trained on and segmented."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.errors import DataError
from features.readers.asfamc import read_asf_amc
from tests.badinput import refused
from tests.test_readers_asfamc import AMC, ASF, _write


def _renumbered(numbers: list[int]) -> str:
    """The test AMC file (three frames, their numbers on lines 4, 9 and 14) with its frames
    numbered ``numbers``."""
    lines = AMC.split("\n")
    for line_no, n in zip((4, 9, 14), numbers, strict=True):
        lines[line_no - 1] = str(n)
    return "\n".join(lines)


def test_amc_frames_numbered_from_zero_read_as_from_one(tmp_path: Path) -> None:
    """Frame numbers count the frames; where they start does not matter."""
    one = read_asf_amc(*_write(tmp_path, amc=_renumbered([1, 2, 3])))
    zero = read_asf_amc(*_write(tmp_path, amc=_renumbered([0, 1, 2])))
    np.testing.assert_array_equal(one.positions, zero.positions)
    assert zero.n_frames == 3


@pytest.mark.parametrize(
    ("numbers", "message"),
    [
        ([1, 2, 5], "line 14: frame 5 follows frame 2 "),  # two frames missing
        ([1, 3, 2], "line 9: frame 3 follows frame 1 "),  # out of order
        ([1, 2, 2], "line 14: frame 2 follows frame 2 "),  # one frame twice
    ],
)
def test_amc_frames_missing_or_out_of_order_are_refused(
    tmp_path: Path, numbers: list[int], message: str
) -> None:
    """Frames 1, 2, 5 were read as three frames one after another: the time between frame 2
    and 5 vanished, and every label after it (one per 12 frames, say) landed 3 frames late
    from there on. The frame number names where the file jumps."""
    asf, amc = _write(tmp_path, amc=_renumbered(numbers))
    with pytest.raises(DataError, match=message):
        read_asf_amc(asf, amc)


def test_convert_refuses_an_amc_file_with_a_gap_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    asf, amc = _write(tmp_path, asf=ASF, amc=_renumbered([1, 2, 4]))
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, str(amc), "line 14: frame 4 follows frame 2")
