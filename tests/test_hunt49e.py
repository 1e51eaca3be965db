"""Hunt 49e: ``watch`` of a live source whose frame rate changes; an unfinished MP4 served
over HTTP.

- A live source's rate was measured over its first second and kept for good: a webcam whose
  auto exposure halves its rate as the light falls (30 to 15 fps) had each frame still
  count 1/30 s, its windows holding 4 s of movement and its segments timed at half the
  wall clock's speed. Now, once its rate over the latest half second has stayed off by more
  than a fifth for 0.8 s, its poses are put on the grid by the wall clock
  (:meth:`posecbr.commands.watch.Regrid._rate_changed`), said once on stderr.
- An MP4 still being recorded (frames, no index), served over HTTP, was "cannot open camera
  or stream"; a file here is refused as unfinished: so is the served one now.
- SIGTERM sometimes ended a watch with "terminate called without an active exception" (exit
  134) after its last line: the end of the watch waited 2 s for the reader thread, and on a
  machine so loaded that a frame took longer, Python shut down with the thread inside
  onnxruntime. The end of a watch now closes the pose estimator, waiting for the frame in
  hand, and no frame is begun after (:meth:`PoseEstimator.close`).
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import features.pose_estimation.tracker as tracker
from features.errors import DataError
from features.pose_estimation import PoseEstimator, stream_poses
from posecbr.commands import watch
from posecbr.commands.watch import Regrid
from tests.test_hunt34c import _Quiet, _serving, _Unsized
from tests.test_hunt48h1 import UNFINISHED, _recording


def _frame(index: int, time_s: float, pose: float | None = None) -> SimpleNamespace:
    """A live source's frame read at ``time_s`` (the wall clock's), every coordinate of its
    pose ``pose`` (``time_s`` when not given): a grid time's pose, blended linearly between two
    frames, is the blend of theirs (with the default, the wall clock's time there)."""
    return SimpleNamespace(
        index=index,
        time_s=time_s,
        video_time_s=float("nan"),
        seen_world=np.full((33, 3), time_s if pose is None else pose),
        visibility=np.ones(33),
        pose=SimpleNamespace(image=np.zeros((33, 5))),
    )


def test_a_camera_that_halves_its_rate_is_followed_by_the_wall_clock(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A camera at 30 fps (each interval off by up to 20 %, at random) for 10 s, with a
    one-off hiccup of a quarter second at 5 s, then at 15 fps for 10 s (its auto exposure as
    the light falls): the frames before the fall are passed one to a grid time, as they
    come (neither the jitter nor the hiccup is a change of rate); over the last 5 s, the
    75 frames at 15 fps give 150 grid times, each 1/30 s of the wall clock after the one
    before (a pose halfway between two frames, blended, at the times between). The frames
    at the half rate before the change is taken (1.1 s or so of them, 0.55 s of movement on
    the grid) fell behind the clock: when it is taken, the grid times they fell behind by
    are left missing, said in the note, and every grid time after lies on the wall clock as
    the last frame before the fall did (within a grid frame: the jitter of the frames in
    the half second before the change), the grid ending within the hiccup's quarter second
    (joined as before) and a frame of the 20 s the camera ran. Before, the 75 frames gave
    75 grid times 1/15 s apart, and the grid ended at 15 s; then, each grid time after the
    change lay 0.55 s early."""
    rng = np.random.default_rng(49)
    times = [0.0]
    while times[-1] < 10.0 - 1.0 / 30.0:
        hiccup = 5.0 <= times[-1] < 5.0 + 1.0 / 30.0
        times.append(times[-1] + (0.25 if hiccup else rng.uniform(0.8, 1.2) / 30.0))
    fell = len(times)
    times += [times[-1] + (j + 1) / 15.0 for j in range(150)]
    grid = Regrid(30.0, "0")
    values: list[float] = []
    given: list[int] = []
    for i, t in enumerate(times):
        taken = grid.take(_frame(i, t))
        given.append(len(taken))
        values += [float(world[0, 0]) for world, _vis, _shown in taken]
    assert given[:fell] == [1] * fell  # one grid time a frame, the frame's own pose
    assert values[:fell] == times[:fell]
    last = values[-150:]
    assert sum(given[-75:]) == 150
    np.testing.assert_allclose(np.diff(last), 1.0 / 30.0, atol=1e-9)
    assert times[-1] - 1.0 / 30.0 < last[-1] <= times[-1]  # the last up to its frame
    on_time = times[fell - 1] - (fell - 1) / 30.0  # the wall clock's time of grid time 0
    after = len(values) - 150 + np.arange(150)  # the grid times of the last 5 s
    np.testing.assert_allclose(np.array(last) - after / 30.0, on_time, atol=1.0 / 30.0)
    missing = int(np.isnan(values).sum())
    assert 0.45 <= missing / 30.0 <= 0.65  # 1.1 s at 15 fps counted at 30
    assert times[-1] - 0.25 - 1.0 / 30.0 <= len(values) / 30.0 <= times[-1] + 1.0 / 30.0
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "note: 0: the frame rate changed from 30 to 15 fps" in err
    assert f"({missing} frames, {missing / 30.0:.2f} s, left missing: the frames before," in err


class _Growing(_Unsized):
    """Sends a file under ``/growing/`` as a file still being written is sent (no length
    stated: its end is the stream's), any other as it is (its length stated)."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        if self.path.startswith("/growing/"):
            self.path = self.path.removeprefix("/growing")
            super().do_GET()
        else:
            _Quiet.do_GET(self)


def test_an_mp4_still_being_recorded_served_over_http_says_so(tmp_path: Path) -> None:
    """The 12-frame MP4 as it stood before its recorder wrote the index (tests/test_hunt48h1:
    its frames' box stating size 0, a 64-bit 0, or its final size), served over HTTP with
    its length stated and as a file being written is sent (no length: the stream ends where
    the file does): refused as unfinished, as the file here is, naming the URL (it was
    "cannot open camera or stream")."""
    folder = tmp_path / "served"
    folder.mkdir()
    for header in ("zero", "large", "sized"):
        (folder / f"{header}.mp4").write_bytes(_recording(tmp_path, header)[1])
    words = UNFINISHED.replace("its frames", "the served file's frames")
    with _serving(folder, _Growing) as address:
        for sent in ("", "/growing"):
            for header in ("zero", "large", "sized"):
                url = f"{address}{sent}/{header}.mp4"
                with pytest.raises(DataError) as refused:
                    next(stream_poses(url, timeout_s=5.0))
                assert str(refused.value) == f"{url}: {words}"


def test_the_end_of_a_watch_waits_for_the_pose_model_and_begins_no_frame_after(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A live source read in the watch's reader thread, each frame taking the pose model
    0.2 s (a machine so loaded that the process gets little of it), the watch ended while a
    frame is in the model and the reader's join given 0.02 s (2 s, shorter than such a
    frame): when the end returns, every frame begun is finished (no thread is inside the
    model as Python shuts down, which aborted the process: "terminate called without an
    active exception") and none begins after it. Before, the end returned with the frame
    still in the model, and the reader went on to the next."""
    stub = SimpleNamespace(name="x")
    session = SimpleNamespace(get_inputs=lambda: [stub], get_outputs=lambda: [stub])
    monkeypatch.setattr(tracker, "make_session", lambda *_args: session)
    estimator = PoseEstimator()
    log: list[str] = []
    inside = threading.Event()

    def model(*_args: object) -> tracker.FramePose:
        log.append("begun")
        inside.set()
        time.sleep(0.2)
        log.append("done")
        return tracker.FramePose.missing(True)

    monkeypatch.setattr(estimator, "_process", model)
    monkeypatch.setattr(watch, "JOIN_S", 0.02)

    def camera() -> object:
        while True:
            yield estimator.process(np.zeros((8, 8, 3), dtype=np.uint8))

    frames = watch.frames_in_background(camera(), 5.0, model=estimator)
    next(frames)  # the first frame comes; the second is in the model
    assert inside.wait(5.0)
    frames.close()
    assert log[-1] == "done"
    ended = len(log)
    time.sleep(0.1)  # the reader went on at once
    assert len(log) == ended
