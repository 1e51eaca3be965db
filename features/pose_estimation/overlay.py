"""Draw the estimated stick figure (and, when given, fluent words) onto a video for a person
to check. Written to a temporary name and renamed, so no half-written file is left."""

from __future__ import annotations

import functools
import os
import re
import struct
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from features.errors import DataError
from features.fileio import atomic_path, cannot_write, write_failure

from .video import iter_frames

# BlazePose topology (MediaPipe's POSE_CONNECTIONS), by landmark index.
POSE_CONNECTIONS: tuple[tuple[int, int], ...] = (
    (0, 1), (1, 2), (2, 3), (3, 7), (0, 4), (4, 5), (5, 6), (6, 8), (9, 10),
    (11, 12), (11, 13), (13, 15), (15, 17), (15, 19), (15, 21), (17, 19),
    (12, 14), (14, 16), (16, 18), (16, 20), (16, 22), (18, 20),
    (11, 23), (12, 24), (23, 24), (23, 25), (24, 26), (25, 27), (26, 28),
    (27, 29), (28, 30), (29, 31), (30, 32), (27, 31), (28, 32),
)  # fmt: skip
# The person's left side drawn orange, right side blue, centre white (BGR).
_LEFT = {1, 2, 3, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31}
_RIGHT = {4, 5, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30, 32}
_COLOURS = {"left": (0, 140, 255), "right": (255, 128, 0), "centre": (255, 255, 255)}
NO_PERSON = "no person"
"""Said on a frame in which the model found no one."""
NO_FRAMES = "no frames in the video"
"""Said on a grid time inside a gap of the video's frames (none decoded there: the frame before
the gap stays on screen), as ``segment`` and ``watch`` call such a stretch
(``cbr.segmentation.NO_FRAMES``), not "no person"."""


def _colour(i: int, j: int) -> tuple[int, int, int]:
    if i in _LEFT and j in _LEFT:
        return _COLOURS["left"]
    if i in _RIGHT and j in _RIGHT:
        return _COLOURS["right"]
    return _COLOURS["centre"]


def draw_pose(
    bgr: np.ndarray,
    image_landmarks: np.ndarray,
    words: Sequence[str] = (),
    min_visibility: float = 0.5,
    nobody: str = NO_PERSON,
) -> np.ndarray:
    """Draw one frame's landmarks ``(33, 5)`` (x px, y px, z, visibility, presence) in place.

    Bones with an end below ``min_visibility`` are drawn thin and grey (guessed, not seen);
    ``words`` are written in the top-left corner, after ``nobody`` when no landmark is there:
    white outlined in black, a :class:`Label` on a box of its colour; a word too wide for
    the frame broken into lines (:func:`_lines`), a line that would run off its foot left out.
    """
    h, w = bgr.shape[:2]
    thick = max(2, round(min(h, w) / 240))
    if not np.isnan(image_landmarks[:, :2]).all():
        xy = np.round(image_landmarks[:, :2]).astype(np.int64)
        vis = image_landmarks[:, 3]
        for i, j in POSE_CONNECTIONS:
            seen = vis[i] >= min_visibility and vis[j] >= min_visibility
            colour = _colour(i, j) if seen else (128, 128, 128)
            cv2.line(
                bgr, tuple(map(int, xy[i])), tuple(map(int, xy[j])), colour,
                thick if seen else 1, cv2.LINE_AA,
            )  # fmt: skip
        for k in range(xy.shape[0]):
            if vis[k] >= min_visibility:
                cv2.circle(bgr, tuple(map(int, xy[k])), thick + 1, (0, 0, 255), -1, cv2.LINE_AA)
    else:
        words = [nobody, *words]
    scale = max(0.6, min(h, w) / 600)
    size = round(19 * scale)
    left = min(12, w // 20)
    room = w - 2 * left  # as wide a margin on the right: no word runs past the edge
    n = 0
    for word in words:
        for line, line_size in _lines(str(word), size, room):
            baseline = int((n + 1) * 30 * scale)
            outline, _fill, ascent = _masks(line, line_size)
            if baseline - ascent + outline.shape[0] > h:
                return bgr  # below the frame's foot: left out, not drawn cut
            text = Label(line, word.colour) if isinstance(word, Label) else line
            _write(bgr, text, (left, baseline), line_size / 19)
            n += 1
    return bgr


class Label(str):
    """A word drawn on a box of its own colour (``colour``: RGB, 0-255), its letters black or
    white, whichever stands out more on it: ``segment --overlay`` and ``watch --out`` write
    the activity so, in its colour of ``segment --plot``'s bands (unknown grey), and the box
    keeps it legible on light and dark frames alike. Compares and prints as its text."""

    colour: tuple[int, int, int]

    def __new__(cls, text: str, colour: Sequence[int]) -> Label:
        label = super().__new__(cls, text)
        label.colour = (int(colour[0]), int(colour[1]), int(colour[2]))
        return label


@functools.lru_cache(maxsize=256)
def _lines(text: str, size: int, room: int) -> tuple[tuple[str, int], ...]:
    """``text`` as lines of at most ``room`` pixels, each with its font size: whole when it
    fits at ``size``; else broken after spaces, underscores and hyphens (an activity named in
    44 letters joined by underscores ran past the right edge of frames narrower than about
    260 pixels); a piece still too wide is written smaller (down
    to :data:`_SMALLEST` pixels), and cut short with "…" when even that is too wide."""
    if _width(text, size) <= room:
        return ((text, size),)
    pieces = re.findall(r"[^ _-]*[_-]| *[^ _-]+| +", text)
    lines: list[str] = []
    for piece in pieces:
        joined = lines[-1] + piece if lines else piece
        if lines and _width(joined.rstrip(), size) <= room:
            lines[-1] = joined
        else:
            lines.append(piece.lstrip() if lines else piece)
    out = []
    for line in (part.rstrip() for part in lines):
        if not line:
            continue
        fitted = size
        while fitted > _SMALLEST and _width(line, fitted) > room:
            fitted -= 1
        while len(line) > 1 and _width(line, fitted) > room:
            line = line[:-2] + "…" if len(line) > 2 else line[:1]
        if _width(line, fitted) <= room:
            out.append((line, fitted))
    return tuple(out)


_SMALLEST = 8
"""The smallest font size (pixels) a word is shrunk to so that it fits its frame."""


def _width(text: str, size: int) -> int:
    """The width in pixels of ``text`` drawn at ``size`` (:func:`_masks`' columns)."""
    return int(_font(size).getlength(text)) + 2 * _stroke(size) + 2


def _stroke(size: int) -> int:
    """The width of the outline around letters of ``size`` pixels."""
    return max(1, round(size / 10))


@functools.lru_cache(maxsize=64)
def _font(size: int) -> Any:
    """DejaVu Sans at ``size`` pixels, as Pillow draws it."""
    import matplotlib
    from PIL import ImageFont

    return ImageFont.truetype(str(Path(matplotlib.get_data_path()) / _FONT), size)


def _write(bgr: np.ndarray, text: str, org: tuple[int, int], scale: float) -> None:
    """``text`` white outlined in black, its baseline starting at ``org``, in DejaVu Sans, the
    font matplotlib ships (:func:`_masks`): its outline and fill drawn from one layout, so
    they line up letter by letter. (OpenCV's own font advanced its letters further the
    thicker the stroke: the black outline, drawn 4 pixels thick, ran ahead of the 1-pixel
    white letters, "repetitions: 1" read as a smudge with the fill 17 pixels short of the
    outline at 1920x1080; and it has ASCII only, "élévation" came out with "?".) A
    :class:`Label` is written on a box of its colour instead."""
    size = round(19 * scale)
    if isinstance(text, Label):
        box, ascent = _boxed(str(text), size, text.colour)
        _paste(bgr, org, ascent, box.shape[:2], lambda _region, cut: box[cut])
        return
    keep, add, ascent = _layers(text, size)
    _paste(bgr, org, ascent, keep.shape[:2], lambda region, cut: region * keep[cut] + add[cut])


def _paste(
    bgr: np.ndarray, org: tuple[int, int], ascent: int, shape: tuple[int, ...], blend: Any
) -> None:
    """``blend(region, cut)`` written over the part within ``bgr`` of a text's rectangle of
    ``shape``, its baseline starting at ``org``; ``cut``: that part's rows and columns in the
    rectangle."""
    top, left = org[1] - ascent, org[0]
    h, w = bgr.shape[:2]
    y0, x0 = max(0, top), max(0, left)
    y1, x1 = min(h, top + shape[0]), min(w, left + shape[1])
    if y1 <= y0 or x1 <= x0:
        return
    cut = (slice(y0 - top, y1 - top), slice(x0 - left, x1 - left))
    region = blend(bgr[y0:y1, x0:x1], cut)
    bgr[y0:y1, x0:x1] = np.round(region).astype(bgr.dtype)


@functools.lru_cache(maxsize=256)
def _boxed(text: str, size: int, colour: tuple[int, int, int]) -> tuple[np.ndarray, int]:
    """``text`` at ``size`` on a box of ``colour`` (RGB) the size of its :func:`_masks`, as
    BGR ``(height, width, 3)``, and the baseline's row in it: the letters black or white,
    whichever contrasts more with the box (WCAG's ratio of relative luminances); edged in
    black, so a light box (unknown's grey) keeps its shape on a light frame."""
    _outline, fill, ascent = _masks(text, size)
    lum = _luminance(colour)
    ink = 0.0 if (lum + 0.05) / 0.05 >= 1.05 / (lum + 0.05) else 255.0
    box = np.empty((*fill.shape, 3), dtype=np.float32)
    box[:] = colour[::-1]
    box = box * (1.0 - fill[:, :, None]) + ink * fill[:, :, None]
    edged = np.zeros_like(box)
    edge = max(1, size // 20)
    edged[edge:-edge, edge:-edge] = box[edge:-edge, edge:-edge]
    return np.round(edged).astype(np.uint8), ascent


def _luminance(rgb: tuple[int, int, int]) -> float:
    """WCAG's relative luminance of an sRGB colour (0-255)."""
    c = np.asarray(rgb, dtype=float) / 255.0
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])


@functools.lru_cache(maxsize=256)
def _layers(text: str, size: int) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_masks` as one blend, ``pixel * keep + add`` ``(height, width, 1)``: the black
    outline laid over the frame, then the white letters over both (one pass per word and
    frame, as a stream draws its label and fluent words on every frame)."""
    outline, fill, ascent = _masks(text, size)
    keep = ((1.0 - outline) * (1.0 - fill))[:, :, None].astype(np.float32)
    add = (255.0 * fill)[:, :, None].astype(np.float32)
    return keep, add, ascent


@functools.lru_cache(maxsize=256)
def _masks(text: str, size: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The outline and the fill of ``text`` in DejaVu Sans at ``size`` pixels, as coverage
    ``(height, width)`` in [0, 1], and the baseline's row in them; drawn once per text and
    size (a stream's labels and fluent words repeat)."""
    from PIL import Image, ImageDraw

    font = _font(size)
    stroke = _stroke(size)
    ascent, descent = font.getmetrics()
    width = _width(text, size)
    height = ascent + descent + 2 * stroke
    out = []
    for wide in (stroke, 0):
        image = Image.new("L", (width, height), 0)
        ImageDraw.Draw(image).text(
            (stroke, stroke + ascent), text, font=font, fill=255, anchor="ls",
            stroke_width=wide, stroke_fill=255,
        )  # fmt: skip
        out.append(np.asarray(image, dtype=np.float32) / 255.0)
    return out[0], out[1], stroke + ascent


_FONT = "fonts/ttf/DejaVuSans.ttf"
"""The font of every word an overlay writes, within matplotlib's data (a dependency)."""


MAX_MP4_SIDE = 8191
"""The widest and highest frame the MP4 encoder (``mp4v``, MPEG-4 part 2: 13-bit sizes) takes."""
MIN_MP4_SIDE = 2
"""The narrowest and lowest frame it takes (OpenCV's writer does not open for 1 pixel)."""


def check_mp4_size(width: int, height: int, out: str | Path, what: str = "overlay") -> None:
    """DataError naming ``out`` when frames of ``width`` x ``height`` cannot be encoded as an
    MP4 (:data:`MIN_MP4_SIDE` to :data:`MAX_MP4_SIDE`, an odd side once padded to even:
    :func:`even_size`): checked before the work, not found when the first frame is."""
    if width < MIN_MP4_SIDE or height < MIN_MP4_SIDE:
        raise DataError(
            f"cannot encode an MP4 {what} of {width}x{height} frames: MP4 frames are at least"
            f" {MIN_MP4_SIDE} pixels a side",
            out,
        )
    if max(even_size(width, height)) > MAX_MP4_SIDE:
        odd = "" if max(width, height) > MAX_MP4_SIDE else " and even (an odd side padded by one)"
        raise DataError(
            f"cannot encode an MP4 {what} of {width}x{height} frames: MP4 frames are at most"
            f" {MAX_MP4_SIDE} pixels a side{odd}",
            out,
        )


def even_size(width: int, height: int) -> tuple[int, int]:
    """The size an MP4 (``mp4v``) takes frames of ``width`` x ``height`` at: each side made even
    (MPEG-4 part 2 codes 2x2 chroma blocks; OpenCV's writer took a side one pixel shorter,
    the source's last column or row cut off without a word)."""
    return width + width % 2, height + height % 2


def padding_words(width: int, height: int) -> str:
    """What an MP4 of frames of ``width`` x ``height`` says of their padding
    (:func:`pad_even`), "" when they need none."""
    w, h = even_size(width, height)
    edges = [
        e
        for e, odd in (("column at the right", w > width), ("row at the bottom", h > height))
        if odd
    ]
    if not edges:
        return ""
    return (
        f"{width}x{height} frames written {w}x{h}, a black {' and '.join(edges)} added"
        " (MP4 frames have even sides)"
    )


def pad_even(bgr: np.ndarray) -> np.ndarray:
    """``bgr`` with a black column at the right and a row at the bottom where its width or
    height is odd (:func:`even_size`): every pixel of the source kept where it was, so the
    drawn landmarks stay on the person."""
    h, w = bgr.shape[:2]
    if not (h % 2 or w % 2):
        return bgr
    return cv2.copyMakeBorder(bgr, 0, h % 2, 0, w % 2, cv2.BORDER_CONSTANT, value=(0, 0, 0))


def mp4_rate(fps: float) -> Fraction:
    """The frame rate ``fps`` as the fraction it stands for: a video's rate read as a float
    (30000/1001 is 29.97002997...) given back exactly, the nearest fraction of a denominator
    up to a million (any two such differ by more than a float's error)."""
    return Fraction(fps).limit_denominator(1_000_000)


def retime_mp4(path: Path, fps: float) -> None:
    """Give the frames of the MP4 ``path`` that OpenCV wrote at ``fps`` their times at
    exactly :func:`mp4_rate` of it. OpenCV's writer takes a float and keeps it to a
    power-of-ten denominator within 0.001 fps: 30000/1001 was written as 2997/100, an
    overlay drifting 0.0036 s an hour from its source. The track's time scale, its frames'
    durations (one entry of the ``stts`` box) and the durations of ``mvhd``, ``tkhd``,
    ``elst`` and ``mdhd`` are rewritten in place; the frames are untouched. A file of another
    layout (several durations, composition offsets, a value too wide for its field) is left
    as it was written."""
    rate = mp4_rate(fps)
    with open(path, "r+b") as f:
        end, at = os.fstat(f.fileno()).st_size, 0
        while at + 8 <= end:
            f.seek(at)
            size, kind = struct.unpack(">I4s", f.read(8))
            if size < 8:
                return
            if kind == b"moov":
                f.seek(at)
                moov = bytearray(f.read(size))
                if _retimed(moov, rate):
                    f.seek(at)
                    f.write(moov)
                return
            at += size


_CONTAINERS = {b"moov", b"trak", b"edts", b"mdia", b"minf", b"stbl"}


def _boxes(data: bytearray, start: int, stop: int) -> dict[bytes, list[int]]:
    """The offsets of the boxes of ``data[start:stop]`` and of those inside them, by type."""
    found: dict[bytes, list[int]] = {}
    at = start
    while at + 8 <= stop:
        size, kind = struct.unpack_from(">I4s", data, at)
        if size < 8 or at + size > stop:
            break
        found.setdefault(kind, []).append(at)
        if kind in _CONTAINERS:
            for k, v in _boxes(data, at + 8, at + size).items():
                found.setdefault(k, []).extend(v)
        at += size
    return found


def _retimed(moov: bytearray, rate: Fraction) -> bool:
    """``moov`` (one video track) with its frames at ``rate`` (:func:`retime_mp4`); False when
    it is at that rate already or cannot be rewritten so."""
    boxes = _boxes(moov, 8, len(moov))
    if not _plain(moov, boxes):
        return False
    mvhd, tkhd, mdhd, stts = (boxes[k][0] for k in (b"mvhd", b"tkhd", b"mdhd", b"stts"))
    frames, delta = struct.unpack_from(">II", moov, stts + 16)
    track_scale = _field(moov, mdhd, 20, 28, widens=False)
    if Fraction(_value(moov, track_scale), delta) == rate:
        return False
    media = frames * rate.denominator
    movie_scale = _value(moov, _field(moov, mvhd, 20, 28, widens=False))
    movie = round(Fraction(media * movie_scale, rate.numerator))
    writes = [
        (track_scale, rate.numerator),
        (_field(moov, mdhd, 24, 32), media),
        ((stts + 20, False), rate.denominator),
        (_field(moov, mvhd, 24, 32), movie),
        (_field(moov, tkhd, 28, 36), movie),
        *((_field(moov, elst, 16, 16), movie) for elst in boxes.get(b"elst", [])),
    ]
    if any(value >= 2 ** (64 if wide else 32) for (_at, wide), value in writes):
        return False
    for (at, wide), value in writes:
        struct.pack_into(">Q" if wide else ">I", moov, at, value)
    return True


def _plain(moov: bytearray, boxes: dict[bytes, list[int]]) -> bool:
    """Whether ``moov`` is as OpenCV writes it, which :func:`_retimed` rewrites: one track,
    every frame of one duration (one ``stts`` entry), no composition offsets (``ctts``), at
    most one edit, from the first frame."""
    if any(len(boxes.get(k, [])) != 1 for k in (b"mvhd", b"tkhd", b"mdhd", b"stts")):
        return False
    stts = boxes[b"stts"][0]
    if struct.unpack_from(">I", moov, stts + 12)[0] != 1 or moov[stts + 20 : stts + 24] == bytes(4):
        return False
    edits = boxes.get(b"elst", [])
    if b"ctts" in boxes or len(edits) > 1:
        return False
    for elst in edits:  # its start is in the track's time scale: one from the first frame kept
        wide = moov[elst + 8] == 1
        start = struct.unpack_from(">q" if wide else ">i", moov, elst + (24 if wide else 20))[0]
        if struct.unpack_from(">I", moov, elst + 12)[0] != 1 or start > 0:
            return False
    return True


def _field(moov: bytearray, box: int, v0: int, v1: int, widens: bool = True) -> tuple[int, bool]:
    """The place in ``moov`` of a field at ``v0`` in a version-0 box at ``box``, ``v1`` in a
    version-1 box, and whether it is 64 bits wide (a duration in a version-1 box)."""
    wide = moov[box + 8] == 1
    return box + (v1 if wide else v0), wide and widens


def _value(moov: bytearray, field: tuple[int, bool]) -> int:
    at, wide = field
    return int(struct.unpack_from(">Q" if wide else ">I", moov, at)[0])


MARK_UUID = bytes.fromhex("cab5aa21f4394e688342e23fd7fa5c39")
"""The user type of the MP4 box (ISO/IEC 14496-12 ``uuid``: a user extension, which every
reader skips) that says which command drew an overlay of which video (:func:`mark_mp4`)."""


def mark_mp4(path: Path, mark: str) -> None:
    """Append to the MP4 file ``path`` a top-level ``uuid`` box of type :data:`MARK_UUID`
    holding ``mark`` (UTF-8), as a PNG picture holds its text chunk
    (:func:`features.timeline.picture_mark`): the frames, their index and every player are
    untouched (OpenCV writes no container metadata)."""
    data = mark.encode("utf-8")
    with open(path, "ab") as f:
        f.write(struct.pack(">I4s", 8 + len(MARK_UUID) + len(data), b"uuid") + MARK_UUID + data)


def mp4_mark(path: Path) -> str | None:
    """The mark :func:`mark_mp4` put in the MP4 file ``path``, found by walking its top-level
    boxes (their headers alone); None when it has none, is no MP4 (its first box no
    ``ftyp``) or cannot be read."""
    try:
        with open(path, "rb") as f:
            end, at = os.fstat(f.fileno()).st_size, 0
            while at + 8 <= end:
                f.seek(at)
                size, kind = struct.unpack(">I4s", f.read(8))
                head = 8
                if size == 1:  # a 64-bit size follows
                    (size,), head = struct.unpack(">Q", f.read(8)), 16
                elif size == 0:  # to the end of the file
                    size = end - at
                if (at == 0 and kind != b"ftyp") or size < head:
                    return None
                if kind == b"uuid" and 16 <= size - head <= 4096:
                    body = f.read(size - head)
                    if body[:16] == MARK_UUID:
                        return body[16:].decode("utf-8", "replace")
                at += size
    except (OSError, struct.error):
        return None
    return None


def write_overlay(
    video_path: str | Path,
    image_landmarks: np.ndarray,
    out_path: str | Path,
    fps: float,
    words: Sequence[Sequence[str]] | None = None,
    frame_offset: int = 0,
    video_frames: np.ndarray | None = None,
    gaps: np.ndarray | None = None,
    mark: str | None = None,
) -> Path:
    """Write ``video_path`` with the stick figure drawn as an MP4 (``mp4v``) at ``out_path``,
    its frames at exactly ``fps`` (:func:`retime_mp4`), an odd side padded to even
    (:func:`pad_even`; :func:`padding_words` says so).

    image_landmarks: ``(frames, 33, 5)``; frame ``frame_offset + i`` of the video gets row i,
    or with ``video_frames`` (a variable-frame-rate video resampled to ``fps``:
    :attr:`~features.pose_estimation.video.VideoPoses.video_frames`), frame
    ``video_frames[i]`` does (a frame may carry several rows, or none), so the overlay plays
    at ``fps`` in step with the video. words: per row, phrases to print (e.g. the fluents
    that hold). gaps: per row, whether it lies inside a gap of the video's frames
    (:func:`features.poses.gap_rows`): such a row says :data:`NO_FRAMES`, not "no person".
    mark: what the overlay is marked with (:func:`mark_mp4`), if anything.
    """
    out = Path(out_path)
    rows = None if video_frames is None else np.asarray(video_frames, dtype=np.int64)
    # The temporary name ends in .mp4: OpenCV picks the container by the file name.
    with atomic_path(out, suffix=".mp4") as tmp:
        _encode(video_path, image_landmarks, tmp, out, fps, words, frame_offset, rows, gaps)
        if mark is not None:
            mark_mp4(tmp, mark)
    return out


def _encode(
    video_path: str | Path,
    image_landmarks: np.ndarray,
    tmp: Path,
    out: Path,
    fps: float,
    words: Sequence[Sequence[str]] | None,
    frame_offset: int,
    video_frames: np.ndarray | None = None,
    gaps: np.ndarray | None = None,
) -> None:
    """The frames of ``video_path`` with the stick figure drawn, encoded into ``tmp``
    (``out`` names the overlay in messages); see :func:`write_overlay`."""
    writer: cv2.VideoWriter | None = None
    written = 0
    try:
        n = image_landmarks.shape[0]
        if video_frames is None:  # row i on frame frame_offset + i
            video_frames = np.arange(n) + frame_offset
        first = 0  # the first row not yet drawn
        for k, rgb in enumerate(iter_frames(video_path)):
            if first >= n:
                break
            stop = first + int(np.searchsorted(video_frames[first:], k, side="right"))
            if stop == first:
                continue
            for i in range(first, stop):
                bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
                if writer is None:
                    h, w = bgr.shape[:2]
                    check_mp4_size(w, h, out)
                    fourcc = cv2.VideoWriter.fourcc(*"mp4v")
                    writer = cv2.VideoWriter(str(tmp), fourcc, fps, even_size(w, h))
                    if not writer.isOpened():
                        raise DataError("cannot encode an MP4 overlay here", out)
                said = words[i] if words is not None else ()
                _draw_row(bgr, image_landmarks[i], said, gaps is not None and bool(gaps[i]))
                writer.write(pad_even(bgr))
                written += 1
            first = stop
        if writer is None:
            raise DataError("no frames to draw", video_path)
    finally:
        if writer is not None:
            writer.release()
    retime_mp4(tmp, fps)
    check_encoded(tmp, written, out)


def _draw_row(bgr: np.ndarray, landmarks: np.ndarray, words: Sequence[str], gap: bool) -> None:
    """One row of the overlay drawn; ``gap``: it lies inside a gap of the video's frames (no
    frame there, not a frame without a person), said :data:`NO_FRAMES` once."""
    if gap:
        draw_pose(bgr, landmarks, [w for w in words if w != NO_FRAMES], nobody=NO_FRAMES)
    else:
        draw_pose(bgr, landmarks, words)


def check_encoded(path: Path, frames: int, out: Path) -> None:
    """Refuse a video file that does not read back with ``frames`` frames: OpenCV's writer only
    warns when a write fails (a full disk, a file size limit), so the file is checked before it
    is renamed into place. ``out`` names the output in the message, which says why the writes
    failed where writing more to the file fails too (:func:`features.fileio.cannot_write`):
    the disk full, as the case base store says it, or a file size limit."""
    cap = cv2.VideoCapture(str(path))
    try:
        found = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else 0
    finally:
        cap.release()
    if found == frames:
        return
    counts = f"{frames} frames encoded but {found} read back"
    raise DataError(cannot_write(write_failure(path), counts), out)
