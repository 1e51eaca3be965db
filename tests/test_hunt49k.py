"""Hunt 49k: overlay videos that were quietly not what was asked; an AMC file's assumed rate.

- ``segment --overlay``, ``extract --overlay`` and ``watch --out`` of a video with an odd
  width or height wrote frames a pixel smaller (OpenCV's ``mp4v`` writer cuts a side to
  even): the source's last column or row was lost without a word. The frames are now padded
  to even with black at the right and bottom, every source pixel kept where it was, and it
  is said once.
- A 30000/1001-fps video's overlay was written at 2997/100 (OpenCV keeps a float rate to a
  power-of-ten denominator): 0.0036 s an hour off its source. Its frames now carry the
  source's times exactly (:func:`features.pose_estimation.overlay.retime_mp4`).
- ``segment`` and ``reps`` of an AMC file (which carries no rate) read it at the assumed
  120 fps without a word, unless a label file disagreed; they say it now, as ``convert``
  does, with the way to give another (``--fps``).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from features.errors import DataError
from features.pose_estimation.overlay import check_mp4_size, write_overlay
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from posecbr.commands.watch import Watcher
from tests.media import read_frames
from tests.once import made_once
from tests.test_hunt40k import _head
from tests.test_watch import _cmu_13_29_windows

NTSC = Fraction(30000, 1001)
WIDTH, HEIGHT, FRAMES = 129, 97, 40
GREY, EDGE = 100, 250


@pytest.fixture(scope="module")
def odd_ntsc(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 frames (1.3 s) of 129x97 at exactly 30000/1001 fps (FFV1 in Matroska: lossless, any size),
    grey with the last column and the last row near white: what a cut side loses."""
    av = pytest.importorskip("av")
    path = tmp_path_factory.mktemp("hunt49k") / "odd.mkv"
    picture = np.full((HEIGHT, WIDTH, 3), GREY, np.uint8)
    picture[-1, :] = EDGE
    picture[:, -1] = EDGE
    with av.open(str(path), "w") as out:
        stream = out.add_stream("ffv1", rate=NTSC)
        stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "bgr0"
        for k in range(FRAMES):
            frame = av.VideoFrame.from_ndarray(picture, format="rgb24")
            frame.pts = k
            frame.time_base = 1 / NTSC
            for packet in stream.encode(frame):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


def _frame_times(path: Path) -> list[Fraction]:
    import av

    with av.open(str(path)) as f:
        stream = f.streams.video[0]
        return [Fraction(frame.pts) * stream.time_base for frame in f.decode(stream)]


def test_an_odd_sized_ntsc_overlay_keeps_every_pixel_and_the_source_rate(
    odd_ntsc: Path, tmp_path: Path
) -> None:
    """The overlay of 129x97 frames is 130x98: the source's last column and row (near white)
    are there, a black column and row beyond them (the old overlay, 128x96, ended a pixel
    before them); its frames are at 30000/1001 fps, frame k at k * 1001/30000 s (the old one
    at 2997/100: k * 100/2997 s)."""
    out = tmp_path / "overlay.mp4"
    nobody = np.full((FRAMES, 33, 5), np.nan)
    write_overlay(odd_ntsc, nobody, out, float(NTSC))
    frames, fps = read_frames(out)
    assert len(frames) == FRAMES
    assert frames[0].shape == (HEIGHT + 1, WIDTH + 1, 3)
    for bgr in frames:  # "no person" is written at the top left: the bottom half read
        lower = bgr[HEIGHT // 2 :]
        assert lower[:-2, WIDTH - 1].mean() > EDGE - 25  # the source's last column
        assert lower[-2, 40:WIDTH].mean() > EDGE - 25  # its last row
        assert lower[:-2, WIDTH - 2].mean() < GREY + 25  # grey before them, as it was
        assert lower[:, WIDTH].mean() < 25 and lower[-1].mean() < 25  # the black padding
    assert fps == float(NTSC)
    assert _frame_times(out) == [k * Fraction(1001, 30000) for k in range(FRAMES)]


def test_an_odd_side_too_wide_once_padded_is_refused_before_the_work() -> None:
    """8191 is the widest MP4 frame; 8191 is odd, padded to 8192: refused before any frame is
    drawn (before, its overlay was cut to 8190 without a word)."""
    with pytest.raises(DataError) as err:
        check_mp4_size(8191, 16, "o.mp4")
    assert str(err.value) == (
        "o.mp4: cannot encode an MP4 overlay of 8191x16 frames: MP4 frames are at most 8191"
        " pixels a side and even (an odd side padded by one)"
    )
    check_mp4_size(8190, 17, "o.mp4")  # 8190x18: encodable


def test_watch_out_of_an_odd_sized_ntsc_video_keeps_its_size_and_rate(
    odd_ntsc: Path,
    amc_head: tuple[Path, Path],
    tmp_path: Path,
    shared_data: Path,
    tmp_path_factory: pytest.TempPathFactory,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``watch --out`` of the 129x97, 30000/1001-fps video (the pose model stubbed: CMU
    13_31's first pose in every frame) writes 130x98 frames at 30000/1001 fps and says the
    padding once (before: 128x96 at 2997/100, not a word)."""
    import features.pose_estimation.tracker as tracker
    from features.pose_estimation import PoseEstimator

    db = made_once(
        tmp_path_factory, "cmu-13-29-windows", lambda f: _cmu_13_29_windows(f, shared_data)
    )
    image = np.full((33, 5), np.nan)
    image[:, 3:] = 1.0  # every joint seen, none drawn (no place in the picture)
    standing = read_asf_amc(amc_head[1], amc_head[0]).to_canonical().positions[0]
    pose = tracker.FramePose(image, standing, True, False, 1.0, None)
    stub = SimpleNamespace(name="x")
    session = SimpleNamespace(get_inputs=lambda: [stub], get_outputs=lambda: [stub])
    monkeypatch.setattr(tracker, "make_session", lambda *_args: session)
    monkeypatch.setattr(PoseEstimator, "_process", lambda *_args: pose)
    monkeypatch.setattr(Watcher, "warm_up", lambda _self: None)  # a latency's, 1 s: not here
    out = tmp_path / "watched.mp4"
    capsys.readouterr()
    argv = ["watch", str(odd_ntsc), "--db", str(db), "--out", str(out), "--speed", "0"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    said = (
        f"note: {out}: 129x97 frames written 130x98, a black column at the right and row at"
        " the bottom added (MP4 frames have even sides)"
    )
    assert err.count(said) == 1, err
    frames, fps = read_frames(out)
    assert len(frames) == FRAMES and frames[0].shape == (HEIGHT + 1, WIDTH + 1, 3)
    assert frames[-1][HEIGHT // 2 : -2, WIDTH - 1].mean() > EDGE - 25
    assert fps == float(NTSC)


ASSUMED = (
    "read at 120 fps (assumed: AMC files carry no rate, CMU and HDM05 record at 120); give"
    " its rate with --fps if it was recorded at another"
)


@pytest.fixture(scope="module")
def amc_head(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """CMU 13_31's first 360 frames (3 s at 120 fps) and the skeleton it is read with."""
    folder = tmp_path_factory.mktemp("hunt49k-amc")
    rec = _head(shared_data / "cmu-mocap6" / "amc" / "13_31.amc", 360, folder / "13_31.amc")
    return rec, shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"


def test_reps_of_an_amc_file_says_its_rate_was_assumed(
    amc_head: tuple[Path, Path], shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Said once, naming the file; not when the rate is given (``--fps``) or read from an
    HDM05 name (``..._120``)."""
    rec, asf = amc_head
    capsys.readouterr()
    assert main(["reps", str(rec), "--asf", str(asf)]) == 0
    assert capsys.readouterr().err == f"note: {rec}: {ASSUMED}\n"
    assert main(["reps", str(rec), "--asf", str(asf), "--fps", "120"]) == 0
    assert capsys.readouterr().err == ""
    named = next((shared_data / "hdm05" / "train" / "1").glob("HDM_bd_*_120.amc"))
    assert main(["reps", str(named)]) == 0
    assert "note:" not in capsys.readouterr().err


def test_segment_of_an_amc_file_says_its_rate_was_assumed(
    amc_head: tuple[Path, Path],
    shared_data: Path,
    tmp_path_factory: pytest.TempPathFactory,
    capsys: pytest.CaptureFixture[str],
) -> None:
    rec, asf = amc_head
    db = made_once(
        tmp_path_factory, "cmu-13-29-windows", lambda f: _cmu_13_29_windows(f, shared_data)
    )
    capsys.readouterr()
    assert main(["segment", str(rec), "--asf", str(asf), "--db", str(db)]) == 0
    assert capsys.readouterr().err == f"note: {rec}: {ASSUMED}\n"
