"""Small sound files and videos with sound, written by PyAV, for the container tests
(``tests/test_hunt34h.py``, ``tests/test_hunt35g.py``; the callers skip without PyAV), and a
video's frames as OpenCV decodes them (:func:`read_frames`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def _silence(fmt: str, n: int, rate: int, pts: int) -> Any:
    """A mono frame of ``n`` silent samples in sample format ``fmt`` at ``rate`` Hz."""
    import av

    dtype = np.int16 if fmt.startswith("s16") else np.float32
    frame = av.AudioFrame.from_ndarray(np.zeros((1, n), dtype), format=fmt, layout="mono")
    frame.sample_rate, frame.pts = rate, pts
    return frame


def silence_file(
    path: Path, codec: str, fmt: str, n: int, rate: int, container: str | None = None
) -> Path:
    """About a second of silence (``rate // n`` frames of ``n`` samples, mono, sample format
    ``fmt``) by ``codec``, in ``container`` (None: the one the file name says; an ``.m2ts``
    file in M2TS mode)."""
    import av

    options = {"mpegts_m2ts_mode": "1"} if path.suffix == ".m2ts" else {}
    out = av.open(str(path), "w", format=container, options=options)
    stream = out.add_stream(codec, rate=rate)
    for k in range(rate // n):
        for packet in stream.encode(_silence(fmt, n, rate, k * n)):
            out.mux(packet)
    for packet in stream.encode():
        out.mux(packet)
    out.close()
    return path


def mux_frames_and_silence(
    out: Any, video: Any, sound: Any, frames: int, sound_s: float, sound_format: str, n: int
) -> None:
    """Into ``out``: ``frames`` grey frames at 30 fps (64 x 48) by ``video`` and ``sound_s``
    seconds of silence (mono, ``n`` samples a packet, sample format ``sound_format``) by
    ``sound``, interleaved by time; then both streams flushed and ``out`` closed."""
    import av

    rate = sound.codec_context.sample_rate
    chunks = round(sound_s * rate / n)
    v = a = 0
    while v < frames or a < chunks:
        if v < frames and (a >= chunks or v / 30 <= a * n / rate):
            picture = np.full((48, 64, 3), (3 * v) % 250, np.uint8)
            frame = av.VideoFrame.from_ndarray(picture, format="rgb24")
            frame.pts, v = v, v + 1
            packets = video.encode(frame)
        else:
            packets = sound.encode(_silence(sound_format, n, rate, a * n))
            a += 1
        for packet in packets:
            out.mux(packet)
    for stream in (video, sound):
        for packet in stream.encode():
            out.mux(packet)
    out.close()


def read_frames(path: Path) -> tuple[list[np.ndarray], float]:
    """Every frame of the video ``path`` as OpenCV decodes it (BGR), and the rate it states."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    frames = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        frames.append(bgr)
    cap.release()
    return frames, fps
