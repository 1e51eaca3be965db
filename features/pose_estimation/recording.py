"""A video written frame by frame that a kill leaves playable up to its last frame written.

:class:`Recording` encodes each frame once, with OpenCV's MPEG-4 encoder, into FFmpeg's NUT
container, which needs no index at its end (an MP4's ``moov`` box is written when the writer
is released: an MP4 a kill leaves opens in no player). FFmpeg writes a file in blocks of
256 KiB (its file protocol's packet size for a file it can seek in: about 10 frames of
a 1280x720 video lost at a kill) but flushes what it writes to a pipe after every frame, so
the NUT goes through a named pipe (a FIFO beside the file) that the recording copies to the
file as it comes, the frame's bytes in the file before :meth:`Recording.write` returns. Where
no FIFO can be made (a file system without them, Windows), FFmpeg writes the file itself.
:meth:`Recording.to_mp4` makes the MP4 of the frames written from the NUT's encoded frames,
copied, not encoded again (OpenCV's raw video encapsulation: ``VIDEOWRITER_PROP_RAW_VIDEO``):
the same frames, bit for bit, as OpenCV's MP4 writer gives.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..errors import DataError
from ..fileio import cannot_write, write_failure

#: The encoder: OpenCV's FFmpeg MPEG-4 Part 2, the cheapest to run of those OpenCV writes
#: (3.8-4.6 ms of CPU a 1280x720 frame; MJPEG 7.1 ms, MPEG-1 9.2 ms, FFV1 38 ms) and
#: the one ``watch --out`` and ``segment --overlay`` always wrote.
FOURCC = cv2.VideoWriter.fourcc(*"mp4v")

_PIPE_BYTES = 1 << 20  # the pipe's size asked for (Linux's most without privileges)
_F_SETPIPE_SZ = 1031


class Recording:
    """Frames of ``size`` (width, height, both even) at ``fps`` written to the NUT file
    ``path`` (which must end in ``.nut``: OpenCV picks the container by the name), through
    a FIFO named ``path`` with ``.pipe.nut`` for its ending when one can be made there
    (removed when the recording is released). Raises DataError naming ``what`` when the
    video cannot be encoded here."""

    def __init__(self, path: Path, fps: float, size: tuple[int, int], what: str) -> None:
        self.path, self.fps, self.size, self.what = path, fps, size, what
        self.frames = 0
        self.failed = False  # the file could not take the pipe's bytes (a full disk)
        self._fifo: Path | None = None
        self._read_fd = -1
        self._file: Any = None
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        target = self._open_fifo()
        self._writer: Any = cv2.VideoWriter(str(target), FOURCC, fps, size)
        if not self._writer.isOpened():
            self._close_fifo()
            raise DataError("cannot encode an MP4 video here", what)
        if self._fifo is not None:
            self._thread = threading.Thread(
                target=self._copy, name="posecbr-recording", daemon=True
            )
            self._thread.start()

    def _open_fifo(self) -> Path:
        """The FIFO FFmpeg is to write into, its reading end open (non-blocking: FFmpeg's
        open of its writing end returns at once) and ``path`` open to copy it to; ``path``
        itself where no FIFO can be made."""
        fifo = self.path.with_name(self.path.name.removesuffix(".nut") + ".pipe.nut")
        try:
            os.mkfifo(fifo, 0o600)
        except (OSError, AttributeError):  # no FIFOs on this file system, or no mkfifo
            return self.path
        try:
            self._read_fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
            self._file = open(self.path, "wb", buffering=0)  # noqa: SIM115 - closed in release
        except OSError:
            self._fifo = fifo
            self._close_fifo()
            return self.path
        self._fifo = fifo
        with contextlib.suppress(OSError):  # a bigger pipe: FFmpeg waits on the copy less
            import fcntl

            fcntl.fcntl(self._read_fd, _F_SETPIPE_SZ, _PIPE_BYTES)
        return fifo

    def _drain(self) -> bool:
        """Copy what the pipe holds to the file; False once FFmpeg has closed it. What the
        file cannot take (a full disk) is dropped, the pipe still emptied (FFmpeg would wait
        on it for good): the NUT then lacks frames, which :meth:`to_mp4`'s reader finds."""
        with self._lock:
            while True:
                try:
                    data = os.read(self._read_fd, _PIPE_BYTES)
                except BlockingIOError:
                    return True
                if not data:
                    return False
                view = memoryview(data)
                while view and not self.failed:
                    try:
                        view = view[self._file.write(view) :]
                    except OSError:
                        self.failed = True

    def _copy(self) -> None:
        """The copying thread: FFmpeg blocks on a full pipe while it writes a frame (one frame
        of a large video is more than the pipe holds), so the pipe is emptied as it fills;
        until FFmpeg closes it."""
        while True:
            select.select([self._read_fd], [], [])
            if not self._drain():
                return

    def write(self, bgr: np.ndarray) -> None:
        """Encode one frame; its bytes are in the file when this returns (through the FIFO)."""
        self._writer.write(bgr)
        self.frames += 1
        if self._thread is not None:
            self._drain()

    def release(self) -> None:
        """Finish the NUT file (the writer released, the pipe copied to its end, the FIFO
        removed); again does nothing."""
        if self._writer is not None:
            self._writer.release()
            self._writer = None
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self._close_fifo()

    def _close_fifo(self) -> None:
        if self._read_fd >= 0:
            os.close(self._read_fd)
            self._read_fd = -1
        if self._file is not None:
            self._file.close()
            self._file = None
        if self._fifo is not None:
            self._fifo.unlink(missing_ok=True)
            self._fifo = None

    def to_mp4(self, mp4: Path) -> None:
        """Write the frames recorded to the MP4 file ``mp4`` (a name ending in ``.mp4``),
        their encoded bytes copied from the NUT file, not encoded again (each frame's key
        frame mark kept; the stream's header, the MPEG-4 decoder's configuration, given with
        the first frame, as OpenCV's encapsulation takes it). Released first. Raises
        DataError when it cannot be written."""
        self.release()
        cap = cv2.VideoCapture(str(self.path), cv2.CAP_FFMPEG, [cv2.CAP_PROP_FORMAT, -1])
        # a key frame interval other than 1 (at 1, OpenCV marks every frame a key frame),
        # each frame's own mark then given with it
        params = [cv2.VIDEOWRITER_PROP_RAW_VIDEO, 1, cv2.VIDEOWRITER_PROP_KEY_INTERVAL, 1 << 30]
        out = cv2.VideoWriter(str(mp4), cv2.CAP_FFMPEG, FOURCC, self.fps, self.size, params)
        try:
            if not cap.isOpened() or not out.isOpened():  # a full disk cut the NUT file short
                seen = "the video could not be copied to MP4"
                raise DataError(cannot_write(write_failure(self.path), seen), self.what)
            ok, header = cap.retrieve(None, int(cap.get(cv2.CAP_PROP_CODEC_EXTRADATA_INDEX)))
            first = header.reshape(-1) if ok and header is not None else np.empty(0, np.uint8)
            while True:
                ok, packet = cap.read()
                if not ok:
                    break
                if first.size:
                    packet = np.concatenate([first, packet.reshape(-1)])[np.newaxis]
                    first = first[:0]
                out.set(cv2.VIDEOWRITER_PROP_KEY_FLAG, cap.get(cv2.CAP_PROP_LRF_HAS_KEY_FRAME))
                out.write(packet)
        finally:
            out.release()
            cap.release()
