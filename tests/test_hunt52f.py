"""Hunt 52F: a jittered drop-out of a live source, numba's on-disk cache past a file size
limit, and a HEIF photo whose colr box states another colour range than its coded stream.

- A live source (``watch``) whose frames stop for a quarter to half a second and resume on
  time (a drop-out), its arrivals jittered, is told from a burst by the frames after the
  pause, not the first alone (:meth:`posecbr.commands.watch.Regrid._burst`): before, a frame
  after the pause that came early and one after it late had the pause taken for a burst's
  (frames held up, read at once), every frame after it placed by its count, as early as the
  pause was long.
- A kernel compiled with ``cache=True`` (``features._fluent_kernels._compiled``) that finds no
  room to save itself to numba's cache (a file size limit, ``ulimit -f``; a full disk) is used
  unsaved: before, numba's failed write ended the command, one that writes no file of its own
  (``posecbr describe`` of a long clip), with "cannot write: ... File too large".
- A HEIC or AVIF photo whose colr box (nclx) states full range where its coded stream states
  limited (or none), or the reverse, is read in the box's range, as libheif and libavif
  read it (ISO/IEC 23008-12: the box rules): before, FFmpeg's decoding by the stream's
  range stood, greys 10-17 levels off.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pytest
from PIL import Image, features

from features._fluent_kernels import _compiled
from features.pose_estimation import iter_frames
from posecbr.commands.watch import Regrid
from tests.test_hunt49e import _frame
from tests.test_hunt50a import _taken
from tests.test_hunt50e import _box


@pytest.mark.parametrize("fps", [30.0, 15.0])
def test_a_jittered_drop_out_is_not_taken_for_a_burst(
    fps: float, capsys: pytest.CaptureFixture[str]
) -> None:
    """A camera at ``fps`` for 6 s whose frames taken within 3.0-3.4 s are lost, each frame
    read 0.35 of a frame interval early or late in turn, the first after the pause late (the
    next then comes 0.3 of an interval after it, the one after that 1.7): a drop-out. Grid
    time k (one to a frame, as the frames came at the rate begun with) has the pose of
    k / fps, the grid times strictly inside the pause missing, and the pause said as a stall,
    not a burst. Before, the second frame, 0.3 of an interval after the first, had the pause
    taken for a burst's: the frames after it placed by their count, 0.37-0.4 s early."""
    taken = np.arange(round(6 * fps)) / fps
    lost = (taken > 3.0) & (taken < 3.4)
    kept = np.flatnonzero(~lost)
    first = int(np.flatnonzero(lost)[-1]) + 1  # the first frame after the pause
    came = taken + np.where((np.arange(len(taken)) - first) % 2 == 0, 0.35, -0.35) / fps
    frames = [_frame(j, came[i], taken[i]) for j, i in enumerate(kept)]
    values, _shown = _taken(Regrid(fps, "0"), frames)
    assert len(values) == len(taken)
    np.testing.assert_array_equal(np.isnan(values), lost)
    np.testing.assert_allclose(values[~lost], taken[~lost], atol=1e-9)
    err = capsys.readouterr().err
    assert err.count("the stream stalled") == 1 and "at once" not in err


def _plus_one(n: int) -> int:
    return n + 1


def test_a_kernel_without_room_in_the_cache_is_used_unsaved(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, file_size_limit: Callable[[int], None]
) -> None:
    """The cache's files of this function are several kB; with 1 kB allowed none fits. Before:
    ``OSError: [Errno 27] File too large`` from numba's save."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernel = _compiled(cache=True)(_plus_one)
    file_size_limit(1 << 10)
    assert kernel(5) == 6
    # nothing cut at the limit left behind: numba writes a temporary and renames it
    assert [
        p.name for p in tmp_path.rglob("*") if p.is_file() and p.stat().st_size >= 1 << 10
    ] == []
    assert not list(tmp_path.rglob("*.tmp.*"))


def _nclx(full: bool) -> bytes:
    """A colr box of type nclx (BT.709 primaries, sRGB transfer, BT.601 matrix) stating full
    range or limited."""
    return _box(b"colr", b"nclx" + struct.pack(">HHHB", 1, 13, 6, 0x80 if full else 0))


def test_a_heic_whose_colr_box_says_full_range_is_read_in_full_range(tmp_path: Path) -> None:
    """Four grey quarters (40, 100, 160, 220) coded by x265 in limited range (PyAV's
    conversion: luma 16 + 219 g / 255, that is 50, 102, 153, 205; its VUI states no range),
    in a HEIC whose colr box states full range: the box rules (ISO/IEC 23008-12; libheif
    decoded this file to 50, 102, 153, 205), so the luma is the grey, within x265's error
    (2 levels). Before, FFmpeg's limited range stood: 40, 100, 160, 220, 10-15 levels off.
    The same file without the box reads as before."""
    from tests.test_hunt51f import _x265
    from tests.test_hunt51u import _heic, _quarters

    if not _x265():
        pytest.skip("PyAV without the x265 encoder")
    path = tmp_path / "full.heic"
    path.write_bytes(_heic(_quarters(), [_nclx(True)]))
    (frame,) = list(iter_frames(path))
    path.write_bytes(_heic(_quarters(), []))
    (plain,) = list(iter_frames(path))
    luma = np.round(16 + 219 * _quarters().astype(float) / 255)
    assert np.abs(frame.astype(float) - luma).max() <= 2
    assert np.abs(plain.astype(float) - _quarters()).max() <= 2


@pytest.mark.skipif(not features.check("avif"), reason="Pillow without AVIF")
@pytest.mark.parametrize("written", ["limited", "full"])
def test_an_avif_whose_colr_box_says_the_other_range_is_read_as_libavif_reads_it(
    written: str, tmp_path: Path
) -> None:
    """Grey quarters written by Pillow (libavif) in ``written`` range, then the full-range
    flag of its colr box turned over (the AV1 sequence header still says ``written``): read
    as Pillow reads it (libavif takes the box's range), within 2 levels; 11-17 levels off
    before (the stream's range taken)."""
    path = tmp_path / "grey.avif"
    Image.fromarray(_grey()).save(path, quality=95, range=written)
    data = bytearray(path.read_bytes())
    flag = data.index(b"colrnclx") + 14
    data[flag] ^= 0x80
    path.write_bytes(bytes(data))
    with Image.open(path) as picture:
        expected = np.asarray(picture.convert("RGB")).astype(int)
    (frame,) = list(iter_frames(path))
    assert np.abs(frame.astype(int) - expected).max() <= 2
    assert np.abs(expected - _grey()).max() >= 10  # the box's range is not the written one


def _grey() -> np.ndarray:
    """A 96x64 picture of four grey quarters, 40, 100, 160, 220 (by rows from the top left)."""
    grey = np.zeros((64, 96, 3), np.uint8)
    grey[:32, :48], grey[:32, 48:], grey[32:, :48], grey[32:, 48:] = 40, 100, 160, 220
    return grey
