"""Hunt 51d: ``watch --out`` of a stream that starts slow, and outputs of several files.

- A live source whose rate rises within its first 4 s is watched again from its start
  (``Watcher._remake``); with ``--out`` the frames of those seconds are drawn again, and
  their images were held in memory until then (4 s of 1920x1080 at 30 fps: 750 MB). They
  are kept in a temporary file now (``KeptImages``), read back when drawn again.
- The note that the ``--out`` video's odd-sided frames are padded was said twice, once
  more when the video was drawn again at the rate the stream rose to.
- ``segment``'s pictures and overlays, and a clip's pose file and overlay in ``extract``,
  are written together (``features.fileio.write_together``): all, or none and the files
  there before as they were. Before, each was written in turn.
"""

from __future__ import annotations

import contextlib
import gc
import io
import time
import weakref
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

import features.pose_estimation as pose_estimation
from features.interrupts import INTERRUPTED_STATUS
from features.pose_estimation import StreamFrame
from features.pose_estimation.tracker import FramePose
from features.readers.asfamc import read_asf_amc
from posecbr.cli import main
from posecbr.commands.watch import Watcher
from tests.badinput import assert_unchanged, good_pose_file, small_case_base, snapshot
from tests.test_hunt50j import _clip
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows

SLOW = 15  # frames at 15 fps, the first second, then 30 fps
N = SLOW + 60
HEIGHT, WIDTH = 121, 161  # odd sides: the video's frames padded to 122x162


def _colour(i: int) -> tuple[int, int, int]:
    """Frame ``i``'s colour (RGB): green and blue steps of 12 apart name it (up to 18 x 18
    frames), far enough apart to tell after MPEG-4's loss."""
    return 0, 20 + 12 * (i % 18), 20 + 12 * (i // 18)


def _times(stall_s: float = 0.0, after_s: float = 0.5) -> list[float]:
    """When the camera's frames come: 15 a second for the first second, then 30, none for
    ``stall_s`` after the one at ``after_s`` (those after it that much later)."""
    times = [i / 15.0 if i < SLOW else 1.0 + (i - SLOW) / 30.0 for i in range(N)]
    return [t + (stall_s if t > after_s + 1e-6 else 0.0) for t in times]


def _slow_watch(
    db: Path, world: np.ndarray, out: Path | None, times: list[float]
) -> dict[str, Any]:
    """``watch 0 --out OUT`` of a camera that sends 15 frames a second for its first second,
    then 30 (``world``: CMU 13_30's jumping jacks at 30 fps, each frame the pose at the time
    it was taken), each frame's image one colour (:func:`_colour`): the exit status, stderr,
    and how many of the images the stream gave were still alive (not freed) each time the
    watch began again. ``times``: when each frame comes (:func:`_times`; the poses the
    same). ``out`` None: no ``--out``."""
    given: list[weakref.ref[np.ndarray]] = []

    def stream(source: Any, **kwargs: Any) -> Iterator[StreamFrame]:
        for i, t in enumerate(times):
            image = np.full((33, 5), np.nan)
            image[:, 3] = 1.0  # every joint seen (mocap), none placed in the picture
            pose = FramePose(image, world[i + min(i, SLOW)], True, False, 1.0, None)
            rgb = np.empty((HEIGHT, WIDTH, 3), dtype=np.uint8)
            rgb[:] = _colour(i)
            given.append(weakref.ref(rgb))
            yield StreamFrame(i, float(t), pose, rgb, time.perf_counter())

    alive: list[int] = []
    remake = Watcher._remake

    def counted(self: Watcher, fps: float) -> None:
        gc.collect()  # an image only a cycle of garbage holds is not held
        alive.append(sum(ref() is not None for ref in given))
        remake(self, fps)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pose_estimation, "stream_poses", stream)
        mp.setattr(Watcher, "_remake", counted)
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            written = [] if out is None else ["--out", str(out)]
            status = main(["watch", "0", "--db", str(db), "--max-frames", str(N), *written])
    return {"status": status, "out": out, "err": err.getvalue(), "alive": alive}


def _colours_seen(video: Path) -> list[np.ndarray]:
    """Each frame's colour (BGR) in ``video``, the median of a patch at its bottom right,
    where nothing is drawn."""
    cap = cv2.VideoCapture(str(video))
    seen = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        seen.append(np.median(bgr[HEIGHT - 30 : HEIGHT - 10, WIDTH - 30 : WIDTH - 10], axis=(0, 1)))
    cap.release()
    return seen


# on one xdist worker: the module's jumping_jacks, slow_start made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt51d")


@pytest.fixture(scope="module")
def jumping_jacks(shared_data: Path) -> np.ndarray:
    """CMU 13_30 (120 fps) at 30 fps: world positions ``(frames, joints, 3)``."""
    seq = read_asf_amc(
        shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf",
        shared_data / "cmu-mocap6" / "amc" / "13_30.amc",
    )
    return seq.positions[::4]


@pytest.fixture(scope="module")
def slow_start(
    case_base: Path,  # noqa: F811
    jumping_jacks: np.ndarray,
    tmp_path_factory: pytest.TempPathFactory,
) -> dict[str, Any]:
    """:func:`_slow_watch` into a folder of its own."""
    out = tmp_path_factory.mktemp("hunt51d") / "watched.mp4"
    return _slow_watch(case_base, jumping_jacks, out, _times())


def test_a_slow_start_drawn_again_holds_not_its_images_in_memory(
    slow_start: dict[str, Any],
) -> None:
    """The rise is taken once, when about 1.9 s of the stream (about 42 frames) had come;
    then only the frames in flight were alive (the reader's queue of 8, the one it reads,
    the one in hand, the one before it: 8-13 seen, under load), the first frames' images
    freed. Before, every frame read since the first was, and those queued (52-53). The
    video is the 30-fps grid from the first frame: grid time k (k / 30 s) shows the frame
    on screen then, the last that came by k / 30 s (for k < 30 the 15-fps frame k // 2,
    then frame 15 + (k - 30)), each image's colour kept through the read back; nothing is
    left beside the video."""
    assert slow_start["status"] == 0
    assert slow_start["err"].count("the frame rate rose from 15 to 30 fps at 1.9 s") == 1
    [alive] = slow_start["alive"]
    assert alive <= 20
    seen = _colours_seen(slow_start["out"])
    times = _times()
    assert len(seen) == round(times[-1] * 30) + 1
    expected = [max(i for i, t in enumerate(times) if t <= k / 30 + 1e-6) for k in range(len(seen))]
    for k, (bgr_median, frame) in enumerate(zip(seen, expected, strict=True)):
        red, green, blue = _colour(frame)
        np.testing.assert_allclose(bgr_median, [blue, green, red], atol=5, err_msg=f"grid {k}")
    assert sorted(p.name for p in slow_start["out"].parent.iterdir()) == ["watched.mp4"]


def test_the_padding_note_is_said_once_when_the_video_is_drawn_again(
    slow_start: dict[str, Any],
) -> None:
    """The frames' odd sides padded to even ones: said once, as the frames are written
    once. Before, said a second time when the video was drawn again at 30 fps."""
    notes = [line for line in slow_start["err"].splitlines() if "a black column" in line]
    assert notes == [
        f"note: {slow_start['out']}: 161x121 frames written 162x122, a black column at the"
        " right and row at the bottom added (MP4 frames have even sides)"
    ]


def test_a_slow_start_whose_frames_cannot_be_kept_is_followed_at_its_first_rate(
    case_base: Path,  # noqa: F811
    jumping_jacks: np.ndarray,
    tmp_path: Path,
    file_size_limit: Callable[[int], None],
) -> None:
    """The disk full for the kept frames (a file size limit of 1 MB: 18 of the 58-KB
    images; the video, at most 307 KB, fits): said once, and the stream followed at its
    first rate as a rise after 4 s is (the grid 0.9 s ahead of the clock made up), the
    video written, nothing else left. Before, the frames were in memory (no such limit): the
    rise taken, the video drawn again at 30 fps."""
    out = tmp_path / "watched.mp4"
    file_size_limit(1_000_000)
    watched = _slow_watch(case_base, jumping_jacks, out, _times())
    assert watched["status"] == 0
    notes = [line for line in watched["err"].splitlines() if "cannot be kept" in line]
    assert notes == [
        f"note: {out}: the first frames cannot be kept to be drawn again (File too large): a"
        " rise of the stream's frame rate is followed at its first rate"
    ]
    assert watched["alive"] == []  # not watched again
    assert "the frame rate changed from 15 to 30 fps" in watched["err"]
    cap = cv2.VideoCapture(str(out))
    assert cap.get(cv2.CAP_PROP_FPS) == 15.0
    cap.release()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["watched.mp4"]


def test_a_stall_right_after_the_rise_shows_the_kept_frame_before_it(
    case_base: Path,  # noqa: F811
    jumping_jacks: np.ndarray,
    tmp_path: Path,
) -> None:
    """No frame for 0.6 s after the one at 1.93 s, the rise taken just before: the stall's
    grid times show the frame before it, one of the kept frames, whose image is read back
    after the others were drawn again (the kept images stay until no grid time can show
    one). Each grid time k shows the last frame that came by k / 30 s."""
    out = tmp_path / "watched.mp4"
    times = _times(0.6, after_s=1.95)
    watched = _slow_watch(case_base, jumping_jacks, out, times)
    assert watched["status"] == 0, watched["err"]
    assert watched["err"].count("the frame rate rose from 15 to 30 fps") == 1
    assert watched["err"].count("the stream stalled: 0.6 s without frames") == 1
    seen = _colours_seen(out)
    assert len(seen) == round(times[-1] * 30) + 1
    for k, bgr_median in enumerate(seen):
        frame = max(i for i, t in enumerate(times) if t <= k / 30 + 1e-6)
        red, green, blue = _colour(frame)
        np.testing.assert_allclose(bgr_median, [blue, green, red], atol=5, err_msg=f"grid {k}")


def test_a_stall_before_the_rise_is_said_once(
    case_base: Path,  # noqa: F811
    jumping_jacks: np.ndarray,
) -> None:
    """No frame for 0.6 s after the one at 0.5 s, then the stream as before: the stall is
    said once, when it came, and the rise taken. Before, it was said again when the kept
    frames were taken again at 30 fps ("... at 0.5-1.1 s", then "... at 0.4-1.1 s")."""
    watched = _slow_watch(case_base, jumping_jacks, None, _times(0.6))
    assert watched["status"] == 0
    assert watched["err"].count("the frame rate rose from") == 1
    stalls = [line for line in watched["err"].splitlines() if "the stream stalled" in line]
    assert stalls == ["note: 0: the stream stalled: 0.7 s without frames at 0.5-1.1 s left missing"]


def test_segment_pictures_are_written_all_or_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``segment A B --plot DIR/`` (DIR to be made) stopped by Ctrl-C while its second
    picture is drawn, the first drawn: "interrupted", exit 130, and nothing left, not DIR,
    not the first picture, no temporary file. Before, the first recording's picture was
    left in DIR. (A full disk goes the same way: tests of extract below.)"""
    import features.timeline as timeline

    db = small_case_base(tmp_path)
    clips = sorted((tmp_path / "train").glob("l*/*.npz"))[:2]  # Latin names: no font search
    drawn: list[Path] = []
    plot = timeline.plot_timeline

    def stopped(tl: Any, path: Path, **kwargs: Any) -> Path:
        drawn.append(path)
        if len(drawn) == 2:
            raise KeyboardInterrupt
        return plot(tl, path, **kwargs)

    monkeypatch.setattr(timeline, "plot_timeline", stopped)
    before = snapshot(tmp_path)
    argv = ["segment", *map(str, clips), "--db", str(db), "--plot", f"{tmp_path}/pics/"]
    capsys.readouterr()
    assert main(argv) == INTERRUPTED_STATUS
    assert capsys.readouterr().err.splitlines()[-1] == "posecbr segment: interrupted"
    assert len(drawn) == 2
    assert_unchanged(tmp_path, before)


def test_extract_leaves_no_pose_file_of_a_clip_whose_overlay_failed(
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    file_size_limit: Callable[[int], None],
) -> None:
    """``extract clip.mp4 --out poses.npz --overlay clip.mp4`` over an earlier pose file of
    the user's, the disk full for the overlay (a limit of 64 KiB: a pose file of 12 frames
    is about 29 KB, their overlay about 140 KB): one line naming the overlay, exit 1, and
    the earlier pose file byte for byte, no other file. Before, the pose file was written
    first: the clip failed with the earlier one replaced by its poses."""
    source = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    clip = _clip(source, tmp_path / "in" / "squat.mp4", 0)
    earlier = good_pose_file(tmp_path / "poses.npz")
    overlay = tmp_path / "squat_overlay.mp4"
    before = snapshot(tmp_path)
    capsys.readouterr()
    file_size_limit(64 * 1024)
    argv = ["extract", str(clip), "--out", str(earlier), "--overlay", str(overlay)]
    assert main(argv) == 1
    [line] = capsys.readouterr().err.splitlines()
    assert_unchanged(tmp_path, before)
    assert line.startswith(f"posecbr extract: error: {overlay}: cannot write: "), line
    assert line.endswith("; none of the 2 files written (the earlier poses.npz kept as it was)")
