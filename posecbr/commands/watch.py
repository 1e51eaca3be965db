"""``posecbr watch SOURCE --db CB``: segment a live stream as it comes (:mod:`cbr.live`).

SOURCE is a webcam index (``0``), a stream URL (``rtsp://...``) or a video file, which is
played at its own rate, each frame when its presentation time comes (a variable frame rate
as it was filmed; ``--speed 2`` twice as fast, ``--speed 0`` as fast as it decodes), as is
a video file served over the network (a URL whose frame count OpenCV knows, or an HTTP(S)
file whose server states its length: a raw ``.h264`` stream, a browser's WebM), at the rate
the file here would be read at; a live source is timed by the wall clock. Poses come from
BlazePose frame by frame; the rolling activity label, the repetitions counted so far and the
fluents that hold now are drawn on the frames (``--out video.mp4`` writes them, headless;
``--show`` opens a window where OpenCV has one).
One JSON line per finished segment goes to stdout, as it finishes (``start_s``, ``end_s``,
``start_frame``, ``end_frame``, ``label``, null when unknown, ``confidence``, ``unknown``,
``repetitions``, ``explanation``, ``novelty``, ``count`` (the number of repetitions, as
``repetitions`` gives it too), as ``posecbr segment --json`` gives them); a segment's line
comes once the decoders have settled it, seconds after its end, and the first segment's,
when it has no whole repetition of its own, once the first repetition after it is known
(:meth:`cbr.live.LiveSegmenter._judge_held`). With
``--split repetitions`` each repetition is judged too, as ``classify --split repetitions``
judges it (:mod:`cbr.live_verdicts`: counted over the stream, not per segment; judged alone
by the case base once the next one is counted and 0.5 s has passed, given once and never
revised), one JSON line each on stdout as it is judged: ``repetition`` (its number),
``start_s``, ``end_s`` and ``classify --json``'s record of the piece (``start_frame``,
``end_frame``, ``label``: the verdict, ``confidence``, ``text``: its explanation, ...); the
last verdict is drawn on the frames, and the end lists every verdict on stderr. With
``--progress SECONDS``, every SECONDS of the stream while a segment is open, one more line on
the segment in progress (``"event": "progress"``, :meth:`cbr.live.LiveProgress.to_dict`: its
label as the decoders have settled it, its repetitions that end before any frame it can
still be cut on; provisional, never more than its finished line will say; while the person
holds still, since when, ``still_s``: over a hold the decoders settle nothing), and every line
says which it is first (``"event": "segment"``, ``"repetition"``); without it the lines are
as they were. At
the end the latency from a frame's coming to having its rolling label (drawn on the frame,
not the JSON lines) is printed on stderr (median,
95th percentile, worst): a file's frame played at its own rate comes when it is due, as a
camera would deliver it, however late the watch reads it; a live source's when it is read.
A live source that sends no frame for longer than a quarter second and resumes (before
``--stall``) has the time between left missing ("no frames in the video"), as ``extract``
leaves a gap in a video, and said so on stderr; one whose frames then come at once after a
pause shorter than half a second (a burst: held up on the way) is put on the grid by the wall
clock from there on, its frames a frame interval apart. The frame after such a pause waits for
the next to tell the two apart: one that resumes at its own pace (a drop-out: the camera's
frames of the pause lost) has the pause left missing as a stall's, and out of its rate. One
whose rate rises within its first 4 s, before a segment is given (a stream that starts slow,
bursts or not), is watched again from its start at the rate it rose to.

Ctrl-C or SIGTERM (``kill``, a supervisor's stop) ends the watch as the end of a file does
(the frame in hand is finished, the last segment printed, the ``--out`` video written, exit
0); a second one stops at once, writing nothing. A reader that closes stdout (``| head -1``)
ends it too, the ``--out`` video written up to there. A stream that stalls (no frame for
``--stall`` seconds) or a camera or URL that stops sending is reported in one line, with a
non-zero exit, after the segments in progress are printed; the ``--out`` video of the frames
watched until then is finished and written, as at the end of a file, and the line says so;
so is a file refused on the way as cut short (its segment in progress not printed).
Killed (``kill -9``, power loss), a watch leaves the recording of the ``--out`` video, which
plays up to the last frame drawn, and which the next writer of the video keeps as
``NAME.partial.nut`` (:data:`RESCUE_SUFFIX`).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import errno
import json
import math
import os
import queue
import signal
import statistics
import sys
import threading
import time
from collections.abc import Generator, Iterator
from contextlib import closing, contextmanager
from pathlib import Path
from typing import Any

from cbr.judges import JUDGES
from features.errors import ConfigError, DataError, PosecbrError
from features.fileio import PARTIAL, atomic_path, check_output, path_exists, stdout_gone
from features.interrupts import raise_interrupt, sigterm_held
from features.text import counted, shown
from posecbr.arguments import PathOption, add_k_option, check_mp4_name
from posecbr.recordings import note_low_rate

from .segment import overlay_label


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "watch",
        epilog="example: posecbr watch 0 --db windows.sqlite --show",
        help="label a live stream (webcam, URL, video file) as it comes, counting repetitions",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("source", help="webcam index (0), stream URL or video file")
    p.add_argument("--db", required=True, help="case base file (SQLite) or SQLAlchemy URL")
    p.add_argument("--name", default=None, help="case base name (default: the only one)")
    p.add_argument(
        "--out",
        "--overlay",  # as segment and extract name the video with the stick figure drawn
        dest="out",
        action=PathOption,
        metavar="VIDEO.mp4",
        help="write the annotated frames (--overlay: the same, as segment and extract name it)",
    )
    p.add_argument("--show", action="store_true", help="show the annotated frames in a window")
    p.add_argument(
        "--speed",
        type=float,
        default=1.0,
        metavar="X",
        help="a video file plays at this multiple of its own rate (default 1; 0: as fast as "
        "possible)",
    )
    p.add_argument(
        "--stall",
        type=float,
        default=5.0,
        metavar="SECONDS",
        help="seconds without a frame before giving up (default 5)",
    )
    p.add_argument(
        "--max-frames",
        type=int,
        metavar="N",
        help="stop after this many frames (default: no limit)",
    )
    p.add_argument(
        "--split",
        choices=("segments", "repetitions"),
        default="segments",
        help="repetitions: also judge and explain each repetition as it finishes with the case"
        " base (e.g. one trained with --target correct: correct or incorrect), as classify"
        " --split repetitions judges each, one JSON line each beside the segments' (default:"
        " segments alone)",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="the segments are JSON lines already, one per finished segment (taken, as"
        " segment takes it, and changes nothing)",
    )
    p.add_argument(
        "--progress",
        type=float,
        default=None,
        metavar="SECONDS",
        help="also print, every SECONDS of the stream's time while a segment is open, one"
        ' JSON line {"event": "progress", ...}: its label and the repetitions settled so far'
        " (provisional: never more than its finished line says; still_s while the person"
        " holds still); every line then carries"
        ' "event" (segment, repetition, progress) (default: finished segments alone)',
    )
    add_k_option(
        p,
        1,
        ", in each window, as segment -k N (default 1; at most the case base's own k, which"
        " `posecbr casebase info` shows)",
    )
    p.add_argument(
        "--unknown",
        choices=JUDGES,
        default=JUDGES[0],
        metavar="RULE",
        help=f"what makes a stretch unknown, as in posecbr segment: {', '.join(JUDGES)}"
        " (default spread-margin)",
    )
    p.set_defaults(func=run, out_folder=False)


#: recordings of poses, not videos: segment reads them
RECORDING_SUFFIXES = frozenset({".npz", ".bvh", ".amc"})


def _as_path(source: str) -> str:
    """``file:clip.mp4`` (a ``file:`` URL without ``//``, which FFmpeg opens as the path after
    it) as the path ``clip.mp4``, so that it is checked and played as that file is; any other
    source as it is (``file://`` URLs are played as the network streams they name are)."""
    if source.startswith("file:") and not source.startswith("file://"):
        return source.removeprefix("file:")
    return source


def _is_file(source: str) -> bool:
    return "://" not in source and not source.isdigit()


def _read_files(source: str) -> list[str]:
    """The files on this machine a source reads: a video file, or the one a ``file://`` URL
    names (FFmpeg opens the path after ``file:`` as it is); none for a camera or a stream."""
    if _is_file(source):
        return [source]
    return [source.removeprefix("file:")] if source.startswith("file://") else []


#: the slowest --speed (a hundredth of the frame rate) and the longest --stall (a day): the
#: waits they make must be ones the clock can time
MIN_SPEED = 0.01
MAX_STALL_S = 86_400.0


def _check(args: argparse.Namespace) -> None:
    if not (math.isfinite(args.speed) and (args.speed == 0 or args.speed >= MIN_SPEED)):
        raise ConfigError(
            f"must be 0 (as fast as possible) or a number >= {MIN_SPEED:g}, got {args.speed:g}",
            "--speed",
        )
    if not 0 < args.stall <= MAX_STALL_S:
        raise ConfigError(
            f"must be > 0 seconds and at most {MAX_STALL_S:g} (a day), got {args.stall:g}",
            "--stall",
        )
    if args.k < 1:  # as segment refuses it, before the case base is read
        raise ConfigError(f"must be >= 1, got {args.k}", "-k")
    if args.max_frames is not None and args.max_frames < 1:
        raise ConfigError(f"must be >= 1, got {args.max_frames}", "--max-frames")
    if args.progress is not None and not (math.isfinite(args.progress) and args.progress > 0):
        raise ConfigError(f"must be a number of seconds > 0, got {args.progress:g}", "--progress")
    if args.out is not None:
        check_mp4_name(args.out, args.out_folder, "output video")
        from casebase_store import store_files

        inputs: list[str | Path] = [*_read_files(args.source), *store_files(args.db)]
        check_output(args.out, inputs=inputs, what="output video")
    _check_source(args.source)
    if args.show and not _has_windows():
        raise ConfigError("this OpenCV has no window support: use --out video.mp4", "--show")


def _check_source(source: str) -> None:
    """A source that is a file must be a video file there is, as must the file a ``file://``
    URL names (refused as its path is: FFmpeg would say only that it cannot open it)."""
    named = _read_files(source)
    if named and not _is_file(source) and not path_exists(Path(named[0])):
        raise DataError("no such video file", Path(named[0]))
    if not source:  # an unset shell variable: Path("") is the current folder
        raise DataError("the source is empty: name a webcam index, stream URL or video file")
    if _is_file(source) and Path(source).is_dir():
        raise DataError("is a folder, not a video file", source)
    if _is_file(source) and not path_exists(Path(source)):
        if source.startswith("-") and source[1:].isdigit():  # OpenCV's "any camera", -1
            raise DataError(
                "no such video file, and a camera index is a whole number from 0 (the first"
                " camera)",
                source,
            )
        raise DataError("no such video file", source)
    if _is_file(source) and not Path(source).is_file():  # reading a pipe waits for a writer
        raise DataError("is a pipe, socket or device, not a video file", source)
    if _is_file(source) and Path(source).suffix.lower() in RECORDING_SUFFIXES:
        raise DataError(
            "watch plays videos, cameras and streams; segment this recording with posecbr segment",
            source,
        )
    if _is_file(source) and _is_still(Path(source)):
        # OpenCV plays a still as a one-frame stream: the pose model was loaded and run, and
        # the watch ended "after 1 frame (0.04 s)", as if a video had been cut short
        raise DataError(
            f"{_picture_words(Path(source))}, not a video: watch plays videos, cameras and"
            " streams (posecbr extract reads a picture)",
            source,
        )


def _is_still(path: Path) -> bool:
    """Whether the file at ``path`` is a still picture: named as one (``.jpg``, ``.png``,
    ``.heic``, ...), or one by its first bytes (:func:`features.fileio.picture_words`) and not
    named as a video (a motion-JPEG video begins as a JPEG does)."""
    from features.fileio import file_head, picture_words
    from features.formats import SHOWN_VIDEO_SUFFIXES

    from .extract import IMAGE_SUFFIXES

    suffix = path.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        return True
    return suffix not in SHOWN_VIDEO_SUFFIXES and picture_words(file_head(path)) is not None


def _refuse_served_still(source: str, stall_s: float) -> None:
    """Refuse a still picture an HTTP(S) server gives (a file of a length stated whose first
    bytes are a picture's, :func:`features.fileio.picture_words`, not named as a video), as
    a picture file here is refused (:func:`_check_source`): it was watched as a one-frame
    stream, or, a phone's HEIC or AVIF photo, refused as an "unfinished MP4/MOV". Asked once
    the stream was asked for its rate: a server that answers nothing has stalled by then."""
    from urllib.parse import urlsplit

    from features.fileio import picture_words
    from features.formats import SHOWN_VIDEO_SUFFIXES
    from features.pose_estimation.served import served_file

    if not source.lower().startswith(("http://", "https://")):
        return
    if Path(urlsplit(source).path).suffix.lower() in SHOWN_VIDEO_SUFFIXES:
        return
    served = served_file(source, stall_s)
    words = None if served is None else picture_words(served.start)
    if words is not None:
        raise DataError(
            f"{words}, not a video: watch plays videos, cameras and streams (posecbr extract"
            " reads a picture saved on this machine)",
            source,
        )


def _picture_words(path: Path) -> str:
    """What a still picture (:func:`_is_still`) is, in a refusal's words: by its first bytes
    (:func:`features.fileio.picture_words`: "a PNG or JPEG picture", "an AVIF picture"), else
    "a picture" (one named so that holds something else)."""
    from features.fileio import file_head, picture_words

    return picture_words(file_head(path)) or "a picture"


def _has_windows() -> bool:
    """Whether this OpenCV can open a window: its build names a GUI backend (the headless
    wheel's says NONE)."""
    import cv2

    for line in cv2.getBuildInformation().splitlines():
        if line.strip().startswith("GUI:"):
            return line.split(":", 1)[1].strip().upper() != "NONE"
    return True


HALT_LOOK_S = 0.1
"""How often a wait for the stream's next item looks whether the user has stopped the watch."""

JOIN_S = 2.0
"""How long the end of a watch waits for the reader thread to finish the frame it is reading
once the pose model is idle (:data:`MODEL_WAIT_S`; a stalled network read may never
return)."""

MODEL_WAIT_S = 60.0
"""How long the end of a watch waits for the pose model to finish the frame the reader
thread gave it (tens of milliseconds on an idle machine; seconds where the process gets
little of a loaded machine's time): a thread left inside onnxruntime as Python shuts down
aborts the process ("terminate called without an active exception", exit 134). Waited for
:data:`JOIN_S` alone, a watch stopped by SIGTERM on a machine so loaded that a frame took
longer aborted so after its last line."""


def due_s(index: int, video_time_s: float, fps: float, speed: float) -> float:
    """When a file's frame ``index`` is due, in seconds after its first frame, played at
    ``speed`` times its own rate: its presentation time (``video_time_s``, from the first
    frame's: a variable frame rate plays as it was filmed) over ``speed``, or
    ``index / fps`` over ``speed`` when it has none to trust (NaN: :class:`FrameClock`)."""
    t = video_time_s if math.isfinite(video_time_s) else index / fps
    return t / speed


class Pacer:
    """Holds each frame of a file played at ``speed`` times its rate until it is due
    (:func:`due_s`, counted from the first frame; a frame without a time, among frames with
    them, is due a frame interval after the last one with one): ``stream_poses``'s
    ``pace``. :attr:`until` is when the frame in hand is due (``time.perf_counter()``):
    until then the stream is not stalled, however long the wait. :attr:`stop` set ends a
    wait at once."""

    def __init__(self, fps: float, speed: float) -> None:
        self.fps, self.speed = fps, speed
        self.stop = threading.Event()
        self.started: float | None = None
        self.until = 0.0
        self.timed: tuple[int, float] | None = None  # the last frame with a time, and it
        # (index, until) of the latest frames paced, for :meth:`due_at`: more than the
        # reader's queue and the frame in hand hold; paced in the reader's thread, read in
        # the watch's
        self.dues: collections.deque[tuple[int, float]] = collections.deque(maxlen=64)
        self._dues_lock = threading.Lock()

    def __call__(self, index: int, video_time_s: float) -> bool:
        now = time.perf_counter()
        if self.started is None:
            self.started = now
        t = video_time_s
        if math.isfinite(t):
            self.timed = (index, t)
        elif self.timed is not None:  # no time of its own: a frame interval after the last
            t = self.timed[1] + (index - self.timed[0]) / self.fps
        self.until = self.started + due_s(index, t, self.fps, self.speed)
        with self._dues_lock:
            self.dues.append((index, self.until))
        return not self.stop.wait(max(0.0, self.until - now))

    def due_at(self, index: int) -> float | None:
        """When frame ``index`` was due (``time.perf_counter()``: when a camera would have
        delivered it), None when it is not among the latest frames paced."""
        with self._dues_lock:
            return next((until for i, until in reversed(self.dues) if i == index), None)


class Alive:
    """When the stream last showed it was still at work between frames (a served file read
    again at its end: ``stream_poses``'s ``alive``), ``time.perf_counter()``; calling it
    stamps now. Until ``--stall`` seconds after it, the stream is not stalled."""

    def __init__(self) -> None:
        self.at = 0.0

    def __call__(self) -> None:
        self.at = time.perf_counter()


class _Reader:
    """A stream's frames read in a thread into a small queue of (kind, item): ("frame", f),
    then ("end", None) or ("error", exc). :meth:`close` stops it (and the ``pacer`` holding
    the stream back, if any), closes ``model``, the pose estimator the stream runs
    (:meth:`features.pose_estimation.PoseEstimator.close`: the frame in hand finished, waited
    for up to :data:`MODEL_WAIT_S`; no frame begun after), and waits up to :data:`JOIN_S`
    for the thread. ``halt`` set (the user stopped the watch) ends a wait for the next item:
    the stream ends there."""

    def __init__(
        self,
        frames: Iterator[Any],
        pacer: Pacer | None = None,
        alive: Alive | None = None,
        halt: threading.Event | None = None,
        model: Any = None,
    ) -> None:
        self.frames, self.pacer, self.alive, self.model = frames, pacer, alive, model
        self.halt = halt or threading.Event()
        self.box: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=8)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._read, name="posecbr-watch-reader", daemon=True)
        self.thread.start()

    def _hand(self, kind: str, item: Any) -> bool:
        """Pass an item to the consumer; False once it has stopped listening."""
        while not self.stop.is_set():
            try:
                self.box.put((kind, item), timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _read(self) -> None:
        try:
            for f in self.frames:
                if not self._hand("frame", f):
                    return
            self._hand("end", None)
        except BaseException as exc:  # delivered to the main thread
            self._hand("error", exc)
        finally:  # the capture is released by the thread that reads it
            close = getattr(self.frames, "close", None)
            if close is not None:
                close()

    def get(self, stall_s: float, where: str) -> tuple[str, Any]:
        """The next item; DataError naming ``where`` when none comes for ``stall_s`` seconds
        beyond the time the frame in hand is due (a file's frames held back by the pacer are
        not a stall, however long the gap between two of them) and the stream's last sign of
        work (:class:`Alive`). A frame already waiting is taken however late this thread
        looks (a busy machine may wake it after the stall time: the stream did not stall).
        ``halt`` set ends the wait as the stream's end: a camera or network stream that sent
        nothing when the user stopped the watch (Ctrl-C, SIGTERM) was waited on to the stall
        time, then said stalled, exit 1, its video not written."""
        asked = time.perf_counter()
        while True:
            if self.halt.is_set():
                return "end", None
            quiet_since = max(
                asked,
                self.pacer.until if self.pacer is not None else 0.0,
                self.alive.at if self.alive is not None else 0.0,
            )
            left = quiet_since + stall_s - time.perf_counter()
            if left <= 0:
                try:
                    return self.box.get_nowait()
                except queue.Empty:
                    raise StreamLost(
                        f"the stream stalled: no frame for {stall_s:g} s", where
                    ) from None
            try:
                return self.box.get(timeout=min(left, HALT_LOOK_S))
            except queue.Empty:
                continue

    def close(self) -> None:
        self.stop.set()
        if self.pacer is not None:
            self.pacer.stop.set()
        if self.model is not None:
            self.model.close(MODEL_WAIT_S)
        self.thread.join(JOIN_S)


def frames_in_background(
    frames: Iterator[Any],
    stall_s: float,
    pacer: Pacer | None = None,
    where: str = "stream",
    alive: Alive | None = None,
    halt: threading.Event | None = None,
    model: Any = None,
) -> Generator[Any, None, None]:
    """The stream's frames, read in a thread (:class:`_Reader`); ``pacer``: the one that
    holds ``frames`` back (a file played at its own rate, as a camera delivers), stopped
    with the reader. Raises DataError naming ``where`` (the source) when no frame arrives
    for ``stall_s`` seconds (beyond the frame's due time and ``alive``'s stamp), and
    :class:`SourceRefused` for a DataError of ``frames`` (a file cut short); ends when
    ``halt`` is set (the user stopped it: :func:`stop_on_interrupt`'s ``also``). Closed (or
    ended), it stops the reader and waits for it, and for ``model``, the pose estimator
    ``frames`` runs (closed: :class:`_Reader`): a thread left inside OpenCV or onnxruntime
    while Python shuts down aborts the process (exit 134)."""
    reader = _Reader(frames, pacer, alive, halt, model)
    try:
        while True:
            kind, item = reader.get(stall_s, where)
            if kind == "end":
                return
            if kind == "error":
                if isinstance(item, DataError) and not isinstance(item, StreamLost):
                    raise SourceRefused(item.message, item.source) from item
                raise item
            yield item
    finally:
        reader.close()


class StreamLost(DataError):
    """A stream that stalled past ``--stall``, or a camera or live stream that stopped
    sending: what was watched of it is given (:meth:`Watcher.watch`) before this is said."""


class SourceRefused(DataError):
    """The stream's source refused on the way, after frames came (a file, here or served,
    cut short or holding fewer frames than its container states): the ``--out`` video of the
    frames watched is finished and kept, as for a stream lost (:func:`_watched`); the segment
    in progress is not given (the file is refused, as ``segment`` refuses it whole)."""


class Stop(threading.Event):
    """Set when the user stops a watch; ``signum``: the signal that stopped it."""

    def __init__(self) -> None:
        super().__init__()
        self.signum: int = signal.SIGINT

    def stop(self, signum: int) -> None:
        self.signum = signum
        self.set()


@contextmanager
def stop_on_interrupt(also: threading.Event | None = None) -> Iterator[Stop]:
    """Ctrl-C (SIGINT) or SIGTERM (the polite stop a supervisor sends: systemd, ``docker
    stop``, ``kill PID``, a program's ``Popen.terminate()``) sets the event instead of
    raising: the watch ends after the frame in hand, as at the end of a file; a second one
    raises KeyboardInterrupt at once. ``also`` is set with it (a :class:`Pacer`'s stop: a
    file held back until a frame's time, however far off, ends there). Outside the main
    thread (where no signal handler can be set) the event is never set."""
    stopped = Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stopped
        return

    def interrupted(signum: int, _frame: Any) -> None:
        if stopped.is_set():
            raise_interrupt(signum)  # a second SIGTERM is said as one (exit 143)
        stopped.stop(signum)
        if also is not None:
            also.set()

    # set and put back with SIGTERM held: one that came between setting (or putting back)
    # the two handlers raised KeyboardInterrupt with SIGINT's still the watch's, for good
    with sigterm_held(then=interrupted) as sigterm_before:
        sigint_before = signal.signal(signal.SIGINT, interrupted)
    try:
        yield stopped
    finally:
        # SIGTERM's handler is put back as the hold ends, even after a Ctrl-C in the block
        with sigterm_held(then=sigterm_before):
            signal.signal(signal.SIGINT, signal.SIG_DFL if sigint_before is None else sigint_before)


def run(args: argparse.Namespace) -> int:
    from features.pose_estimation import (
        PoseEstimator,
        open_video,
        served_file_rate,
        stream_poses,
    )
    from features.pose_estimation.overlay import check_encoded, check_mp4_size, retime_mp4

    from .segment import check_k_option, judge_named, load_case_base, note_not_windows

    args.source = _as_path(args.source)
    _check(args)
    stored = load_case_base(args.db, args.name)
    clf = stored.classifier
    check_k_option(clf, args.k)  # before the pose model is loaded or the stream opened
    judge = judge_named(clf, args.unknown, args.db)
    source: Any = int(args.source) if args.source.isdigit() else args.source
    if _is_file(args.source):
        cap, info = open_video(args.source)
        cap.release()
        if args.out is not None:
            check_mp4_size(info.width, info.height, args.out, "video")
        fps: float | None = info.fps
    else:  # a file served over the network is played as a file is
        fps = None if isinstance(source, int) else served_file_rate(source, args.stall)
        _refuse_served_still(args.source, args.stall)  # its server answers: no wait added
    if fps is not None:  # as segment and reps say it of the same video
        note_low_rate(args.source, fps, True)  # its poses the pose model's
    is_file = fps is not None
    pacer = Pacer(fps, args.speed) if fps and args.speed > 0 else None
    alive = Alive()  # a served file read again at its end for a cut: no stall
    # the pose model loaded here, before the stall clock runs: loading it (seconds on a slow
    # or busy machine) is no stall of the stream
    estimator = PoseEstimator(smoothing=True)
    # the source opened here, before the warm-up: one that cannot be is said without its wait
    poses = stream_poses(
        source,
        estimator=estimator,
        max_frames=args.max_frames,
        fps=fps,
        timeout_s=args.stall,
        pace=pacer,
        alive=alive,
    )
    halt = pacer.stop if pacer is not None else threading.Event()  # set by Ctrl-C, SIGTERM
    frames = frames_in_background(poses, args.stall, pacer, args.source, alive, halt, estimator)
    each = stored if args.split == "repetitions" else None  # judges each repetition
    watcher = Watcher(clf, judge, args, fps, each)
    watcher.pacer = pacer
    try:
        with (
            _video_output(args.out) as video,
            closing(frames),
            stop_on_interrupt(halt) as stop,
        ):
            watcher.video = video
            watcher.warm_up()
            lost = _watched(watcher, frames, is_file, stop)
            if video is not None and watcher.writer is None:
                watcher.close(stop)  # nothing watched: says so, as without --out
                raise _NoFrameDrawn
            if video is not None:
                watcher.writer.to_mp4(video)  # the frames encoded once, copied into the MP4
                retime_mp4(video, float(watcher.fps or 30.0))  # 30000/1001 kept, not 29.97
                check_encoded(video, watcher.drawn, args.out)
            if lost is None:
                watcher.close(stop)
        if lost is not None:  # the video finished and in place; the watch did not end as asked
            lost.add(
                f"the video of the {counted(watcher.drawn, 'frame')} watched was written to"
                f" {shown(args.out)}"
            )
            raise lost
        if args.out is not None:  # on stderr, as every "written to": stdout holds the segments
            print(f"video written to {shown(args.out)}", file=sys.stderr)
        # at the end of a watch that went well: a stream refused on the way (cut short,
        # stalled) is one line
        note_not_windows(stored, args.db, "watch", args.split == "repetitions")
    except _NoFrameDrawn:
        pass  # stopped before the first frame: no video, not an empty one
    finally:  # the video in place (or not to be written): its copy for a kill is not needed
        watcher.drop_rescue()
    return 0


def _watched(
    watcher: Watcher, frames: Iterator[Any], is_file: bool, stop: threading.Event
) -> DataError | None:
    """:meth:`Watcher.watch` the stream; a stream lost, or refused by its source, after
    frames were drawn is returned, not raised: their video is finished and written before it
    is said. Lost before (no video drawn, or none asked for), it is raised."""
    try:
        watcher.watch(frames, is_file, stop)
    except (StreamLost, SourceRefused) as exc:
        if watcher.writer is None:
            raise
        return exc
    return None


RESCUE_SUFFIX = f"{PARTIAL}.nut"
"""The ending of the ``--out`` video's recording (:meth:`Watcher._write`), its rescue copy
when the watch is killed: FFmpeg's
NUT container, which needs no index at its end (measured, frames killed after 300: an MP4
opens not at all, Matroska, AVI and ASF with no frame count and no seeking; NUT and MPEG-TS
give theirs and seek, and OpenCV writes MPEG-TS only after a warning on stderr).
:data:`features.fileio.PARTIAL` in it: a killed watch's copy is kept, not removed."""


class _NoFrameDrawn(Exception):
    """Leaves the ``--out`` video unwritten (the user stopped before the first frame)."""


@contextmanager
def _video_output(out: Path | None) -> Iterator[Path | None]:
    """A temporary file for the ``--out`` video, renamed to ``out`` when the watch ends well
    or its stream is lost after frames were drawn (:func:`run`: their video is finished, not
    half-written) (features.fileio; ending in .mp4: OpenCV picks the container by the file
    name)."""
    if out is None:
        yield None
        return
    with atomic_path(out, make_parents=False, suffix=".mp4") as tmp:
        yield tmp


class Watcher:
    """Feeds frames to the live segmenter, draws, writes, prints and times them."""

    def __init__(
        self,
        clf: Any,
        judge: Any,
        args: argparse.Namespace,
        fps: float | None,
        stored: Any = None,
    ) -> None:
        self.clf, self.judge, self.args = clf, judge, args
        self.stored = stored  # the case base that judges each repetition (--split repetitions)
        self.fps = fps
        self.live: Any = None
        self.verdicts: Any = None  # cbr.live_verdicts.RepetitionVerdicts, --split repetitions
        self._grid: Any = None  # Regrid, made with the segmenter
        self.writer: Any = None  # features.pose_estimation.recording.Recording
        self.video: Path | None = None  # the MP4 the drawn frames go to (a temporary file)
        self.rescue_path: Path | None = None  # their recording, which a kill leaves playable
        self.drawn = 0  # frames written to it
        self.emitted = 0  # segments printed
        # --progress SECONDS (None: off): a line on the segment in progress every that many
        # seconds of the stream, the next at the stream's time next_progress * SECONDS
        self.every: float | None = getattr(args, "progress", None)  # (a Namespace made in
        # Python, without the option: off)
        self.next_progress = 1
        self.progressed = 0  # progress lines printed
        self.seen = False  # a segment printed saw the person (not nobody in view throughout)
        self.hips_out = 0  # frames in a row showing the shoulders, not the hips (:meth:`_hips`)
        self.said_hips_out = False  # the note that the hips are out of view is said once
        self.no_hips = False  # a frame showed the shoulders without the hips
        self.hip_in_run = False  # a frame of that run showed one hip (no arms alone)
        self.is_file = False  # a video file (here or served), not a camera or live stream
        self.stdout_gone = False  # the reader of the printed segments has gone: stop
        self.latency = Latencies()  # frame to label, tallied: bounded on any stream
        self.pacer: Pacer | None = None  # a file's, played at its own rate: when frames are due
        self.colours: dict[str, Any] | None = None  # each activity's, once drawn
        self.n = 0
        self.read = 0  # frames the source gave (before the grid of a variable rate's)
        self.whole = False  # the last of them was the file's last (at --max-frames: read whole)
        # a live source's frames since its first, while its grid may be re-made at a rate
        # that rose (:meth:`_remake`); None once it may not
        self.kept: list[Any] | None = None
        self.images: KeptImages | None = None  # their images, with --out
        # those images once taken again, until the grid holds none of the kept frames (the
        # frame on screen through a stall after them, or held after a pause: :meth:`_take`)
        self.spent: KeptImages | None = None
        self.padding_said = False  # the note that the --out video's odd side is padded
        self.replaying = False  # the kept frames are taken again, at the rate they rose to
        self.held_since: list[float] = []  # when each frame the grid holds (a pause's) came
        self.started = time.perf_counter()

    def warm_up(self) -> None:
        """Run the segmenter's work once on a made-up figure before the stream starts
        (:func:`cbr.live.warm_up`; it evaluates the fluents drawn too): the first run loads
        compiled kernels (about 0.4 s), which would otherwise hold up the first frames and
        those queued behind them."""
        from cbr.live import warm_up

        try:
            warm_up(self.clf, self.judge, k=self.args.k)
        except DataError:  # a figure this case base cannot describe: the stream warms it
            pass
        self.started = time.perf_counter()  # frames per second: of the stream alone

    def watch(self, frames: Iterator[Any], is_file: bool, stop: threading.Event) -> None:
        """:meth:`follow` until the stream ends or the user stops it (``stop``: Ctrl-C); the
        video writer is released either way. A stream lost (:class:`StreamLost`) has the
        segments in progress printed first, as at the end of a file: its frames were
        watched (before, an activity going on when the camera was lost was never said), and
        the watch's summary on stderr (:meth:`_summary`: the latency, each repetition's
        verdict; before, a stream lost said neither)."""
        self.is_file = is_file
        try:
            self.follow(frames, is_file, stop)
        except StreamLost:
            self._flush()
            self._finish()
            self._summary()
            raise
        finally:
            if self.writer is not None:  # kept until the video is in place (:meth:`drop_rescue`)
                self.writer.release()

    def follow(self, frames: Iterator[Any], is_file: bool, stop: threading.Event) -> None:
        waiting: list[Any] = []  # a live source's first second: to measure its frame rate
        for frame in frames:
            if stop.is_set() or self.stdout_gone:
                break  # the user stopped watching: finish what was seen
            self.read += 1
            self.whole = frame.last
            if self.live is None:
                if self.fps is None:
                    waiting.append(frame)
                    self.fps = _frame_rate([f.time_s for f in waiting])
                    if self.fps is None:
                        continue
                self._start(waiting)
                waiting.clear()  # taken (kept, if at all, by :meth:`_take`): not held any longer
            self._take(frame)
        self._flush()
        if self.stdout_gone:
            return
        if self.n == 0 and not stop.is_set():
            raise DataError("the stream gave no frame", self.args.source)
        if not is_file and not self.limited and not stop.is_set():
            raise StreamLost(
                f"the stream ended after {counted(self.n, 'frame')} (camera or connection lost?)",
                self.args.source,
            )

    def _start(self, waiting: list[Any]) -> None:
        """Make the segmenter and the grid at :attr:`fps` and take the frames ``waiting``
        before the one in hand (a live source's first second, its rate measured over it;
        none for a file): a live source's kept (:attr:`kept`) to be watched again should
        its rate soon rise (:meth:`_remake`)."""
        from cbr.live import LiveSegmenter

        fps = float(self.fps or 0.0)
        self.live = LiveSegmenter(self.clf, fps, self.judge, self.args.source, k=self.args.k)
        self._judge_repetitions()
        self._grid = Regrid(fps, self.args.source)
        if waiting:
            self.kept, self._grid.remakable = [], True
            if self.args.out is not None:
                try:
                    self.images = KeptImages(self.args.out.parent)
                except OSError as exc:
                    self._not_kept(exc)
        for early in waiting[:-1]:
            self._take(early)

    @property
    def limited(self) -> bool:
        """The user's ``--max-frames`` stopped the watch: the source gave that many frames
        and may have had more (a file of exactly that many ended on its own)."""
        limit = self.args.max_frames
        return limit is not None and self.read >= limit and not self.whole

    def _ended(self) -> str:
        """What stopped the stream: the user's ``--max-frames``, or its end."""
        if self.limited:
            return f"--max-frames {self.args.max_frames} stopped the watch"
        return "the stream ended"

    def _take(self, frame: Any) -> None:
        kept = self.kept
        if kept is not None and not self.replaying:
            if (
                self.emitted
                or self.progressed
                or (kept and frame.time_s - kept[0].time_s > REMAKE_S)
            ):
                self._stop_keeping()  # too late: followed as it is
            else:
                try:
                    kept.append(_Kept.of(frame, self.images))
                except OSError as exc:
                    self._not_kept(exc)
        taken = self._grid.take(frame)
        if self.kept is not None and self._grid.rose is not None:
            self._remake(self._grid.rose)
            return
        self._push(taken)
        if self.spent is not None and not any(
            isinstance(held, _Kept) for held in (self._grid.prev, *self._grid.held)
        ):
            self.spent.close()  # no kept frame left to draw
            self.spent = None
        since = self._since(frame)
        if since == since and not self.replaying:  # not NaN: the source said when it read it
            now = time.perf_counter()
            # the grid holds the latest of the frames held before and this one (none, or
            # from one after a pause on): those before them given now
            came = [*self.held_since, since]
            given = max(0, len(came) - len(self._grid.held))
            for since_given in came[:given]:
                self.latency.add(now - since_given)
            self.held_since = came[given:]

    def _push(self, taken: list[tuple[Any, Any, Any]]) -> None:
        """Push the grid times the grid just gave (:meth:`Regrid.take`) to the segmenter,
        printing the segments they finish and drawing each."""
        grid = zip(taken, self._grid.absent, self._grid.images, strict=True)
        for (world, visibility, shown_frame), absent, image in grid:
            finished = self.live.push(world, visibility, absent, image)
            if self.live.jumped and not self.replaying:  # said when it was first taken
                self._note_jump()
            self._hips(world)
            self.n += 1
            for segment in finished:
                self._emit(segment)
            if self.verdicts is not None:
                self._verdict_lines(self.verdicts.update())
            self._progress()
            if self.args.out is not None:  # each verdict drawn from the frame it was due at
                self._verdicts_judged()
            self._draw(shown_frame, absent)

    def _flush(self) -> None:
        """The stream has ended: push the grid times of the frame the grid held for the next
        (:meth:`Regrid.flush`), if any, its latency counted. A rise of the rate taken while
        they are given (:attr:`Regrid.rose`, the frames after it not given) has the stream
        watched again at it (:meth:`_remake`), as when it is taken before the end. Before,
        the frames held after the rise were dropped and the stream followed at its first
        rate."""
        if self._grid is None or not self._grid.held or self.stdout_gone:
            return
        taken = self._grid.flush()
        if self.kept is not None and self._grid.rose is not None:
            # the rate rose at a frame held: watched again at it, as had another frame come
            self._remake(self._grid.rose, ended=True)
            taken = self._grid.flush()  # the new grid's held (not re-made again: not remakable)
        self._push(taken)
        now = time.perf_counter()
        for since in self.held_since:
            self.latency.add(now - since)
        self.held_since = []

    def _stop_keeping(self) -> None:
        """The stream's rate is followed as it is from here on: no frame kept any longer."""
        self.kept, self._grid.remakable = None, False
        if self.images is not None:
            self.images.close()
            self.images = None

    def _not_kept(self, exc: OSError) -> None:
        """The kept frames' images cannot be written (:class:`KeptImages`: a full disk): said,
        and the stream followed at its first rate, as after :data:`REMAKE_S`."""
        print(
            f"note: {shown(self.args.out)}: the first frames cannot be kept to be drawn again"
            f" ({exc.strerror or exc}): a rise of the stream's frame rate is followed at its"
            " first rate",
            file=sys.stderr,
        )
        self._stop_keeping()

    def _remake(self, fps: float, ended: bool = False) -> None:
        """Watch a live source again from its first frame at ``fps``, the rate it rose to
        within :data:`REMAKE_S` of it, before any segment was given (:attr:`kept`): a new
        segmenter and grid (:class:`Regrid` on the wall clock from the first frame, the
        frames before the rise resampled to ``fps``), the frames kept taken again (the
        ``--out`` video drawn again at ``fps``; a ``--show`` window not shown them twice, nor
        a note said twice), said once on stderr; ``ended``: the rise was taken among the
        frames held when the stream ended (:meth:`_flush`, which counts their latency), every
        kept frame taken again. A stream that starts slow (a camera's auto
        exposure settling, a network stream's start) was watched at its first second's rate
        for good: at 15 fps then 30, half its frames resampled away."""
        from cbr.live import LiveSegmenter

        kept, before = self.kept or [], float(self.fps or fps)
        self.kept = None
        images, self.images = self.images, None
        print(
            f"note: {self.args.source}: the frame rate rose from {before:.3g} to {fps:.3g} fps"
            f" at {kept[-1].time_s - kept[0].time_s:.1f} s, before any segment was given:"
            f" watched again from its start at {fps:.3g} fps (the frames before the rise"
            " resampled to it by the clock)",
            file=sys.stderr,
        )
        self.fps = fps
        self.live = LiveSegmenter(self.clf, fps, self.judge, self.args.source, k=self.args.k)
        self._judge_repetitions()
        self._grid = Regrid(fps, self.args.source, interval=1.0 / before)
        self.n = 0
        self.next_progress = 1  # none printed yet (:meth:`_take`): due from the start again
        if self.writer is not None:  # its frames drawn again, at the new rate
            self.writer.release()
            if self.rescue_path is not None:
                self.rescue_path.unlink(missing_ok=True)
            self.writer, self.rescue_path, self.drawn = None, None, 0
        grid, grid.quiet = self._grid, True  # its notes said as the frames first came
        self.spent = images  # closed once the grid holds no kept frame (:meth:`_take`)
        in_hand = [] if ended else kept[-1:]
        try:
            self.replaying = True
            try:
                for frame in kept[: len(kept) - len(in_hand)]:
                    self._take(frame)
            finally:
                self.replaying = False
            for frame in in_hand:
                self._take(frame)  # the frame in hand: its latency counted
        finally:
            grid.quiet = False

    def _since(self, frame: Any) -> float:
        """When ``frame`` came, from which its latency runs: a file's frame played at its
        own rate was due at its time (:meth:`Pacer.due_at`), as a camera delivers it, though
        it was read later when the watch fell behind (the frames before it still in the
        queue: from its read, 250 frames of a 30-fps video watched at 12.5 frames/s said a
        median of 71 ms, each label coming up to 11 s after its frame); else when it was read
        (NaN: not said)."""
        due = self.pacer.due_at(frame.index) if self.pacer is not None else None
        read_at = float(frame.read_at)
        return read_at if due is None else min(due, read_at)

    def _note_jump(self) -> None:
        """Say on stderr that the pose jumped to another person at the frame just pushed
        (the segmenter saw it: :attr:`cbr.live.LiveSegmenter.jumped`, by
        :func:`features.pose_estimation.video.person_jumps`: the person followed left the
        picture while another was in view), as ``extract`` says it, frames counted as
        ``extract`` counts them (on the grid of a variable frame rate's); repetitions are
        counted apart on either side of it, as ``segment`` counts them."""
        from features.pose_estimation.video import jump_words

        words = jump_words(self.args.source, [self.n], self.live.fps)
        print(f"note: {shown(words)}", file=sys.stderr)

    def _hips(self, world: Any) -> None:
        """Say once, on stderr, that the hips are out of view when the shoulders have been seen
        without them for :data:`cbr.segmentation.MIN_SEGMENT_S` (a camera close up, the
        patient seated): neither hip seen, the labels stand on the arms alone while they are
        out (:mod:`cbr.live` judges a window without them on its arms, as ``segment`` judges
        a recording shown from the shoulders up; before, no activity was labelled and such a
        stretch was given as nobody in view); one hip seen, no activity is labelled without
        the torso and such a stretch is given as nobody in view, which alone told the user
        nothing of why."""
        import numpy as np

        from cbr.segmentation import MIN_SEGMENT_S
        from features.skeleton import JOINT_INDEX

        joints = ("left_shoulder", "right_shoulder", "left_hip", "right_hip")
        seen = np.isfinite(world[[JOINT_INDEX[j] for j in joints]]).all(axis=1)
        self.hips_out = self.hips_out + 1 if seen[:2].all() and not seen[2:].all() else 0
        self.hip_in_run = self.hips_out > 0 and (self.hip_in_run or bool(seen[2:].any()))
        self.no_hips = self.no_hips or self.hips_out > 0
        if self.said_hips_out or self.hips_out < MIN_SEGMENT_S * self.live.fps:
            return
        self.said_hips_out = True
        start_s = (self.n + 1 - self.hips_out) / self.live.fps
        said = (
            "no activity is labelled without the torso, and a stretch without it is given as"
            " nobody in view"
            if self.hip_in_run
            else "labelled from the arms alone while they are"
        )
        print(
            f"note: {shown(self.args.source)}: the hips are out of view from {start_s:.2f} s"
            f" (the shoulders are seen): {said}",
            file=sys.stderr,
        )

    def _judge_repetitions(self) -> None:
        """Given the case base to judge each repetition with (``--split repetitions``:
        :attr:`stored`), judge the repetitions of the segmenter just made
        (:class:`cbr.live_verdicts.RepetitionVerdicts`); a stream watched again from its
        start (:meth:`_remake`) keeps the verdicts given so far, counting on from the end of
        the last one judged."""
        if self.stored is None:
            return
        from cbr.live_verdicts import RepetitionVerdicts

        self.verdicts = RepetitionVerdicts(self.stored, self.live, self.verdicts, background=True)

    def _verdict_lines(self, verdicts: list[Any]) -> None:
        """Print the lines of ``verdicts`` (:meth:`cbr.live_verdicts.RepetitionVerdicts.update`'s
        or ``ready``'s)."""
        for verdict in verdicts:
            self._print_line(verdict.to_dict(), "repetition")

    def _verdicts_judged(self) -> None:
        """Wait for the verdicts still being judged (on their own thread: the frames go on
        meanwhile) and print them: before any other line, so that the lines come in the order
        they came when each verdict was judged in the frame loop, and before a frame of the
        ``--out`` video is drawn (the video is the same as it was then)."""
        if self.verdicts is not None and self.verdicts.asked:
            self._verdict_lines(self.verdicts.ready(wait=True))

    def _finish(self) -> None:
        """The stream has ended: the segments not yet given, and (``--split repetitions``)
        the verdicts of the repetitions not yet judged, the last counted among them."""
        finished = self.live.finish() if self.live is not None else []
        for segment in finished:
            self._emit(segment)
        if self.verdicts is not None:
            self._verdict_lines(self.verdicts.update(ended=True))

    def _emit(self, segment: Any) -> None:
        from cbr.segmentation import NO_FRAMES, NOBODY

        self.emitted += 1
        self.seen = self.seen or segment.explanation not in (NOBODY, NO_FRAMES)
        self._print_line(segment.to_dict(self.fps), "segment")

    def _progress(self) -> None:
        """``--progress SECONDS`` (:attr:`every`): at the first frame pushed at or after each
        multiple of SECONDS of the stream's time, the segment in progress as it stands
        (:meth:`cbr.live.LiveSegmenter.progress`: its label as the decoders have settled it,
        those of the repetitions drawn that end before any frame it can still be cut on),
        one line; none while no segment's label is settled yet
        (the stream's first seconds). Not while the kept frames are watched again
        (:meth:`_remake`: none was printed before, :meth:`_take`)."""
        if self.every is None or self.replaying:
            return
        reached = math.floor(self.live.n / (self.every * self.live.fps) + 1e-9)
        if reached < self.next_progress:
            return
        self.next_progress = reached + 1
        now = self.live.progress()
        if now is not None:
            self.progressed += 1
            self._print_line(now.to_dict(self.live.fps))

    def _print_line(self, line: dict[str, Any], event: str | None = None) -> None:
        """One JSON line on stdout, flushed (a segment's, a repetition's or a progress line);
        with ``--progress`` each says which it is first, ``"event": event`` (without it, the
        lines are as they were: every reader took each as a finished segment's)."""
        if event != "repetition":  # the verdicts asked for before it come first
            self._verdicts_judged()
        if self.stdout_gone:
            return
        if self.every is not None and event is not None:
            line = {"event": event, **line}
        try:
            print(json.dumps(line), flush=True)
        except BrokenPipeError:  # the program reading the lines has closed them or exited
            stdout_gone()
            self.stdout_gone = True
            print(
                f"note: {shown(self.args.source)}: standard output was closed by its reader:"
                " the watch ends here",
                file=sys.stderr,
            )

    def _draw(self, frame: Any, absent: bool = False) -> None:
        """Draw ``frame`` (the one on screen at the grid time just pushed) with the label;
        ``absent``: that time lies in a gap of the video (no frame of its own: the frame
        before the gap stays on screen), which the label says, as ``segment`` calls such a
        stretch, not "nobody in view"."""
        if self.args.out is None and (self.replaying or not self.args.show):
            return
        import cv2
        import numpy as np

        from cbr.segmentation import NO_FRAMES, NOBODY
        from features.pose_estimation.overlay import draw_pose

        bgr = cv2.cvtColor(frame.rgb, cv2.COLOR_RGB2BGR)
        current = self.live.current()
        label = self.live.label or ("unknown" if current is not None else "...")
        key = self.live.label  # the activity, coloured as segment --plot colours it
        if absent:
            label, key = NO_FRAMES, None
        elif self.live.nobody_in_view:  # not unknown: no movement to be like anything
            label, key = self.live.nobody_reason, None  # the gap just passed, or nobody in view
        words = [
            overlay_label(label, key, self._colours()),
            f"repetitions: {current.repetitions if current else 0}",
        ]
        last = None if self.verdicts is None else self.verdicts.last
        if last is not None and last.judged.explanation is not None:
            words.append(
                f"repetition {last.number}: {last.judged.explanation.text.splitlines()[0]}"
            )
        if not absent and self.live.nobody_in_view:
            if words[0] == NOBODY and np.isnan(frame.pose.image[:, :2]).all():
                words = words[1:]  # draw_pose says "no person"
        draw_pose(bgr, frame.pose.image, words + self._fluents())
        if self.args.out is not None:
            self._write(bgr)
        if self.args.show and not self.replaying:
            self._show(bgr)

    def _colours(self) -> dict[str, Any]:
        """Each activity's colour, by its place among the case base's (as ``segment --plot``
        and ``segment --overlay`` colour it)."""
        if self.colours is None:
            from features.timeline import band_colours

            self.colours = band_colours([], [str(c) for c in self.clf.classes_])
        return self.colours

    def _fluents(self, top: int = 3) -> list[str]:
        """The fluent states that hold in the latest frame (most confident first)."""
        import numpy as np

        from features.fluents import evaluate
        from features.timeline import background

        recent = self.live.recent(10)
        result = evaluate(recent)
        conf = np.nan_to_num(result.confidence[-1], nan=0.0)
        conf[background(result)] = 0.0
        best = np.argsort(-conf, kind="stable")[:top]
        return [result.words[i] for i in best if conf[i] >= 0.8]

    def _write(self, bgr: Any) -> None:
        """Write a drawn frame to the ``--out`` video's recording (:data:`RESCUE_SUFFIX`): a
        hidden temporary beside ``--out`` in a container that needs no index at its end, each
        frame's bytes in it when this returns
        (:class:`features.pose_estimation.recording.Recording`). The MP4's index (its
        ``moov`` box) is written when its writer is released, so a watch killed (``kill -9``,
        power loss) left an MP4 temporary no player opens, and the next writer removed it;
        the recording plays up to the last frame written, and the next writer of ``--out``
        keeps it under a visible name (:func:`features.fileio.remove_stale_temporaries`). The
        MP4 is made of its encoded frames when the watch ends (:func:`run`), not encoded
        again (each frame was encoded twice, to the MP4 and to a copy: 1.2 ms more CPU a
        640x480 frame); the recording is removed once the video is in place, or is not to be
        written."""
        from features.pose_estimation.overlay import pad_even

        if self.writer is None:
            from features.fileio import temporary_file, write_error
            from features.pose_estimation.overlay import check_mp4_size, even_size, padding_words
            from features.pose_estimation.recording import Recording

            h, w = bgr.shape[:2]
            check_mp4_size(w, h, self.args.out, "video")
            try:
                self.rescue_path = temporary_file(self.args.out, RESCUE_SUFFIX)
            except OSError as exc:
                raise DataError(write_error(exc), self.args.out) from None
            size = even_size(w, h)  # an odd side padded, not cut by the writer
            fps = float(self.fps or 30.0)
            self.writer = Recording(self.rescue_path, fps, size, str(self.args.out))
            if padding_words(w, h) and not self.padding_said:  # once: not again at a re-make
                print(f"note: {shown(self.args.out)}: {padding_words(w, h)}", file=sys.stderr)
                self.padding_said = True
        self.writer.write(pad_even(bgr))
        self.drawn += 1

    def drop_rescue(self) -> None:
        """The watch has ended and the ``--out`` video is in place, or is not to be written:
        its recording is not needed. (Removed only then: a kill while the MP4 is made of it
        and checked, seconds for an hour's video, leaves it too.)"""
        if self.writer is not None:
            self.writer.release()
        if self.rescue_path is not None:
            self.rescue_path.unlink(missing_ok=True)
            self.rescue_path = None
        for images in (self.images, self.spent):  # the watch ended soon after its start
            if images is not None:
                images.close()
        self.images = self.spent = None

    def _show(self, bgr: Any) -> None:
        import cv2

        try:
            cv2.imshow("posecbr watch", bgr)
            cv2.waitKey(1)
        except cv2.error:
            raise PosecbrError("this OpenCV has no window support: use --out video.mp4") from None

    def close(self, stop: Stop) -> None:
        """The end of the stream: the last segment and the latency. With no segment given, or
        a video file (here or served) watched to its end with nobody in view in any frame (as
        ``segment`` and ``reps`` refuse it; its segments printed, as every segment is when it
        finishes), refused: as the stream ending or ``--max-frames`` stopping it (exit 1), or
        as the user stopping it (``stop`` set: interrupted, exit 130, or 143 for SIGTERM),
        not blamed on the stream. A video stopped by ``--max-frames`` with nobody seen is not
        refused (the rest of it was not watched: the person may come later, as a camera
        watching an empty room may see one): a note says so."""
        from cbr.segmentation import MIN_WINDOW_S

        self._finish()
        seconds = f" ({self.n / self.fps:.2f} s)" if self.fps else ""
        said = None
        if not self.emitted:  # as segment refuses a recording shorter than a window
            said = (
                f"after {counted(self.n, 'frame')}{seconds}, before the shortest window"
                f" ({MIN_WINDOW_S:g} s) of the stream was seen: no segment to give"
            )
        elif self.is_file and not self.seen and not self.limited:
            # a video with nobody in it, as segment and reps refuse it (a camera watching an
            # empty room is no bad input: its segments say nobody in view); its segments
            # were printed as they finished, as every segment is
            nobody = "no torso in any of them (the hips out of view)" if self.no_hips else None
            said = (
                f"after {counted(self.n, 'frame')}{seconds} with"
                f" {nobody or 'nobody in view in any of them'}: no activity to label"
            )
        if said is not None:
            if stop.is_set():
                raise_interrupt(stop.signum, said=f"{self.args.source}: stopped {said}")
            raise DataError(f"{self._ended()} {said}", self.args.source)
        if self.is_file and not self.seen:
            print(
                f"note: {shown(self.args.source)}: nobody in view in the"
                f" {counted(self.n, 'frame')}{seconds} watched ({self._ended()}: the video's"
                " frames after them, if any, were not watched)",
                file=sys.stderr,
            )
        self._summary()

    def _summary(self) -> None:
        """On stderr: how many frames were watched, how fast, and their latency frame to
        label; with ``--split repetitions``, each repetition's verdict and how many got each
        answer. Said at the end of a watch (:meth:`close`) and before a stream lost is
        (:meth:`watch`)."""
        if self.latency.count:
            ms = self.latency.percentile
            wall = time.perf_counter() - self.started
            print(
                f"watched {counted(self.n, 'frame')} in {wall:.1f} s"
                f" ({self.n / wall:.1f} frames/s); "
                f"latency frame to label: median {1000 * ms(50):.1f} ms, "
                f"95th percentile {1000 * ms(95):.1f} ms, worst {1000 * self.latency.worst:.1f} ms",
                file=sys.stderr,
            )
        if self.verdicts is not None:
            _print_verdicts(self.verdicts.given, self.stored.target)


def _print_verdicts(verdicts: list[Any], target: str) -> None:
    """The end of a ``watch --split repetitions``, on stderr: each repetition's verdict, as
    ``classify --split repetitions`` heads each (the first line of its explanation; its
    frames and times as its line gave them, at the rate it was judged at), and how many got
    each answer, as its summary counts them."""
    from collections import Counter

    from cbr.explain import label_words

    for v in verdicts:
        e = v.judged.explanation
        said = (
            e.text.splitlines()[0]
            if e is not None
            else f"unclassifiable ({v.judged.unclassifiable})"
        )
        print(
            f"repetition {v.number}, frames {v.start_frame}-{v.end_frame - 1}"
            f" ({v.start_frame / v.fps:.1f}-{v.end_frame / v.fps:.1f} s): {shown(said)}",
            file=sys.stderr,
        )
    answers = Counter(str(v.label) for v in verdicts if v.label is not None)
    told = ", ".join(f"{shown(label_words(lab, target))} {n}" for lab, n in sorted(answers.items()))
    print(
        f"{counted(len(verdicts), 'repetition')} judged" + (f": {told}" if told else ""),
        file=sys.stderr,
    )


@dataclasses.dataclass(frozen=True)
class _Kept:
    """A live source's frame kept while its grid may be re-made (:attr:`Watcher.kept`): what
    the grid and the drawing read of it, and where its image is kept to be drawn again
    (``--out``: :class:`KeptImages`; None else), read back as :attr:`rgb`."""

    index: int
    time_s: float
    video_time_s: float
    read_at: float
    seen_world: Any
    visibility: Any
    pose: Any
    image: tuple[KeptImages, int, tuple[int, ...], Any] | None

    @classmethod
    def of(cls, frame: Any, images: KeptImages | None) -> _Kept:
        return cls(
            frame.index,
            frame.time_s,
            frame.video_time_s,
            frame.read_at,
            frame.seen_world,
            frame.visibility,
            frame.pose,
            None if images is None else images.put(frame.rgb),
        )

    @property
    def rgb(self) -> Any:
        """The frame's image, as the stream gave it (read back from its :class:`KeptImages`)."""
        if self.image is None:
            return None
        images, offset, shape, dtype = self.image
        return images.get(offset, shape, dtype)


class KeptImages:
    """The images of a live source's frames kept to be drawn again (:attr:`Watcher.kept`,
    with ``--out``), in an unnamed temporary file in the folder of the ``--out`` video (the
    file system's own: no name a kill could leave behind), not in memory: 4 s of 1920x1080
    at 30 fps is 750 MB of images (docs/measurements.md: a 1080p stream that rose at 3.5 s
    peaked at 937 MB, now 586 MB, its video the same bytes). Their bytes are written as
    they are, not compressed: a lossless PNG of a 1080p frame took 126-256 ms to encode
    here (TIFF's LZW 74 ms), where a frame of a 30-fps stream has 33 ms; written, one
    takes a copy."""

    def __init__(self, folder: Path) -> None:
        import tempfile

        # unbuffered: a write that fails (a full disk) fails in put, not in a later flush
        self.file = tempfile.TemporaryFile(dir=folder, buffering=0)  # noqa: SIM115 - close
        self.size = 0

    def put(self, rgb: Any) -> tuple[KeptImages, int, tuple[int, ...], Any]:
        """Keep ``rgb``; where it is, to :meth:`get` it back with. Raises OSError (a full disk)."""
        import numpy as np

        data = np.ascontiguousarray(rgb).data.cast("B")
        offset, done = self.size, 0
        self.file.seek(offset)
        while done < len(data):
            written = self.file.write(data[done:])
            if not written:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            done += written
        self.size += len(data)
        return self, offset, tuple(rgb.shape), rgb.dtype

    def get(self, offset: int, shape: tuple[int, ...], dtype: Any) -> Any:
        """The image :meth:`put` kept at ``offset``."""
        import numpy as np

        image = np.empty(shape, dtype=dtype)
        view, done = image.data.cast("B"), 0
        self.file.seek(offset)
        while done < len(view):
            read = self.file.readinto(view[done:])
            if not read:
                raise OSError(errno.EIO, "the kept images' file ended early")
            done += read
        return image

    def close(self) -> None:
        self.file.close()


class Latencies:
    """The latencies of a stream (seconds), tallied in a histogram of fixed size: memory
    and time per frame the same at the stream's millionth frame as at its first (a watch left
    running for days; every latency was kept before, about 32 bytes a frame, 83 MB a day at
    30 fps, all sorted at the end). Bins grow by :data:`RATIO` from :data:`LOWEST_S` to
    :data:`HIGHEST_S` (one below, one above), so a percentile (:meth:`percentile`, as
    ``numpy.percentile`` interpolates it between the values around its rank) is within half
    a bin, 0.05 %, of the exact one; the least and the worst are exact."""

    RATIO = 1.001
    LOWEST_S = 1e-5
    HIGHEST_S = 1e4

    def __init__(self) -> None:
        import numpy as np

        self.bins = math.ceil(math.log(self.HIGHEST_S / self.LOWEST_S, self.RATIO)) + 2
        self.counts = np.zeros(self.bins, dtype=np.int64)
        self.count = 0
        self.least, self.worst = math.inf, -math.inf

    def add(self, seconds: float) -> None:
        if seconds < self.LOWEST_S:
            i = 0
        else:
            i = min(self.bins - 1, 1 + int(math.log(seconds / self.LOWEST_S, self.RATIO)))
        self.counts[i] += 1
        self.count += 1
        self.least, self.worst = min(self.least, seconds), max(self.worst, seconds)

    def _ranked(self, rank: int) -> float:
        """The value of rank ``rank`` (0: the least): its bin's geometric middle, within the
        least and the worst (exact for those two)."""
        import numpy as np

        if rank in (0, self.count - 1):
            return self.least if rank == 0 else self.worst
        i = int(np.searchsorted(np.cumsum(self.counts), rank, side="right"))
        middle = self.LOWEST_S * float(self.RATIO ** (i - 0.5))
        return min(max(middle, self.least), self.worst)

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile (0-100) of the latencies added (one at least)."""
        at = (self.count - 1) * q / 100.0
        low, high = math.floor(at), math.ceil(at)
        below, above = self._ranked(low), self._ranked(high)
        return below + (at - low) * (above - below)


RATE_CHANGE = 0.2
"""How far off the rate it began with (as a share of it) a live source's rate over its
latest frames (:data:`CHANGE_WINDOW_S`) must be, for :data:`CHANGE_HOLD_S`, to be taken as
changed (:meth:`Regrid._rate_changed`): a camera's auto exposure halves it (50 %); jitter of
20 % on each frame interval moves the rate over 15 of them by some 3 %."""
CHANGE_WINDOW_S = 0.5
"""Over how many seconds of a live source's latest frames its rate now is measured
(:func:`_frame_rate`): a one-off event, a hiccup (a quarter second without a frame; longer
than :data:`BURST_S` is a stall, left out) or a burst (frames read at once after the reader
was held up), is in the window for no longer than it is long."""
CHANGE_HOLD_S = 0.8
"""How long (s) a live source's rate must stay off by :data:`RATE_CHANGE` to be taken as
changed: longer than a one-off hiccup or burst stays off in the window (half a second and
the hiccup's quarter); a camera that halves its rate is followed by the wall clock some
1.1 s after (the rate over the window off by a fifth 0.3 s after, then held): its frames in
between, one to a grid time at the old rate, fell 0.55 s behind the clock, and that many grid
times are then left missing (:meth:`Regrid._rate_changed`)."""

RATE_SLACK = 0.05
"""How far off a live source's rate, measured over its first second, may be: the frames'
lead over the clock it keeps (:meth:`Regrid._stalled`) is forgiven at up to this share of the
time passed. A rate measured from 30 frame intervals that each wander by up to 20 % is off
by 2 % (one standard deviation); a burst's lead, frames read at once after the reader was
held up, is another thing, kept for the next stall for seconds (8 frames at 30 fps: 5 s)."""
RATE_WINDOW_S = 2.0
"""Over how many seconds of a live source's latest frames its frame interval is measured once
it follows the wall clock (:meth:`Regrid._placed`, :func:`_interval`): a second at each end
of a stream that changed its rate once more, half of them after the change."""
BURST_S = 0.5
"""How long a pause a live source's frames may come late after, once it follows the wall
clock, and still be placed a frame interval apart as a burst (frames held up on the way and
then read at once: a network's jitter; a reader held up by a slow frame) rather than at the
times they came (:meth:`Regrid._placed`): 4-6 frames at once at 15 fps come after a pause of
0.27-0.40 s. The frames that come late after a longer pause, or that all still come late a
pause later, came after a stall, its time left missing."""
AT_ONCE = 0.75
"""How soon (a share of the frame interval) each frame after one held after a pause
(:meth:`Regrid._pausing`) must come, a share of as many frame intervals as it lies after it,
for the pause to be a burst's (frames held up on the way, then read as fast as the reader
takes them: the pose model's 10-13 ms a frame on a free core, a third of a 30-fps interval,
more on a busy machine) rather than a drop-out's (the stream resuming at its own pace: a
frame interval apart, give or take their jitter): :meth:`Regrid._burst`."""
JITTER = 0.4
"""How far (a share of the frame interval) a live source's frames may each come off their
time and a drop-out still be told from a burst (:meth:`Regrid._burst`): the time from the
frame held after a pause to the j-th after it is then off its j frame intervals by less than
twice as much, so a j-th that came sooner than that is a burst's; a burst's frames come at
least j quarter intervals sooner (:data:`AT_ONCE`), so by the fourth one of the two is sure.
A network stream's arrivals (+-10 ms at 30 fps: 0.3)."""
REMAKE_S = 4.0
"""How long after a live source's first frame a rise of its rate (a stream that starts slow:
15 fps, then 30 as a camera's auto exposure settles) may be taken by watching it again from
its start at the new rate (:meth:`Watcher._remake`), before any segment is given: its
frames are kept until then (with ``--out``, their images to draw again, in a file:
:class:`KeptImages`). A later rise is followed on the first rate's grid by the wall clock."""
CATCH_UP = 4.0
"""Over how many times its length the lead a live source's frames ran ahead of the wall clock
by, before its rate's rise was taken, is made up (:meth:`Regrid._rate_changed`): the grid's
clock meanwhile at three quarters of the wall clock's speed, the movement a third faster
than it was made (every frame's pose kept; at the lead's end on the clock)."""


class Regrid:
    """A file's or a live source's frames as the live segmenter takes them: evenly spaced at
    ``fps``. While the frames' own times (``video_time_s``) lie at index / fps (a constant
    rate), or a live source's frames come at ``fps`` (the rate measured over its first
    second), each frame is passed as it is (a live source's stalls left missing:
    :meth:`_stalled`). From the first frame of a file that strays (a variable frame rate:
    see :mod:`features.pose_estimation.video`), or once a live source's rate over its latest
    frames has been off ``fps`` by more than :data:`RATE_CHANGE` for :data:`CHANGE_HOLD_S`
    (a webcam's auto exposure halving it as the light falls, a network stream's rate
    sagging, or rising as the light comes back: :meth:`_rate_changed`), the poses are put on
    the grid k / fps as the frames come, by their own times (a live source's: the wall
    clock's, from the window its rate was first off in: the grid times its frames fell
    behind the clock by meanwhile are left missing, :meth:`_behind`, and a lead they ran
    ahead of it by is made up over :data:`CATCH_UP` times its length; a burst of frames,
    held up on the way and read at once, each a frame interval after the one before:
    :meth:`_placed`; from the first burst before any change of rate too:
    :meth:`_burst_begins`; from the first frame when made with ``interval``, the interval its
    frames came at: a live source watched again at the rate it rose to,
    :meth:`Watcher._remake`, which a rise is left to when :attr:`remakable`, :attr:`rose`
    then its rate), each grid time linearly between the frames around it (a joint
    missing in either stays missing; every joint missing between two frames further apart
    than :func:`features.pose_estimation.video.bridge_limit_s`: a gap in the video, or the
    stream stalled, no motion made up for it, as ``extract`` leaves it; :attr:`absent` says
    which), and the user is told once on stderr, and once more at each such gap. Before, a
    live source's frames were counted at the rate of its first second for good: a camera
    that fell from 30 to 15 fps had each frame still count 1/30 s, its windows holding 4 s
    of movement and its segments timed at half the wall clock's speed."""

    def __init__(self, fps: float, source: str, interval: float | None = None) -> None:
        self.fps, self.source = fps, source
        self.resampling = False
        self.k = 0  # the next grid frame
        self.prev: Any = None  # the last frame taken
        self.first_s = math.nan  # the first frame's time_s (a live source's: the wall clock's)
        self.zero_s = math.nan  # when grid frame 0 was, by the clock stalls are counted by
        self.absent: list[bool] = []  # of the grid times the last take gave: inside a gap
        self.images: list[Any] = []  # and their image landmarks (the pose's jumps)
        # a live source's latest frames (time_s, grid frame), half a second of them: its rate
        self.recent: collections.deque[tuple[float, int]] = collections.deque()
        self.off_since = math.nan  # since when (time_s) that rate has been off fps
        self.off_from = (math.nan, 0)  # then: the window's first frame (time_s, grid frame)
        self.owed = 0  # grid times the frames fell behind the clock by, left missing
        self.by_clock = False  # a live source's frames put on the grid by the wall clock
        self.origin_s = math.nan  # then: the wall clock's time of grid frame 0
        self.placed_s = math.nan  # then: when the last frame taken lies on the grid's clock
        # a live source's latest frames (time_s, how late each came after its place on the
        # grid's clock: 0 before it follows the wall clock, which of its frames it is),
        # :data:`RATE_WINDOW_S` of them (:meth:`_placed`)
        self.clocked: collections.deque[tuple[float, float, int]] = collections.deque()
        self.came = 0  # a live source's frames so far
        self.interval = 1.0 / fps  # its frame interval now (s), once it follows the clock
        self.ahead = (0.0, 0.0)  # then: how far its grid ran ahead of the clock (s), and since
        # a live source whose rate, risen, is to be taken by re-making the grid (and the
        # segmenter) at it (:meth:`Watcher._remake`), not followed here: then the rate
        self.remakable = False
        self.rose: float | None = None
        # the frames taken are a re-made grid's kept ones, taken again (:meth:`Watcher._remake`):
        # its notes were said when they first came (a stall said twice, its times a little off)
        self.quiet = False
        # a live source's frame that came after a pause (:meth:`_pausing`) and those after
        # it, held until they tell a burst from a drop-out (:meth:`_burst`, :meth:`_released`)
        self.held: list[Any] = []
        if interval is not None:  # on the wall clock from the first frame, which came so
            self.resampling = self.by_clock = True
            self.interval = interval

    def _note(self, words: str) -> None:
        """Say ``words`` of the source on stderr, unless :attr:`quiet`."""
        if not self.quiet:
            print(f"note: {self.source}: {words}", file=sys.stderr)

    def take(self, frame: Any) -> list[tuple[Any, Any, Any]]:
        """(world, visibility, the frame on screen then) for each grid time up to this
        frame's (:attr:`absent` and :attr:`images` for each); none while this frame is held
        (:attr:`held`: after a pause, :meth:`_pausing`, until the frames after it tell a
        burst from a drop-out, :meth:`_burst`): the frames held before it are given first
        (:meth:`_released`)."""
        if not self.held:
            return self._take(frame)
        self.held.append(frame)
        burst = self._burst()
        if burst is None:
            self.absent, self.images = [], []
            return []
        return self._given(burst)

    def flush(self) -> list[tuple[Any, Any, Any]]:
        """:meth:`take`'s grid times of the frames held when the stream ends (none when none
        is): the first a burst's if a frame came after it (each at once: :meth:`_burst`),
        else, with none after it, placed at the time it came, as a drop-out's."""
        out: list[tuple[Any, Any, Any]] = []
        absent: list[bool] = []
        images: list[Any] = []
        while self.held:  # a frame given may be held again, after a pause of its own
            out += self._given(len(self.held) > 1)
            absent, images = absent + self.absent, images + self.images
        self.absent, self.images = absent, images
        return out

    def _burst(self) -> bool | None:
        """Whether the frame held after a pause (the first of :attr:`held`) is the first of a
        burst, told by the latest frame held after it, the j-th: False (a drop-out, the
        stream resumed at its own pace) when it came no sooner than :data:`AT_ONCE` of j
        frame intervals after the held one, as no burst's does; True when sooner than j
        intervals less twice :data:`JITTER`'s, as no drop-out's does, its frames each off
        their times by less than :data:`JITTER`; else None, told by the next (by the
        fourth, one of the two holds). The time from the held frame to the j-th after it is
        off its j intervals by twice an arrival's jitter at most, however large j; a burst's
        frames come a quarter interval sooner each at least. A drop-out on time and a burst
        read at once are told by the first frame, as before; before, the first frame alone
        told every pause: 0.25-0.5-s drop-outs at 30 fps, arrivals +-10 ms, 13 of 100 taken
        for bursts (poses up to 0.47 s off their times)."""
        first, *after = self.held
        since = (after[-1].time_s - first.time_s) / self.interval
        if not since < AT_ONCE * len(after):
            return False
        return True if since < len(after) - 2.0 * JITTER else None

    def _given(self, burst: bool) -> list[tuple[Any, Any, Any]]:
        """:meth:`take`'s grid times of the frames held (:attr:`held`): the first after the
        pause given as a burst's or not (:meth:`_released`), the others taken after it (one
        of them held again after a pause of its own, and those after it; none after a rise
        of the rate, :attr:`rose`: the grid is to be made again)."""
        held, self.held = self.held, []
        out = self._released(held[0], burst)
        absent, images = self.absent, self.images
        for frame in held[1:]:
            if self.rose is not None:
                break
            out += self.take(frame)
            absent, images = absent + self.absent, images + self.images
        self.absent, self.images = absent, images
        return out

    def _take(self, frame: Any) -> list[tuple[Any, Any, Any]]:
        """:meth:`take` of a frame when none is held."""
        from features.pose_estimation.video import strays

        t = frame.video_time_s
        self.absent, self.images = [], []
        if self.prev is None:
            self.first_s = self.zero_s = frame.time_s
            if self.by_clock:  # made on the wall clock: grid time 0 is this frame's
                self.origin_s, self.placed_s = frame.time_s, 0.0
                self._came(frame.time_s, 0.0)
                self.prev, self.k = frame, 1
                self.absent, self.images = [False], [_image(frame)]
                return [(frame.seen_world, frame.visibility, frame)]
        if not (self.resampling or math.isfinite(t)) and not self._rate_changed(frame):
            # a live source (or a file without frame times) at the rate it began with
            if self.rose is not None:  # to be re-made at the rate it rose to: nothing given
                return []
            if self._pausing(frame):
                return []
            return self._counted(frame)
        if self.by_clock:  # a live source whose rate changed, at this frame or before
            if self._rose_on_clock(frame) or self._pausing(frame):
                return []
            return self._behind(frame) + self._resampled(frame, self._placed(frame))
        if not self.resampling:
            if not strays(t, frame.index, self.fps):
                self.prev, self.k = frame, frame.index + 1
                self.absent, self.images = [False], [_image(frame)]
                return [(frame.seen_world, frame.visibility, frame)]
            self.resampling = True
            self._note(
                f"variable frame rate (frame {frame.index} is at {t:.3f} s, not"
                f" {frame.index / self.fps:.3f} s): poses resampled to {self.fps:g} fps as"
                " they come"
            )
        return self._resampled(frame, t)

    def _counted(self, frame: Any) -> list[tuple[Any, Any, Any]]:
        """:meth:`take` of a live source's ``frame`` at the rate it began with: on the grid
        time after the frame before's, after those it stalled for (:meth:`_stalled`)."""
        out = self._stalled(frame)
        if out and self.clocked and self.clocked[-1][0] == frame.time_s:
            time_s, late_s, _count = self.clocked[-1]  # the camera's frames lost, counted
            self.came += len(out)  # (:func:`_interval`: once a burst puts it on the clock)
            self.clocked[-1] = (time_s, late_s, self.came)
        if self.recent:  # the grid frame it lies on, after those left missing
            self.recent[-1] = (frame.time_s, self.k + len(out))
        self.prev, self.k = frame, self.k + len(out) + 1
        self.absent, self.images = [True] * len(out) + [False], [None] * len(out)
        self.images.append(_image(frame))
        return [*out, (frame.seen_world, frame.visibility, frame)]

    def _pausing(self, frame: Any) -> bool:
        """Whether a live source's ``frame`` came after a pause longer than
        :func:`features.pose_estimation.video.bridge_limit_s` but shorter than
        :data:`BURST_S` (the second frame on: a webcam's wait for its second frame is a
        stall), or on the grid by the wall clock, after the frame before's place by as long
        (a burst's last frames, placed by their count, and the frames of a drop-out after
        them lost): held (:attr:`held`, nothing given for it) until the next frame tells what
        the pause was (:meth:`_released`)."""
        from features.pose_estimation.video import bridge_limit_s

        prev = self.prev
        if prev is None or self.k < 2 or not frame.time_s - prev.time_s < BURST_S:
            return False
        pause = frame.time_s - prev.time_s
        if self.by_clock:  # or after the frame before's place: a burst's frames placed late
            behind = self._on_clock(frame.time_s) - self.placed_s
            late = self.clocked[-1][1] if self.clocked else math.inf
            if not behind - self.interval < late - (1.0 - AT_ONCE) * self.interval:
                pause = max(pause, behind)  # unless still catching up, as :meth:`_placed` says
        if not pause > bridge_limit_s(self.fps):
            return False
        self.held, self.absent, self.images = [frame], [], []
        return True

    def _released(self, held: Any, burst: bool) -> list[tuple[Any, Any, Any]]:
        """:meth:`take` of the frame ``held`` after a pause (:meth:`_pausing`), told by the
        frames after it (:meth:`_burst`). The first of a ``burst`` (frames held up on the way
        and read at once) is placed a frame interval after the frame before, as the camera
        took it (:meth:`_burst_begins`, :meth:`_placed`). Else the stream resumed at its own pace
        after a drop-out (the camera's frames of the pause lost, not held up): the frame lies
        at the time it came and the pause's grid times are left missing, said once on stderr
        (:meth:`_stalled`; :meth:`_placed`'s ``resumed``), as a stall longer than
        :data:`BURST_S` is. Before, every such pause was taken as a burst's: the frames after
        a drop-out were placed a frame interval apart by their count, each as early as the
        pause was long, until half a second later the lag was made up, the pause's grid times
        left missing only then (0.27-0.45-s drop-outs every 2 s at 30 fps: 34 of 78 grid times
        missing outside the pauses, poses up to 0.43 s off the clock)."""
        self.absent, self.images = [], []
        if not self.by_clock:
            if burst:
                self._burst_begins(held)
                return self._resampled(held, self._placed(held))
            return self._counted(held)
        return self._behind(held) + self._resampled(held, self._placed(held, resumed=not burst))

    def _resampled(self, frame: Any, t: float) -> list[tuple[Any, Any, Any]]:
        """:meth:`take` of a frame at ``t`` s on the grid's clock (a file's own time, a live
        source's wall clock from :attr:`origin_s`) once resampling: the grid times from
        :attr:`k` up to ``t``, each between the frame before and this one."""
        import numpy as np

        from features.pose_estimation.video import blend, bridged_weight, gap_words

        prev = self.prev
        start = math.nan if prev is None else self.placed_s if self.by_clock else prev.video_time_s
        if prev is None or not math.isfinite(t) or t <= start:
            return []  # no time to place it by
        out, gap = [], []
        while self.k / self.fps <= t + 1e-9:
            w = bridged_weight(self.k / self.fps, start, t, self.fps)
            gap.append(bool(np.isnan(w)))
            world = blend(prev.seen_world, frame.seen_world, w)
            vis = blend(np.asarray(prev.visibility), np.asarray(frame.visibility), w)
            image = _image(prev), _image(frame)
            self.images.append(None if any(i is None for i in image) else blend(*image, w))
            out.append((world, vis, frame if w >= 1.0 - 1e-9 else prev))
            self.k += 1
        self.prev, self.placed_s = frame, t
        self.absent += gap
        if any(gap) and not self.by_clock:
            self._note(gap_words([(start, t)]))
        elif any(gap):  # as :meth:`_stalled` says it, from the first frame
            since = self.origin_s - self.first_s
            words = gap_words([(start + since, t + since)])
            self._note(f"the stream stalled: {words}")
        return out

    def _behind(self, frame: Any) -> list[tuple[Any, Any, Any]]:
        """The grid times a live source's frames fell behind the wall clock by before its
        change of rate was taken (:attr:`owed`, :meth:`_rate_changed`), each (missing world,
        missing visibility, the frame before on screen): their poses were given early, one
        to a grid time at the old rate, and are not given twice."""
        import numpy as np

        owed, self.owed = self.owed, 0
        self.k += owed
        self.absent += [True] * owed
        self.images += [None] * owed
        nan = np.full((len(frame.visibility),), np.nan)
        return [(np.full_like(frame.seen_world, np.nan), nan, self.prev)] * owed

    def _placed(self, frame: Any, resumed: bool = False) -> float:
        """When a live source's ``frame`` lies on the grid's clock once it follows the wall
        clock (s from :attr:`origin_s`, plus what is left of a lead to make up,
        :attr:`ahead`): a frame interval after the frame before (the count's time: the
        interval over the latest :data:`RATE_WINDOW_S`, :func:`_interval`), never after it came
        (the wall clock: a rate that rises is followed at once) and not before it by more
        than the least any frame of the latest :data:`BURST_S` came after its place (the
        stream's own delay, which a frame that came as soon as any shows). A frame late
        after a pause is one of a burst, frames held up on the way and then read at once,
        placed a frame interval after the one before, as the camera took them; a lag that
        every frame of the latest :data:`BURST_S` has (none comes after a longer pause) is
        the stream's, a stall: made up at once, the time between left missing as before.
        Before, each frame lay at the time it came: a burst's frames fell on one grid time,
        all but the last of them lost. Frames that are still catching up (each less late
        than the one before by more than a quarter of a frame interval, :data:`AT_ONCE`: a
        burst read as fast as the reader takes frames) are placed by their count whatever
        that lag: before, a burst after a 0.43-s pause read 0.6 of an interval apart was
        taken for a stall once the frames before the pause had left the latest
        :data:`BURST_S` (11 grid times missing in the middle of it at 30 fps).
        ``resumed``: the frame came after a drop-out
        (:meth:`_released`): at the time it came, the lag made up at once, the camera's frames
        lost in the pause counted (:func:`_interval` counts frames)."""
        now = float(frame.time_s)
        came = self._on_clock(now)
        clocked = self.clocked
        while clocked and clocked[0][0] <= now - RATE_WINDOW_S:
            clocked.popleft()
        placed = came
        if clocked:
            if len(clocked) > 3:
                self.interval = _interval(clocked, self.interval)
            due = self.placed_s + self.interval  # the count's time
            late = came - due
            lag = min((c[1] for c in clocked if c[0] > now - BURST_S), default=late)
            if resumed:
                lag = late
                self.came += max(0, round(late / self.interval))
            elif late < clocked[-1][1] - (1.0 - AT_ONCE) * self.interval:
                lag = 0.0  # catching up: a burst still read, as fast as the reader takes them
            placed = min(came, due + max(0.0, min(late, lag)))
        self._came(now, came - placed)
        return placed

    def _on_clock(self, now: float) -> float:
        """The wall clock's time ``now`` on the grid's clock (s from :attr:`origin_s`, plus
        what is left of a lead to make up, :attr:`ahead`) once it follows the wall clock."""
        came = now - self.origin_s
        lead, since = self.ahead
        if lead > 0:  # the grid's lead over the clock, made up as the clock goes on
            came += lead * max(0.0, 1.0 - (now - since) / (CATCH_UP * lead))
        return came

    def _rose_on_clock(self, frame: Any) -> bool:
        """Whether a live source already on the grid by the wall clock (a burst put it there:
        :meth:`_burst_begins`), whose grid may yet be re-made at a rate that rises
        (:attr:`remakable`), has risen at ``frame``: its rate over the latest
        :data:`CHANGE_WINDOW_S` above ``fps`` by more than :data:`RATE_CHANGE` for
        :data:`CHANGE_HOLD_S`, as :meth:`_rate_changed` takes a rise before. :attr:`rose` is
        then the rate over the latest :data:`CHANGE_HOLD_S`, and nothing is given for
        ``frame`` (:meth:`Watcher._remake` watches the stream again from its start). Before,
        a rise after a burst was followed on the first rate's grid for good (15 fps, a
        burst, then 30 fps: half the frames resampled away)."""
        if not self.remakable:
            return False
        recent = self.recent
        recent.append((frame.time_s, self.k))
        while len(recent) > 2 and recent[1][0] <= frame.time_s - CHANGE_WINDOW_S:
            recent.popleft()
        rate = _frame_rate([time_s for time_s, _k in recent], CHANGE_WINDOW_S, BURST_S)
        if rate is None or rate / self.fps - 1.0 <= RATE_CHANGE:
            self.off_since = math.nan
            return False
        if not frame.time_s - self.off_since >= CHANGE_HOLD_S:  # NaN: off from now
            if math.isnan(self.off_since):
                self.off_since = frame.time_s
            return False
        latest = [c[0] for c in self.clocked if c[0] > frame.time_s - CHANGE_HOLD_S]
        self.rose = _frame_rate([*latest, frame.time_s], CHANGE_WINDOW_S, BURST_S) or rate
        return True

    def _came(self, time_s: float, late_s: float) -> None:
        """Count a live source's frame that came at ``time_s`` (the wall clock's), ``late_s``
        after its place on the grid's clock, among :attr:`clocked`."""
        self.came += 1
        self.clocked.append((time_s, late_s, self.came))
        while self.clocked[0][0] <= time_s - RATE_WINDOW_S:
            self.clocked.popleft()

    def _rate_changed(self, frame: Any) -> bool:
        """Whether a live source's frames, from ``frame`` on, are to be put on the grid by the
        wall clock: its rate over its latest frames (:data:`CHANGE_WINDOW_S`,
        :func:`_frame_rate` of their times: an interval longer than :data:`BURST_S`, a
        stall, left out; a burst's pause counted with its frames) has been off ``fps`` by more
        than :data:`RATE_CHANGE` for
        :data:`CHANGE_HOLD_S` (not a hiccup, nor jitter). Then the grid's clock
        (:attr:`origin_s`) is the wall clock from the first frame of the window the rate was
        first off in (before the change: on the grid as it came), and the grid times the
        frames since, one to a grid time at the old rate, fell behind it by (:attr:`owed`)
        are left missing (:meth:`_behind`): their poses were given early, and a grid time
        given is final. A rate that rose had them run ahead of it instead, their poses given
        late: that lead (:attr:`ahead`) is made up over :data:`CATCH_UP` times its length,
        the frames meanwhile put on the grid by a clock that runs a quarter slower than the
        wall clock (:meth:`_placed`; none left out). The user is told once on stderr, from
        which rate to which and how many grid times are missing, or how far ahead the grid
        is. Before, the grid's clock was set so that ``frame`` lay on the next grid time: a
        camera that halved its rate had every grid time after the change 0.55 s early by the
        wall clock, and a stream that doubled its rate from 15 fps had every grid time after
        it some 1.0 s late, for good."""
        recent = self.recent
        recent.append((frame.time_s, self.k))
        while len(recent) > 2 and recent[1][0] <= frame.time_s - CHANGE_WINDOW_S:
            recent.popleft()
        rate = _frame_rate([time_s for time_s, _k in recent], CHANGE_WINDOW_S, BURST_S)
        if rate is None or abs(rate / self.fps - 1.0) <= RATE_CHANGE:
            self.off_since = math.nan
            self._came(frame.time_s, 0.0)  # one to a grid time: at its place
            return False
        if not frame.time_s - self.off_since >= CHANGE_HOLD_S:  # NaN: off from now
            if math.isnan(self.off_since):
                self.off_since, self.off_from = frame.time_s, recent[0]
            self._came(frame.time_s, 0.0)
            return False
        if self.remakable and rate > self.fps:  # the grid re-made at it: nothing said here
            latest = [c[0] for c in self.clocked if c[0] > frame.time_s - CHANGE_HOLD_S]
            self.rose = _frame_rate([*latest, frame.time_s], CHANGE_WINDOW_S, BURST_S) or rate
            return False
        self.resampling = self.by_clock = True
        from_s, from_k = self.off_from
        self.origin_s = from_s - from_k / self.fps
        self.placed_s = self.prev.time_s - self.origin_s  # the frame before's, by the clock
        owed = math.floor(self.placed_s * self.fps + 1e-9) + 1 - self.k
        self.owed = max(0, owed)
        recent.clear()
        behind = ""
        if owed > 0:  # the frames before, counted at the old rate, fell behind the clock
            behind = (
                f" ({counted(owed, 'frame')}, {owed / self.fps:.2f} s, left missing:"
                " the frames before, counted at the old rate, fell that far behind the clock)"
            )
        elif owed < 0:  # they came faster: the grid times they were given ran ahead of it
            lead = (self.k - 1) / self.fps - self.placed_s
            self.ahead = (lead, self.prev.time_s)
            self.placed_s += lead  # the frame before, on the grid where it was given
            behind = (
                f" (the grid {lead:.2f} s ahead of the clock, made up over the next"
                f" {CATCH_UP * lead:.1f} s: the frames before, counted at the old rate, ran"
                " that far ahead of it)"
            )
        self._note(
            f"the frame rate changed from {self.fps:.3g} to {rate:.3g} fps at"
            f" {frame.time_s - self.first_s:.1f} s: poses resampled to {self.fps:.3g} fps by"
            f" the clock as they come{behind}"
        )
        return True

    def _burst_begins(self, frame: Any) -> None:
        """Put a live source on the grid by the wall clock from ``frame``, at the rate it
        began with the first of a burst (:meth:`_released`: frames held up on the way and
        read at once after a pause longer than
        :func:`features.pose_estimation.video.bridge_limit_s`): its frames a frame interval
        apart by their count (:meth:`_placed`), the grid's clock set by the latest frames
        (:attr:`recent`) that came earliest for their grid time, and the user told once on
        stderr. Before (hunt 50m), the pause was a stall: its grid times left missing, then
        the burst's frames, one to a grid time, ran that far ahead of the clock for good
        (bursts of 8 at 30 fps: every grid time after the first burst 0.23 s late by the
        clock). A source that never pauses so long (a steady one, jittered) is passed as it
        was."""
        prev = self.prev
        self.resampling = self.by_clock = True
        self.off_since = math.nan  # a rise from here on: :meth:`_rose_on_clock`
        earlier = list(self.recent)[:-1]  # this frame's own (time_s, grid frame) left out
        self.origin_s = min(time_s - k / self.fps for time_s, k in earlier)
        self.placed_s = prev.time_s - self.origin_s
        self.clocked.pop()  # this frame, counted at its place by :meth:`_rate_changed`
        self.came -= 1
        self._note(
            f"{frame.time_s - prev.time_s:.2f} s without frames at"
            f" {prev.time_s - self.first_s:.1f} s, then frames at once (held up on the way?):"
            f" poses resampled to {self.fps:.3g} fps by the clock as they come"
        )

    def _stalled(self, frame: Any) -> list[tuple[Any, Any, Any]]:
        """The grid times a live source sent no frame for before ``frame``, each (missing
        world, missing visibility, the frame before on screen), said on stderr: a stream
        that stalled (a camera's or a network's hiccup shorter than ``--stall``) and resumed,
        its frames more than :func:`features.pose_estimation.video.bridge_limit_s` apart by
        their times (``time_s``: the wall clock's for a live source; index / fps, never a
        gap, for a file without frame times), as ``extract`` leaves a gap in a video's
        frames. No more than the frames pushed lag the wall clock (frames that came in a burst
        after a stall, ahead of it, are not counted missing twice). Before, the frames either
        side were joined as if none were missing: the segments after a stall were timed
        early by its length and a movement ran across it. The lag is counted from
        :attr:`zero_s`, which a lead of the frames over the clock moves on by up to
        :data:`RATE_SLACK` of the time passed: a rate measured over the first second a
        little low (29.7 for 30 fps) had the frames run ahead of the clock counted from the
        first frame by a frame every 3.3 s, and after about 5 minutes a 3-s stall was joined
        again as if nothing were missing; a burst's lead is kept for seconds (8 frames, the
        reader's queue: 5 s at 30 fps), to be taken off the next stall."""
        import numpy as np

        from features.pose_estimation.video import bridge_limit_s, gap_words

        prev = self.prev
        if prev is not None:  # the frames' lead over the clock, forgiven as a rate's error
            lead = self.k - (frame.time_s - self.zero_s) * self.fps
            slack = RATE_SLACK * max(0.0, frame.time_s - prev.time_s)
            self.zero_s -= max(0.0, min(lead / self.fps, slack))
        if prev is None or not frame.time_s - prev.time_s > bridge_limit_s(self.fps):
            return []
        behind = round((frame.time_s - self.zero_s) * self.fps) - self.k
        between = round((frame.time_s - prev.time_s) * self.fps) - 1
        missing = max(0, min(between, behind))
        if missing:
            words = gap_words([(prev.time_s - self.first_s, frame.time_s - self.first_s)])
            self._note(f"the stream stalled: {words}")
        nan = np.full((len(frame.visibility),), np.nan)
        return [(np.full_like(frame.seen_world, np.nan), nan, prev)] * missing


def _interval(clocked: collections.deque[tuple[float, float, int]], before: float) -> float:
    """A live source's frame interval (s) from its latest frames (when each came, how late,
    which of its frames: :attr:`Regrid.clocked`; four at least): between the frame of the
    older half that came earliest for its count (by the interval ``before``) and that of the
    newer half. Frames held up on the way and read at once come late for their count; the
    last of a burst, or a frame that came on time, does not, and the stream's own delay is
    the same at both: a burst's frames make a staircase of when they came, its steps' slope
    the stream's. (A least-squares slope over the staircase was off by up to a fifth over
    one second and 2-3 % over two, each frame then placed up to 27 ms off.)"""
    half = len(clocked) // 2
    older = [clocked[i] for i in range(half)]
    newer = [clocked[i] for i in range(half, len(clocked))]
    a = min(older, key=lambda c: c[0] - c[2] * before)
    b = min(newer, key=lambda c: c[0] - c[2] * before)
    return (b[0] - a[0]) / (b[2] - a[2])


def _image(frame: Any) -> Any:
    """A frame's image landmarks ``(33, 5)`` (px), or None when it has none (a made-up
    frame)."""
    import numpy as np

    pose = getattr(frame, "pose", None)
    image = getattr(pose, "image", None)
    return None if image is None else np.asarray(image, dtype=float)


def _frame_rate(
    times: list[float], least_s: float = 1.0, longest_s: float | None = None
) -> float | None:
    """A live source's frame rate from ``least_s`` seconds of its frames' times (s; its
    first second, or its latest half second: :meth:`Regrid._rate_changed`), None when they
    span less (not yet known), an interval longer than
    :func:`features.pose_estimation.video.bridge_limit_s` at the median interval's rate
    (three of them, at least a quarter second) left out: no
    frame was sent then (a webcam's wait between its first frame and the next, a stall),
    as :meth:`Regrid._stalled` leaves it missing. Before, a webcam that sent its second
    frame 0.6 s after its first and then 30 a second was measured at 13 fps, and every
    segment was timed 2.3 times too long. ``longest_s``: the longest interval counted
    instead (the latest half second's: :data:`BURST_S`, a burst's pause counted with its
    frames, which came at once: by the median's rule each burst's pause was left out, the
    rest spanned too little, and a rate that fell into bursts was never measured). A pause
    after which the stream resumed at its own pace (a drop-out: the frames of the pause
    lost, not held up and read at once, :func:`_dropped`) is left out of the rate, though
    counted in the span: before, 60 fps with a 0.32-s drop-out in the latest 0.8 s was
    measured at 37.5 fps."""
    import numpy as np

    from features.pose_estimation.video import BRIDGE_FRAMES, MAX_BRIDGE_S

    gaps = np.diff(times)
    if not len(gaps):
        return None
    median = statistics.median(gaps.tolist())  # numpy's: ten times as long, every frame
    if longest_s is None:
        longest_s = max(MAX_BRIDGE_S, BRIDGE_FRAMES * median)
    sent = gaps <= longest_s
    if gaps[sent].sum() < least_s:
        return None
    kept = gaps[sent & ~_dropped(gaps, median, sent)]
    return float(len(kept) / kept.sum())


def _dropped(gaps: Any, median: float, sent: Any) -> Any:
    """Which of a live source's frame intervals ``gaps`` (s; their median ``median``; those
    counted in its rate: ``sent``) are drop-outs: pauses longer than
    :data:`~features.pose_estimation.video.BRIDGE_FRAMES` median intervals after which the
    stream resumed at its own pace, the mean of the (up to as many) intervals after the
    pause no shorter than :data:`AT_ONCE` of the median, as :meth:`Regrid._burst` tells a
    drop-out from a burst (frames held up on the way, then read at once: their pause is
    the time the frames read at once were taken in), nor longer than such a pause (the
    stream's pace fell: 60 fps, then 15, had the slow intervals left out as drop-outs, and
    the fall measured at 54 fps, no change of rate). None is when the pauses so told would
    take more of the time counted than the rest (a stream that comes in bursts whose
    frames, read at once, are most of its intervals: their median is the reader's pace, not
    the stream's), nor a pause with no interval after it (which the frames to come may yet
    tell a burst's)."""
    import numpy as np

    from features.pose_estimation.video import BRIDGE_FRAMES

    out = np.zeros(len(gaps), dtype=bool)
    for i in np.flatnonzero(sent & (gaps > BRIDGE_FRAMES * median)).tolist():  # a few
        after = gaps[i + 1 : i + 1 + BRIDGE_FRAMES]
        pace = float(np.mean(after)) if len(after) else math.nan  # NaN: none told
        out[i] = AT_ONCE * median <= pace <= BRIDGE_FRAMES * median
    if gaps[out].sum() > gaps[sent & ~out].sum():  # mostly pauses: bursts, not drop-outs
        out[:] = False
    return out
