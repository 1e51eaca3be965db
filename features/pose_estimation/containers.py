"""What a video file's own bytes say before it is decoded: whether it is cut short (a JPEG
without its end marker, a Matroska/WebM or FLV file ending inside an element or a tag, an
MP4/MOV file ending inside a box),
whether it holds sound alone (WAVE, FLAC, MP3, AAC, Ogg, or an MP4 or Matroska/WebM file of
sound tracks only), and whether OpenCV counts its frames from its duration (Matroska/WebM,
FLV, MPEG-TS), and how a still picture is turned to be seen (its EXIF orientation).
:mod:`features.pose_estimation.video` asks these before it trusts what OpenCV reports."""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError
from features.fileio import file_head, heif_brand, is_video

JPEG_START, JPEG_END = b"\xff\xd8\xff", b"\xff\xd9"
"""A JPEG file's start-of-image and end-of-image markers."""
EXIF_ORIENTATION = 0x0112
"""The EXIF tag saying how a picture is turned to be seen: 1 as stored, 2-8 flipped and/or
turned (6: a quarter turn clockwise, the portrait photo a phone stores sideways)."""
PICTURE_FORMATS = ("JPEG", "PNG", "TIFF", "WEBP")
"""The still-picture formats (Pillow's names) whose EXIF orientation is read (a camera's MPO
file opens as a JPEG)."""


def picture_orientation(source: Path | Any, head: bytes | None = None) -> int:
    """The EXIF orientation (1-8) of a still picture: a phone stores a portrait photo as its
    sensor took it, sideways, and says in this tag how a viewer turns it upright. FFmpeg,
    and so OpenCV's capture, decodes the picture as stored. ``source``: the picture's path,
    or a file read from its start (``seek``, ``read``, ``tell``: a served file,
    :class:`.served.ServedFile`) whose first bytes are ``head``. 1 for a file that is no
    picture of :data:`PICTURE_FORMATS` (a video), that has no such tag, or whose tag is no
    orientation. A file that starts as a video does (MP4, AVI, Matroska) is none of them,
    said without importing Pillow, which loads every format it reads to open one."""
    if is_video(file_head(source, 16) if head is None else head[:16]):
        return 1
    from PIL import Image

    Image.init()  # every format Pillow reads here registered (WebP only when built with it)
    formats = [name for name in PICTURE_FORMATS if name in Image.OPEN]
    try:
        with Image.open(source, formats=formats) as picture:
            value = picture.getexif().get(EXIF_ORIENTATION, 1)
    except (Image.DecompressionBombError, OSError, SyntaxError, ValueError):
        return 1  # no picture Pillow reads (a video, a damaged picture): OpenCV's verdict stands
    return value if isinstance(value, int) and 1 <= value <= 8 else 1


HeifTurn = tuple[str, tuple[int, ...]]
"""One of the transformative properties of a HEIF picture (ISO/IEC 23008-12), as
:func:`heif_shown` applies it: ("irot", (n,)), n quarter turns counter-clockwise; ("imir",
(axis,)), 0 upside down, 1 left to right; ("clap", (top, left, bottom, right)), the clean
aperture: the rows and columns kept (the bottom and right ones excluded)."""


@dataclass(frozen=True)
class HeifPicture:
    """A HEIF file's primary picture (its pitm item), as a viewer shows it: its brand
    (:func:`features.fileio.heif_brand`), width and height (px: its ispe property's, turned
    and cropped by its ``turns``), how many coded pictures it is made of (a grid's tiles: a
    phone's photo is 512x512 tiles put together; 1 for a picture coded whole), its
    transformative properties in the order its ipma box lists them (:data:`HeifTurn`,
    :func:`heif_shown`), its size as coded (its ispe property's width and height) and, where
    its colr box's nclx range differs from its coded stream's (:func:`heif_ranges`), the
    two (the stream's full range, the box's: :func:`heif_in_range`)."""

    brand: str
    width: int
    height: int
    tiles: int
    turns: tuple[HeifTurn, ...] = ()
    coded: tuple[int, int] = (0, 0)
    ranges: tuple[bool, bool] | None = None


HEIF_META_LIMIT = 16 << 20
"""The largest HEIF meta box (bytes) :func:`heif_picture` reads: a phone's photo's indexes
its tiles, thumbnail and Exif in some kilobytes."""


def heif_picture(fh: Any, size: int, head: bytes) -> HeifPicture | None:
    """The primary picture of a HEIF file (HEIC, AVIF: :func:`features.fileio.heif_brand` of
    its first bytes ``head``) of ``size`` bytes, read from ``fh``: the item its pitm box
    names, its size from its ispe property (a quarter turn by its irot property swaps width
    and height) and, for a grid, the tiles its dimg reference lists. None for a file that is
    no HEIF still or whose meta box cannot be read (no pitm, no ispe for it)."""
    brand = heif_brand(head)
    if brand is None:
        return None
    meta = _top_box(fh, size, b"meta", HEIF_META_LIMIT)
    if meta is None:
        return None
    boxes = {kind: (body, stop) for kind, body, stop in _mp4_boxes(meta, 4, len(meta))}
    if b"pitm" not in boxes or b"iprp" not in boxes:
        return None
    body, _ = boxes[b"pitm"]
    wide = meta[body] >= 1  # version 1: 32-bit item IDs
    primary = int.from_bytes(meta[body + 4 : body + (8 if wide else 6)], "big")
    listed = _heif_property_list(meta, *boxes[b"iprp"], primary)
    ispe = dict(listed).get(b"ispe")
    if ispe is None or len(ispe) < 12:
        return None
    coded = int.from_bytes(ispe[4:8], "big"), int.from_bytes(ispe[8:12], "big")
    turns, width, height = _heif_turns(listed, *coded)
    parts = _heif_derived_from(meta, boxes.get(b"iref"), primary)
    tile = _heif_property_list(meta, *boxes[b"iprp"], parts[0]) if parts else listed
    first = dict(tile)
    colr = next((b for n, b in [*listed, *tile] if n == b"colr" and b[:4] == b"nclx"), None)
    if colr is not None and len(first.get(b"av1C", b"")) == 4 and b"iloc" in boxes:
        # an av1C without the sequence header (libavif's): the coded picture's first OBUs
        places = _heif_locations(meta, *boxes[b"iloc"])
        item = parts[0] if parts else primary
        if item in places and places[item][0] == 0:
            at, n = places[item][1][0]
            fh.seek(at)
            first = {**first, b"av1C": first[b"av1C"] + bytes(fh.read(min(n, 1024)))}
    ranges = heif_ranges(colr, first)
    return HeifPicture(brand, width, height, len(parts) or 1, turns, coded, ranges)


def heif_ranges(colr: bytes | None, coded: dict[bytes, bytes]) -> tuple[bool, bool] | None:
    """Whether a HEIF picture's coded stream states full range (its configuration among the
    properties ``coded``: an hvcC's sequence parameter set's VUI, an av1C's sequence
    header; limited where it states none) and whether its colr box ``colr`` (the body)
    does, when the box is an nclx one that says otherwise; None when they agree, or either
    cannot be read. The box rules (ISO/IEC 23008-12; libheif and libavif decode by it), but
    FFmpeg decodes by the stream's."""
    if colr is None or len(colr) < 11 or colr[:4] != b"nclx":
        return None
    box = bool(colr[10] & 0x80)
    stream = (
        _hevc_full_range(coded[b"hvcC"])
        if b"hvcC" in coded
        else _av1_full_range(coded[b"av1C"])
        if b"av1C" in coded
        else None
    )
    return None if stream is None or stream == box else (stream, box)


def heif_in_range(image: np.ndarray, ranges: tuple[bool, bool] | None) -> np.ndarray:
    """``image`` (8-bit BGR), decoded in the range its coded stream states, as in the range
    its colr box states (:func:`heif_ranges`: the stream's full range, the box's; None: as
    it is): limited-range levels (16-235) FFmpeg stretched to 0-255 put back, or full-range
    levels it took as 0-255 stretched from 16-235. The colour's share is scaled as the
    grey's (its own scale differs by 2 %: 224 levels, not 219) and levels clipped in the
    decoding stay clipped."""
    if ranges is None:
        return image
    scale = 219.0 / 255.0
    levels = image.astype(np.float32)
    out = levels * scale + 16.0 if ranges[1] else (levels - 16.0) / scale
    ranged: np.ndarray = np.clip(np.rint(out), 0, 255).astype(np.uint8)
    return ranged


class _Bits:
    """A reader of the bits of a coded stream's header, most significant first."""

    def __init__(self, data: bytes) -> None:
        self.value, self.size, self.at = int.from_bytes(data, "big"), 8 * len(data), 0

    def read(self, n: int) -> int:
        if self.at + n > self.size:
            raise ValueError("past the end")
        self.at += n
        return (self.value >> (self.size - self.at)) & ((1 << n) - 1)

    def golomb(self) -> int:
        """An unsigned Exp-Golomb number (ue(v))."""
        zeros = 0
        while not self.read(1):
            zeros += 1
            if zeros > 31:
                raise ValueError("not a number")
        return (1 << zeros) - 1 + self.read(zeros)


def _hevc_full_range(config: bytes) -> bool | None:
    """The video_full_range_flag of the sequence parameter set in an hvcC box's ``config``
    (H.265 7.3.2.2, E.2.1): False where it has no VUI or no video signal type; None when
    there is no SPS or it cannot be read."""
    at = 23
    try:
        for _ in range(config[22] if len(config) > 22 else 0):
            kind, count = config[at] & 63, int.from_bytes(config[at + 1 : at + 3], "big")
            at += 3
            for _ in range(count):
                n = int.from_bytes(config[at : at + 2], "big")
                if kind == 33:  # SPS
                    return _sps_full_range(config[at + 2 : at + 2 + n])
                at += 2 + n
    except (ValueError, IndexError):  # cut short, or no SPS as H.265 has it
        return None
    return None


def _sps_full_range(unit: bytes) -> bool:
    """:func:`_hevc_full_range` of one SPS NAL unit (its two-byte header first)."""
    bits = _Bits(unit[2:].replace(b"\0\0\3", b"\0\0"))  # emulation prevention bytes out
    bits.read(4)
    layers = bits.read(3)
    _sps_layers(bits, layers)
    bits.golomb()  # its ID
    if bits.golomb() == 3:  # chroma format 4:4:4: separate colour planes
        bits.read(1)
    bits.golomb(), bits.golomb()  # width, height
    if bits.read(1):  # a conformance window
        for _ in range(4):
            bits.golomb()
    bits.golomb(), bits.golomb()  # bit depths
    poc_bits = bits.golomb() + 4
    for _ in range(9 + 3 * layers if bits.read(1) else 9):
        bits.golomb()  # sub-layer ordering; block sizes, transform hierarchy depths
    if bits.read(1) and bits.read(1):  # scaling lists, stated
        _scaling_lists(bits)
    bits.read(2)  # AMP, SAO
    if bits.read(1):  # PCM
        bits.read(8), bits.golomb(), bits.golomb(), bits.read(1)
    _short_term_sets(bits, bits.golomb())
    if bits.read(1):  # long-term reference pictures
        for _ in range(bits.golomb()):
            bits.read(poc_bits + 1)
    bits.read(2)  # temporal MVP, strong intra smoothing
    return bool(bits.read(1)) and _vui_full_range(bits)


def _sps_layers(bits: _Bits, layers: int) -> None:
    """Read past an SPS's temporal ID nesting flag and profile, tier and level (H.265 7.3.3)
    for ``layers`` sub-layers."""
    bits.read(1 + 88 + 8)
    present = [(bits.read(1), bits.read(1)) for _ in range(layers)]
    if layers:
        bits.read(2 * (8 - layers))
    for profile, level in present:
        bits.read(88 * profile + 8 * level)


def _scaling_lists(bits: _Bits) -> None:
    """Read past an SPS's scaling list data (H.265 7.3.4)."""
    for size in range(4):
        for _ in range(0, 6, 3 if size == 3 else 1):
            if not bits.read(1):
                bits.golomb()
                continue
            for _ in range(min(64, 1 << (4 + (size << 1))) + (size > 1)):
                bits.golomb()  # se(v): as long as ue(v)


def _vui_full_range(bits: _Bits) -> bool:
    """The video_full_range_flag of an SPS's VUI (H.265 E.2.1); False without a video
    signal type."""
    if bits.read(1) and bits.read(8) == 255:  # aspect ratio, stated as a fraction
        bits.read(32)
    if bits.read(1):  # overscan
        bits.read(1)
    if not bits.read(1):
        return False
    bits.read(3)
    return bool(bits.read(1))


def _short_term_sets(bits: _Bits, count: int) -> None:
    """Read past an SPS's ``count`` short-term reference picture sets (H.265 7.3.7)."""
    deltas: list[int] = []
    for i in range(count):
        if i and bits.read(1):  # predicted from the set before
            bits.read(1), bits.golomb()
            n = 0
            for _ in range(deltas[i - 1] + 1):
                used = bits.read(1)
                n += used or bits.read(1)
            deltas.append(n)
        else:
            negative, positive = bits.golomb(), bits.golomb()
            for _ in range(negative + positive):
                bits.golomb(), bits.read(1)
            deltas.append(negative + positive)


def _av1_full_range(config: bytes) -> bool | None:
    """The color_range of the sequence header OBU in an av1C box's ``config`` (AV1 5.5; the
    coded picture's OBUs after its four bytes where it holds none); None when there is none
    or it cannot be read."""
    at = 4
    while at + 2 <= len(config):
        header = config[at]
        kind, at = (header >> 3) & 15, at + 1 + bool(header & 4)  # an extension byte
        n, shift = len(config) - at, 0  # without a size: to the end
        while header & 2 and at < len(config):  # its size, leb128
            n = (n if shift else 0) | (config[at] & 127) << shift
            shift, at = shift + 7, at + 1
            if not config[at - 1] & 128:
                break
        if kind == 1:
            try:
                return _sequence_full_range(_Bits(config[at : at + n]))
            except ValueError:
                return None
        at += n
    return None


def _sequence_full_range(bits: _Bits) -> bool:
    """:func:`_av1_full_range` of a sequence header OBU's payload."""
    profile = bits.read(3)
    bits.read(1)  # still picture
    reduced = bool(bits.read(1))  # a reduced still picture header
    if reduced:
        bits.read(5)
    else:
        _operating_points(bits)
    width_bits, height_bits = bits.read(4) + 1, bits.read(4) + 1
    bits.read(width_bits + height_bits)
    if not reduced and bits.read(1):  # frame ID numbers
        bits.read(7)
    bits.read(3)  # 128x128 superblocks, filter intra, intra edge filter
    if not reduced:
        _inter_tools(bits)
    bits.read(3)  # superres, CDEF, restoration
    if bits.read(1) and profile == 2:  # high bit depth
        bits.read(1)
    mono = bool(bits.read(1)) if profile != 1 else False
    described = (bits.read(8), bits.read(8), bits.read(8)) if bits.read(1) else (2, 2, 2)
    return (not mono and described == (1, 13, 0)) or bool(bits.read(1))


def _operating_points(bits: _Bits) -> None:
    """Read past an AV1 sequence header's timing and operating points (AV1 5.5.1)."""
    decoder_model, delay_bits = False, 0
    if bits.read(1):  # timing info
        bits.read(64)
        if bits.read(1):  # equal picture interval
            bits.golomb()  # uvlc: as ue(v)
        decoder_model = bool(bits.read(1))
        if decoder_model:
            delay_bits = bits.read(5) + 1
            bits.read(32 + 5 + 5)
    display_model = bits.read(1)
    for _ in range(bits.read(5) + 1):
        bits.read(12)
        if bits.read(5) > 7:
            bits.read(1)
        if decoder_model and bits.read(1):
            bits.read(2 * delay_bits + 1)
        if display_model and bits.read(1):
            bits.read(4)


def _inter_tools(bits: _Bits) -> None:
    """Read past an AV1 sequence header's inter coding tools (AV1 5.5.1)."""
    bits.read(4)  # inter-intra, masked compound, warped motion, dual filter
    order_hint = bits.read(1)
    if order_hint:
        bits.read(2)
    if bits.read(1) or bits.read(1):  # screen content tools: chosen, or forced on
        if not bits.read(1):  # integer MV not chosen per frame
            bits.read(1)
    if order_hint:
        bits.read(3)


def _heif_turns(
    listed: list[tuple[bytes, bytes]], width: int, height: int
) -> tuple[tuple[HeifTurn, ...], int, int]:
    """The transformative properties among a picture's ``listed`` properties (name, body, in
    its ipma box's order), each as :func:`heif_shown` applies it to a picture of ``width`` x
    ``height`` px as coded, and the picture's width and height then. A clean aperture's
    window as libheif reckons it: centred at the picture's centre plus its offsets
    (fractions), its left edge rounded down, its top edge to the nearest (:func:`_c_round`),
    its width and height kept, cut to the picture; one that keeps nothing or cannot be read
    is left out (libheif refuses the file: the picture uncropped is posed)."""
    turns: list[HeifTurn] = []
    for name, body in listed:
        if name == b"irot" and body:
            turns.append(("irot", (body[0] & 3,)))
            if body[0] & 1:  # a quarter turn, one way or the other
                width, height = height, width
        elif name == b"imir" and body:
            turns.append(("imir", (body[0] & 1,)))
        elif name == b"clap":
            window = _clean_aperture(body, width, height)
            if window is None:
                continue
            turns.append(("clap", window))
            top, left, bottom, right = window
            width, height = right - left, bottom - top
    return tuple(turns), width, height


def _clean_aperture(body: bytes, width: int, height: int) -> tuple[int, int, int, int] | None:
    """The rows and columns (top, left, bottom, right; the last two excluded) a clap box's
    ``body`` keeps of a ``width`` x ``height`` picture (:func:`_heif_turns`); None when it
    keeps none or a fraction has no denominator."""
    if len(body) < 32:
        return None
    wide_n, wide_d, high_n, high_d = struct.unpack(">IIII", body[:16])
    x_n, x_d, y_n, y_d = struct.unpack(">iIiI", body[16:32])
    if not (wide_d and high_d and x_d and y_d):
        return None
    edges = []
    for size, (n, d), (off_n, off_d), nearest in (
        (width, (wide_n, wide_d), (x_n, x_d), False),
        (height, (high_n, high_d), (y_n, y_d), True),
    ):
        kept = Fraction(n, d)
        first = Fraction(off_n, off_d) + Fraction(size - 1, 2) - (kept - 1) / 2
        start = _c_round(first) if nearest else int(first)  # int: toward zero, as C divides
        last = _c_round(kept - 1 + start)
        start, last = max(start, 0), min(last, size - 1)
        if start > last:
            return None
        edges.append((start, last + 1))
    (left, right), (top, bottom) = edges
    return top, left, bottom, right


def _c_round(value: Fraction) -> int:
    """``value`` rounded as libheif rounds a fraction: half its denominator added to its
    numerator, then divided as C divides (toward zero)."""
    return int(Fraction(value.numerator + value.denominator // 2, value.denominator))


def heif_shown(image: np.ndarray, turns: Sequence[HeifTurn]) -> np.ndarray:
    """``image``, a HEIF picture as coded (a grid's put together), as a viewer shows it: its
    transformative properties ``turns`` (:data:`HeifTurn`) applied in order, as libheif
    applies them (ISO/IEC 23008-12 lists them in that order). A view where it can be."""
    for name, values in turns:
        if name == "irot":
            image = np.rot90(image, values[0])
        elif name == "imir":
            image = image[::-1] if values[0] == 0 else image[:, ::-1]
        else:
            top, left, bottom, right = values
            image = image[top:bottom, left:right]
    return image


@dataclass(frozen=True)
class HeifGrid:
    """A HEIF photo's primary picture made of tiles (a grid, as a phone stores a photo), to
    be decoded tile by tile and put together: ``stream``, its tiles coded one after another
    as one stream FFmpeg reads (``codec`` "hevc": an Annex B stream, each tile its parameter
    sets and its picture; "av1": an IVF file, each tile a frame), ``rows`` x ``columns``
    tiles of ``tile_width`` x ``tile_height`` px in rows from the top left, the picture the
    top-left ``width`` x ``height`` px of them, then turned and cropped as its ``turns`` say,
    in order (:data:`HeifTurn`, :func:`heif_shown`)."""

    codec: str
    stream: bytes
    rows: int
    columns: int
    tile_width: int
    tile_height: int
    width: int
    height: int
    turns: tuple[HeifTurn, ...]


HEIF_TILE_CODECS = {b"hvc1": "hevc", b"hev1": "hevc", b"av01": "av1"}
"""The tiles' codecs (a HEIF item's type) :func:`heif_grid` puts in a stream: HEVC (a HEIC,
an iPhone's photo) and AV1 (an AVIF)."""
HEIF_TILES_LIMIT = 256 << 20
"""The most bytes :func:`heif_grid` reads of a grid's tiles (a phone's 48-megapixel photo
takes some 10 MB)."""


def heif_grid(fh: Any, size: int, head: bytes) -> HeifGrid | None:
    """The primary picture of a HEIF file (:func:`heif_picture`: ``size`` bytes, its first
    bytes ``head``, read from ``fh``) when it is a grid of tiles (its item type ``grid``)
    coded in HEVC or AV1 (:data:`HEIF_TILE_CODECS`), each tile's bytes read from the file
    (its iloc extents, or its idat box), all in one read. None for any other picture: coded
    whole, tiles of another codec, of sizes that differ, fewer than the grid's rows and
    columns, a layout or index that cannot be read."""
    if heif_brand(head) is None:
        return None
    meta = _top_box(fh, size, b"meta", HEIF_META_LIMIT)
    if meta is None:
        return None
    boxes = {kind: (body, stop) for kind, body, stop in _mp4_boxes(meta, 4, len(meta))}
    if not {b"pitm", b"iprp", b"iinf", b"iloc", b"iref"} <= boxes.keys():
        return None
    body, _ = boxes[b"pitm"]
    primary = int.from_bytes(meta[body + 4 : body + (8 if meta[body] >= 1 else 6)], "big")
    tiles = _heif_derived_from(meta, boxes[b"iref"], primary)
    coded = _heif_tiles(meta, boxes, primary, tiles)
    places = _heif_locations(meta, *boxes[b"iloc"])
    if coded is None or any(item not in places for item in [primary, *tiles]):
        return None
    codec, configs, tile_width, tile_height = coded
    idat = meta[slice(*boxes[b"idat"])] if b"idat" in boxes else b""
    data = _heif_items(fh, size, idat, [places[item] for item in [primary, *tiles]])
    layout = None if data is None else _grid_layout(data[0])
    if data is None or layout is None or layout[0] * layout[1] != len(tiles):
        return None
    rows, columns, width, height = layout
    if not (0 < width <= columns * tile_width and 0 < height <= rows * tile_height):
        return None
    stream = (
        _av1_stream(configs, data[1:], tile_width, tile_height)
        if codec == "av1"
        else _hevc_stream(configs, data[1:])
    )
    if stream is None:
        return None
    turns, _, _ = _heif_turns(_heif_property_list(meta, *boxes[b"iprp"], primary), width, height)
    return HeifGrid(codec, stream, rows, columns, tile_width, tile_height, width, height, turns)


def _heif_tiles(
    meta: bytes, boxes: dict[bytes, tuple[int, int]], primary: int, tiles: list[int]
) -> tuple[str, list[bytes], int, int] | None:
    """The codec (:data:`HEIF_TILE_CODECS`), configurations (each tile's hvcC or av1C
    property's body) and width and height (px) of the ``tiles`` a HEIF meta's item
    ``primary``, a grid, is made of (its ``boxes``: name, where its body starts and ends);
    None when it is no grid, or its tiles are of another codec, or of sizes that differ."""
    types = _heif_item_types(meta, *boxes[b"iinf"])
    kinds = {types.get(tile) for tile in tiles}
    if types.get(primary) != b"grid" or len(kinds) != 1 or kinds - HEIF_TILE_CODECS.keys():
        return None
    codec = HEIF_TILE_CODECS[kinds.pop() or b""]
    props = [_heif_properties(meta, *boxes[b"iprp"], tile) for tile in tiles]
    sizes = {p.get(b"ispe", b"")[4:12] for p in props}
    config = b"av1C" if codec == "av1" else b"hvcC"
    if len(sizes) != 1 or any(config not in p for p in props):
        return None
    width, height = struct.unpack(">II", sizes.pop().rjust(8, b"\0"))
    if not width * height:
        return None
    return codec, [p[config] for p in props], width, height


def _heif_item_types(meta: bytes, start: int, end: int) -> dict[int, bytes]:
    """Each item's type (``hvc1``, ``av01``, ``grid``, ``Exif``) by its ID, from a HEIF
    meta's iinf box (``meta[start:end]``)."""
    count_bytes = 2 if meta[start] == 0 else 4
    types: dict[int, bytes] = {}
    for kind, body, stop in _mp4_boxes(meta, start + 4 + count_bytes, end):
        version = meta[body]
        if kind != b"infe" or version < 2:
            continue
        id_bytes = 2 if version == 2 else 4
        at = body + 4 + id_bytes + 2  # its ID, protection index
        if at + 4 <= stop:
            types[int.from_bytes(meta[body + 4 : body + 4 + id_bytes], "big")] = meta[at : at + 4]
    return types


def _heif_locations(
    meta: bytes, start: int, end: int
) -> dict[int, tuple[int, list[tuple[int, int]]]]:
    """Where each item's bytes are, by its ID, from a HEIF meta's iloc box
    (``meta[start:end]``): its construction method (0: in the file, 1: in the idat box) and
    its extents (offset, length), its base offset added. An item whose bytes are elsewhere
    (another method, a length 0: "to the end") is left out."""
    version = meta[start]
    sizes = meta[start + 4], meta[start + 5]
    offset_n, length_n, base_n = sizes[0] >> 4, sizes[0] & 15, sizes[1] >> 4
    index_n = sizes[1] & 15 if version in (1, 2) else 0
    id_n = 2 if version < 2 else 4
    at, found = start + 6 + id_n, {}

    def number(n: int) -> int:
        nonlocal at
        value = int.from_bytes(meta[at : at + n], "big")
        at += n
        return value

    count = int.from_bytes(meta[start + 6 : start + 6 + id_n], "big")
    for _ in range(count):
        if at > end:
            break
        item = number(id_n)
        method = number(2) & 15 if version in (1, 2) else 0
        number(2)  # data reference index: 0, this file
        base = number(base_n)
        extents = []
        for _ in range(number(2)):
            number(index_n)
            offset, length = number(offset_n), number(length_n)
            extents.append((base + offset, length))
        if at <= end and method in (0, 1) and extents and all(n for _, n in extents):
            found[item] = (method, extents)
    return found


def _heif_items(
    fh: Any, size: int, idat: bytes, places: list[tuple[int, list[tuple[int, int]]]]
) -> list[bytes] | None:
    """The bytes of items at ``places`` (:func:`_heif_locations`), those in the file read
    from ``fh`` (of ``size`` bytes) in one read from the first to the last; None when one
    lies past the file's end or the idat box, or they span more than
    :data:`HEIF_TILES_LIMIT`."""
    spans = [(at, at + n) for method, extents in places if method == 0 for at, n in extents]
    first = min((a for a, _ in spans), default=0)
    last = max((b for _, b in spans), default=0)
    if last > size or last - first > HEIF_TILES_LIMIT:
        return None
    fh.seek(first)
    read = bytes(fh.read(last - first)) if spans else b""
    if len(read) < last - first:
        return None
    items = []
    for method, extents in places:
        source, shift = (read, first) if method == 0 else (idat, 0)
        if any(at - shift + n > len(source) or at < shift for at, n in extents):
            return None
        items.append(b"".join(source[at - shift : at - shift + n] for at, n in extents))
    return items


def _grid_layout(data: bytes) -> tuple[int, int, int, int] | None:
    """A grid item's rows, columns, and picture width and height (px), from its bytes
    (version, flags: 1 for 32-bit sizes, rows less one, columns less one, width, height)."""
    if len(data) < 8 or data[0] != 0:
        return None
    n = 4 if data[1] & 1 else 2
    if len(data) < 4 + 2 * n:
        return None
    width = int.from_bytes(data[4 : 4 + n], "big")
    height = int.from_bytes(data[4 + n : 4 + 2 * n], "big")  # not the bytes after it
    return data[2] + 1, data[3] + 1, width, height


def _hevc_stream(configs: list[bytes], tiles: list[bytes]) -> bytes | None:
    """HEVC tiles (each its hvcC property's body and its coded bytes, NAL units each after
    its length) as one Annex B stream: each tile's parameter sets (from its hvcC) and NAL
    units after start codes. None for a configuration that cannot be read."""
    out: list[bytes] = []
    for config, data in zip(configs, tiles, strict=True):
        if len(config) < 23:
            return None
        size, at, units = (config[21] & 3) + 1, 23, []
        for _ in range(config[22]):
            count, at = int.from_bytes(config[at + 1 : at + 3], "big"), at + 3
            for _ in range(count):
                n = int.from_bytes(config[at : at + 2], "big")
                units.append(config[at + 2 : at + 2 + n])
                at += 2 + n
        if at > len(config):
            return None
        at = 0
        while at + size <= len(data):
            n = int.from_bytes(data[at : at + size], "big")
            units.append(data[at + size : at + size + n])
            at += size + n
        out.extend(b"\0\0\0\1" + unit for unit in units)
    return b"".join(out)


def _av1_stream(configs: list[bytes], tiles: list[bytes], width: int, height: int) -> bytes | None:
    """AV1 tiles (each its av1C property's body and its coded bytes) as one IVF file, each
    tile a frame: a temporal delimiter, the sequence header its av1C holds, its bytes."""
    if any(len(config) < 4 for config in configs):
        return None
    header = struct.pack(
        "<4sHH4sHHIIII", b"DKIF", 0, 32, b"AV01", width, height, 1, 1, len(tiles), 0
    )
    frames = [b"\x12\x00" + config[4:] + data for config, data in zip(configs, tiles, strict=True)]
    return header + b"".join(
        struct.pack("<IQ", len(frame), k) + frame for k, frame in enumerate(frames)
    )


def _top_box(
    fh: Any, size: int, name: bytes, limit: int, allowed: frozenset[bytes] | None = None
) -> bytes | None:
    """The body of the first top-level box ``name`` of an ISO base media file of ``size``
    bytes, read from ``fh``; None when there is none, it is larger than ``limit``, or a box
    before it is not one of ``allowed`` (any when None)."""
    at = 0
    while at + 8 <= size:
        fh.seek(at)
        header = fh.read(16)
        stated, kind, length = int.from_bytes(header[:4], "big"), header[4:8], 8
        if stated == 1 and len(header) == 16:
            stated, length = int.from_bytes(header[8:16], "big"), 16
        elif stated == 0:
            stated = size - at
        if stated < length or (allowed is not None and kind not in allowed):
            return None
        if kind == name:
            if stated > limit:
                return None
            fh.seek(at + length)
            return bytes(fh.read(stated - length))
        at += stated
    return None


def _heif_properties(meta: bytes, start: int, end: int, item: int) -> dict[bytes, bytes]:
    """The properties (name: body) the ipma box in a HEIF meta's iprp box (``meta[start:end]``)
    associates with ``item`` (:func:`_heif_property_list`)."""
    return dict(_heif_property_list(meta, start, end, item))


def _heif_property_list(meta: bytes, start: int, end: int, item: int) -> list[tuple[bytes, bytes]]:
    """The properties (name, body) the ipma box in a HEIF meta's iprp box (``meta[start:end]``)
    associates with ``item``, from its ipco box (numbered from 1), in the order it lists
    them (the order transformative properties apply in)."""
    ipco, ipma = _mp4_child(meta, start, end, (b"ipco",)), _mp4_child(meta, start, end, (b"ipma",))
    listed = [(kind, meta[body:stop]) for kind, body, stop in _mp4_boxes(meta, *ipco)]
    at, stop = ipma
    if stop - at < 8:
        return []
    version, flags = meta[at], meta[at + 3]
    id_bytes, index_bytes = (4 if version >= 1 else 2), (2 if flags & 1 else 1)
    count, at = int.from_bytes(meta[at + 4 : at + 8], "big"), at + 8
    for _ in range(count):
        if at + id_bytes + 1 > stop:
            break
        owner = int.from_bytes(meta[at : at + id_bytes], "big")
        n, at = meta[at + id_bytes], at + id_bytes + 1
        indexes = [
            int.from_bytes(meta[at + k * index_bytes : at + (k + 1) * index_bytes], "big")
            & ((1 << (8 * index_bytes - 1)) - 1)  # less the "essential" bit
            for k in range(n)
        ]
        at += n * index_bytes
        if owner == item:
            return [listed[i - 1] for i in indexes if 0 < i <= len(listed)]
    return []


def _heif_derived_from(meta: bytes, iref: tuple[int, int] | None, item: int) -> list[int]:
    """The items a HEIF meta's iref box (its body ``meta[start:end]``) says ``item`` is made
    of (its dimg reference: a grid's tiles, in order); empty when it is made of none."""
    if iref is None or iref[1] - iref[0] < 4:
        return []
    start, end = iref
    id_bytes = 4 if meta[start] >= 1 else 2
    for kind, body, stop in _mp4_boxes(meta, start + 4, end):
        owner = int.from_bytes(meta[body : body + id_bytes], "big")
        if kind != b"dimg" or owner != item:
            continue
        at = body + id_bytes
        n = int.from_bytes(meta[at : at + 2], "big")
        ids = meta[at + 2 : min(stop, at + 2 + n * id_bytes)]
        return [int.from_bytes(ids[k : k + id_bytes], "big") for k in range(0, len(ids), id_bytes)]
    return []


def refuse_cut(path: Path, head: bytes, tail: bytes) -> None:
    """DataError for a file whose first and last bytes (``head``, ``tail``) show it cut
    short: a JPEG without its end-of-image marker (OpenCV decodes what it has of it and
    greys the rest), a Matroska/WebM or FLV file that ends inside an element or a tag
    (:func:`cut_short`), an MP4/MOV file that ends inside a box (:func:`mp4_walk`: FFmpeg
    decodes what it has of the last frames, or reads none when the index at the end is
    missing) or whose frames have no index at all (:func:`mp4_unindexed`: still being
    recorded)."""
    if head.startswith(JPEG_START) and not tail.rstrip(b"\x00\r\n\t ").endswith(JPEG_END):
        raise DataError("truncated JPEG (no end-of-image marker)", path)
    if is_mp4(head):
        try:
            size = path.stat().st_size
            with open(path, "rb") as fh:
                end = mp4_walk(fh, size)
                unindexed = mp4_unindexed(fh, size)
        except OSError as exc:
            raise DataError(f"cannot read ({exc.strerror or exc})", path) from None
        if end is not None and end > size:
            runs = f" that runs to byte {end:,}" if end > size + 1 else "'s header"
            raise DataError(
                f"truncated MP4/MOV: the file ends at byte {size:,}, inside a box{runs}", path
            )
        if unindexed and heif_brand(head) is None:  # a HEIF photo's index is its meta box
            raise DataError(UNFINISHED_MP4.format("its"), path)
    if head.startswith((EBML_START, FLV_START)):
        try:
            with open(path, "rb") as fh:
                cut = cut_short(fh, path.stat().st_size, head, "the file")
        except OSError as exc:
            raise DataError(f"cannot read ({exc.strerror or exc})", path) from None
        if cut is not None:
            raise DataError(cut, path)


UNFINISHED_MP4 = (
    "unfinished MP4/MOV: {} frames have no index (no moov box): still being recorded, or the"
    " recording stopped before it was closed"
)
"""What an MP4/MOV file whose frames have no index (:func:`mp4_unindexed`) is, its owner
("its", "the served file's") put in."""


def cut_short(fh: Any, size: int, head: bytes, what: str) -> str | None:
    """Why an MP4/MOV, Matroska/WebM or FLV file of ``size`` bytes whose first bytes are ``head``,
    read from ``fh`` at its start (forward only: ``seek`` ahead, ``read``, ``tell``), is cut
    short or unfinished, in words naming it ``what`` ("the file"), or None when it is not or
    cannot be judged (no such file). MP4/MOV (:func:`mp4_walk`): it ends inside a box: FFmpeg
    decodes what it has of the last frame as whole; or its frames have no index (no moov
    box, nor a fragment's moof: still being recorded, as :func:`mp4_unindexed` judges a
    file here): FFmpeg cannot open it. Matroska/WebM (:func:`matroska_walk`): it ends inside an
    element: FFmpeg reads the frames before the cut as the whole video when the file states
    no duration, or no frame rate, as a browser's WebM. FLV (:func:`flv_end`): it ends
    inside a tag, or its tags end more than :data:`FLV_SLACK_S` before the duration its
    header states (cut where a tag ends): its frames are counted by their packets (the
    sound may run on after the last frame: :func:`counted_by_duration`)."""
    if is_mp4(head):  # a served MP4/MOV file (a file here: refuse_cut)
        kinds: list[bytes] = []
        end = mp4_walk(fh, size, kinds)
        if end is None:
            return None
        if end <= size:
            unindexed = b"mdat" in kinds and not {b"moov", b"moof"} & set(kinds)
            unindexed = unindexed and heif_brand(head) is None  # a photo: indexed by meta
            return UNFINISHED_MP4.format(f"{what}'s") if unindexed else None
        runs = f" that runs to byte {end:,}" if end > size + 1 else "'s header"
        return f"truncated MP4/MOV: {what} ends at byte {size:,}, inside a box{runs}"
    if head.startswith(EBML_START):
        end = matroska_walk(fh, size)
        if end is None or end <= size:
            return None
        runs = f" that runs to byte {end:,}" if end > size + 1 else "'s header"
        return f"truncated Matroska/WebM: {what} ends at byte {size:,}, inside an element{runs}"
    if head.startswith(FLV_START):
        walked = flv_end(fh, size)
        if walked is None:
            return None
        end, last_s, stated_s = walked
        if end > size:
            return (
                f"truncated FLV: {what} ends at byte {size:,}, inside a tag that runs to"
                f" byte {end:,}"
            )
        if last_s + FLV_SLACK_S < stated_s:
            return (
                f"truncated FLV: {what}'s last packet is at {last_s:.2f} s, its header states"
                f" {stated_s:.2f} s"
            )
    return None


MP4_BOXES = (b"ftyp", b"moov", b"mdat", b"free", b"skip", b"wide", b"pnot")
"""The boxes an MP4/MOV (ISO base media, QuickTime) file begins with: its fifth to eighth
bytes name one of them."""
MP4_TOP_BOXES = frozenset(
    (*MP4_BOXES, b"moof", b"mfra", b"sidx", b"ssix", b"styp", b"prft", b"emsg", b"pdin")
    + (b"uuid", b"meta", b"udta", b"junk")
)
"""The boxes :func:`mp4_walk` knows at an MP4/MOV file's top level; anything else there (a
phone maker's trailer after the last box) is not judged."""


def is_mp4(head: bytes) -> bool:
    """Whether a file whose first bytes are ``head`` is an MP4/MOV file (ISO base media:
    MP4, MOV, 3GP, M4V): its first box is one of :data:`MP4_BOXES`."""
    return len(head) >= 8 and head[4:8] in MP4_BOXES and int.from_bytes(head[:4], "big") != 0


def mp4_walk(fh: Any, size: int, kinds: list[bytes] | None = None) -> int | None:
    """Where the top-level boxes of an MP4/MOV file of ``size`` bytes, read from ``fh`` at
    its start, end as their headers state (bytes): beyond ``size``, the file is cut short
    (``size + 1``: it ends inside a box's header). A box stating size 0 runs to the file's
    end. None where the walk meets bytes that are no box header (a name not of printable
    letters, a size shorter than its header: padding, damage) or a box not of
    :data:`MP4_TOP_BOXES` (a maker's trailer): not judged. ``kinds``: each box's name is
    added to it, as the walk meets it."""
    at = 0
    while at < size:
        fh.seek(at)
        header = fh.read(8)
        if len(header) < 8:
            return None if not header.strip(b"\x00") else size + 1
        stated, kind = int.from_bytes(header[:4], "big"), header[4:8]
        if kind not in MP4_TOP_BOXES:
            return None
        if kinds is not None:
            kinds.append(kind)
        length = 8
        if stated == 1:  # a 64-bit size follows the name
            large = fh.read(8)
            if len(large) < 8:
                return size + 1
            stated, length = int.from_bytes(large, "big"), 16
        if stated == 0:  # to the file's end (a 64-bit 0 too: a recorder reserved one)
            return size
        if stated < length:
            return None
        at += stated
    return at


UNSIZED_LOOK = 1 << 20
"""How far into an MP4/MOV stream whose length is not stated (a server's, sending a file as
it is written) :func:`mp4_unindexed` walks (bytes): the boxes before the frames' take some
hundred bytes; frames' boxes that end within it and no more (a recording stopped) are
judged too."""


def mp4_unindexed(fh: Any, size: int | None) -> bool:
    """Whether an MP4/MOV file of ``size`` bytes, read from ``fh``, holds frames (a top-level
    mdat box) and no index for them (no moov box, nor a fragment's moof, before the walk ends):
    a recording still being written (its recorder writes the index when it stops, and the
    frames' box states size 0, or a 64-bit size 0, "to the file's end", until then) or one
    stopped before it was closed. FFmpeg cannot open it. False where the walk meets bytes
    :func:`mp4_walk` does not judge. ``size`` None: a stream of no stated length, read
    onward from ``fh`` (a server's), walked within its first :data:`UNSIZED_LOOK` bytes to
    a box running to its end or to its end: False when neither comes within them."""
    at, frames = 0, False
    while at + 8 <= (UNSIZED_LOOK if size is None else size):
        fh.seek(at)
        header = fh.read(8)  # then the 64-bit size, if stated: forward only, as it comes
        if size is None and len(header) < 8:
            return frames and not header  # the stream ends where the next box would begin
        stated, kind, length = int.from_bytes(header[:4], "big"), header[4:8], 8
        if kind in (b"moov", b"moof") or kind not in MP4_TOP_BOXES:
            return False
        frames = frames or kind == b"mdat"
        large = fh.read(8) if stated == 1 else b""
        if len(large) == 8:
            stated, length = int.from_bytes(large, "big"), 16
        if stated == 0:  # runs to the file's end
            return frames
        if stated < length:
            return False
        at += stated
    return frames and size is not None  # not judged: no end within the look


MOOV_LIMIT = 256 << 20
"""The largest MP4/MOV index (moov box, bytes) :func:`mp4_timeless_frames` reads: an hour
at 60 fps states some megabytes."""


def _mp4_boxes(data: bytes, start: int, end: int) -> Iterator[tuple[bytes, int, int]]:
    """The boxes in ``data[start:end]``: each one's name and where its body starts and ends;
    stops at one whose size does not fit."""
    at = start
    while at + 8 <= end:
        stated, kind, length = int.from_bytes(data[at : at + 4], "big"), data[at + 4 : at + 8], 8
        if stated == 1 and at + 16 <= end:
            stated, length = int.from_bytes(data[at + 8 : at + 16], "big"), 16
        elif stated == 0:
            stated = end - at
        if stated < length or at + stated > end:
            return
        yield kind, at + length, at + stated
        at += stated


def _mp4_child(data: bytes, start: int, end: int, path: Sequence[bytes]) -> tuple[int, int]:
    """Where the body of the first box along ``path`` (names, one per level) inside
    ``data[start:end]`` starts and ends; (0, 0) when there is none."""
    for name in path:
        for kind, body, stop in _mp4_boxes(data, start, end):
            if kind == name:
                start, end = body, stop
                break
        else:
            return 0, 0
    return start, end


def _mp4_moov(fh: Any, size: int) -> bytes | None:
    """The body of an MP4/MOV file's index (its top-level moov box), read from ``fh``; None
    when a box before it is not of :data:`MP4_TOP_BOXES`, it is larger than
    :data:`MOOV_LIMIT` or there is none."""
    return _top_box(fh, size, b"moov", MOOV_LIMIT, MP4_TOP_BOXES)


def _mp4_video_timing(moov: bytes) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Each video track's time-to-sample table (stts) in an MP4/MOV index ``moov``: how many
    frames in a row (counts) last how long (durations, in the track's ticks)."""
    for kind, body, stop in _mp4_boxes(moov, 0, len(moov)):
        if kind != b"trak":
            continue
        hdlr, hdlr_end = _mp4_child(moov, body, stop, (b"mdia", b"hdlr"))
        if hdlr_end < hdlr + 12 or moov[hdlr + 8 : hdlr + 12] != b"vide":
            continue  # no video: its subtype follows its version, flags and component type
        start, end = _mp4_child(moov, body, stop, (b"mdia", b"minf", b"stbl", b"stts"))
        if end - start < 8:
            continue
        entries = min(int.from_bytes(moov[start + 4 : start + 8], "big"), (end - start - 8) // 8)
        table = np.frombuffer(moov, ">u4", 2 * entries, start + 8)
        yield table[0::2].astype(np.int64), table[1::2].astype(np.int64)


def mp4_timeless_frames(fh: Any, size: int) -> int | None:
    """How many frames the video track of an MP4/MOV file of ``size`` bytes, read from
    ``fh``, holds when its time-to-sample table (stts) gives them all a duration of 0: a
    header stating no frame rate (FFmpeg makes one up: 12.25 fps for a 25 fps H.264 clip,
    2.08 for an MJPG one, each frame as long as the whole clip); None when it gives them
    time, holds one frame or none (a fragmented file's frames are in its fragments), or its
    index cannot be read."""
    moov = _mp4_moov(fh, size)
    if moov is None:
        return None
    for counts, durations in _mp4_video_timing(moov):
        frames = int(counts.sum())
        if frames > 1 and not int((counts * durations).sum()):
            return frames
    return None


@dataclass(frozen=True)
class VideoTrack:
    """A video track of an MP4/MOV file: its width and height as its track header states
    them (px, before the turn its display matrix gives), its frame count (its time-to-sample
    table's) and how a player turns its frames (:data:`MATRIX_TURNS`: an EXIF orientation)."""

    width: int
    height: int
    frames: int
    turn: int = 1


MATRIX_TURNS = {
    (1, 0, 0, 1): 1,
    (-1, 0, 0, 1): 2,
    (-1, 0, 0, -1): 3,
    (1, 0, 0, -1): 4,
    (0, 1, 1, 0): 5,
    (0, 1, -1, 0): 6,
    (0, -1, -1, 0): 7,
    (0, -1, 1, 0): 8,
}
"""The EXIF orientation (1-8, :func:`.video.upright`) a track header's display matrix gives,
by the signs of its first four entries (a, b, c, d: a stored pixel x, y is shown at
a x + c y, b x + d y, shifted): 6 is a quarter turn clockwise (a phone's portrait video
stored landscape), 2 a mirror (some phones' front camera). A matrix of no quarter turn is
taken as 1."""


def mp4_video_tracks(fh: Any, size: int) -> list[VideoTrack]:
    """Each video track of an MP4/MOV file of ``size`` bytes, read from ``fh``, that holds
    frames (:class:`VideoTrack`), in the order the file lists them (FFmpeg's streams, of
    which OpenCV decodes the first). Empty when its index cannot be read (a fragmented
    file's frames are in its fragments: none counted)."""
    moov = _mp4_moov(fh, size) or b""
    tracks: list[VideoTrack] = []
    for kind, body, stop in _mp4_boxes(moov, 0, len(moov)):
        hdlr, hdlr_end = _mp4_child(moov, body, stop, (b"mdia", b"hdlr"))
        tkhd, tkhd_end = _mp4_child(moov, body, stop, (b"tkhd",))
        matrix = tkhd + (52 if tkhd_end > tkhd and moov[tkhd] == 1 else 40)  # past the times
        if kind != b"trak" or hdlr_end < hdlr + 12 or moov[hdlr + 8 : hdlr + 12] != b"vide":
            continue  # no video: its subtype follows its version, flags and component type
        if tkhd_end < matrix + 44:  # the matrix (9 numbers), then the width and height
            continue
        a, b, _u, c, d = (
            int(np.sign(round(v / 65536))) for v in np.frombuffer(moov, ">i4", 5, matrix)
        )
        width, height = (int.from_bytes(moov[matrix + k : matrix + k + 4], "big") >> 16
                         for k in (36, 40))  # fmt: skip
        stts, end = _mp4_child(moov, body, stop, (b"mdia", b"minf", b"stbl", b"stts"))
        counted = min(int.from_bytes(moov[stts + 4 : stts + 8], "big"), (end - stts - 8) // 8)
        frames = 0
        if counted > 0:
            frames = int(np.frombuffer(moov, ">u4", 2 * counted, stts + 8)[0::2].sum())
        if frames > 0:
            tracks.append(VideoTrack(width, height, frames, MATRIX_TURNS.get((a, b, c, d), 1)))
    return tracks


def mp4_empty_video(fh: Any, size: int) -> bool:
    """Whether an MP4/MOV file of ``size`` bytes, read from ``fh``, has a video track and no
    frame in any (a recording stopped before its first frame: FFmpeg states its track's
    clock, such as 16000 ticks a second, as its frame rate). A fragmented file (an ``mvex`` box in
    its index), whose frames are in its fragments, is not judged (False)."""
    moov = _mp4_moov(fh, size)
    if moov is None or _mp4_child(moov, 0, len(moov), (b"mvex",)) != (0, 0):
        return False
    tables = list(_mp4_video_timing(moov))
    return bool(tables) and all(int(counts.sum()) == 0 for counts, _ in tables)


FLV_START = b"FLV\x01"
"""The first bytes of an FLV file (its signature and version)."""
FLV_SLACK_S = 1.0
"""How far (s) before the duration an FLV file's header states its last packet may lie and
the file be whole: the last packet's own length (a frame's, a sound packet's) lies within
it; a file cut where a tag ends, a second or more short, does not."""


def flv_end(fh: Any, size: int) -> tuple[int, float, float] | None:
    """Where an FLV file's tags end as they state their sizes (bytes: beyond ``size``, it
    ends inside one), the latest time of its sound and video packets (s) and the duration
    its metadata (``onMetaData``) states (s; 0 when none: a live recording's), walked from
    its start in ``fh``. None where a tag is of no kind FLV has (damage, padding): not
    judged. A last tag without the 4 bytes that repeat its size after it is whole."""
    import struct

    header = fh.read(9)
    if len(header) < 9:
        return size + 1, 0.0, 0.0
    at = int.from_bytes(header[5:9], "big") + 4  # the header, then PreviousTagSize0
    last_ms, stated = 0, 0.0
    while at < size:
        fh.seek(at)
        tag = fh.read(11)
        if len(tag) < 11:
            return at + 11, last_ms / 1000.0, stated
        kind, length = tag[0] & 0x1F, int.from_bytes(tag[1:4], "big")
        if kind not in (8, 9, 18):  # sound, video, script data
            return None
        if kind == 18 and not stated and length < 1 << 16:
            data = fh.read(length)
            found = data.find(b"\x00\x08duration\x00")  # an AMF0 key, then a number
            if found >= 0 and len(data) >= found + 19:
                (value,) = struct.unpack(">d", data[found + 11 : found + 19])
                stated = value if math.isfinite(value) and value > 0 else 0.0
        else:
            last_ms = max(last_ms, int.from_bytes(tag[4:7], "big") | tag[7] << 24)
        end = at + 11 + length
        if end > size:
            return end, last_ms / 1000.0, stated
        at = end + 4
    return min(at, size), last_ms / 1000.0, stated


_SOUND_STARTS = {
    b"fLaC": "a FLAC file",
    b"ID3": "an MP3 file",
    b"\xff\xfb": "an MP3 file",
    b"\xff\xf3": "an MP3 file",
    b"\xff\xf2": "an MP3 file",
    b"\xff\xf1": "an AAC file",
    b"\xff\xf9": "an AAC file",
}
"""The first bytes of audio formats that hold no video, and what they are."""
_TRACKS, _TRACK_ENTRY, _TRACK_TYPE = 0x1654AE6B, 0xAE, 0x83


def sound_only(path: Path, head: bytes) -> str | None:
    """What a file OpenCV cannot open as a video is when it holds sound and no video (a
    WAVE, FLAC, MP3, AAC or Ogg sound file, the Ogg with a skeleton or not; an MP4/M4A/MOV,
    Matroska/WebM, FLV or MPEG-TS file whose only tracks are sound), else None (not told apart from
    damage: not judged)."""
    import mmap

    for start, kind in _SOUND_STARTS.items():
        if head.startswith(start):
            return kind
    if head.startswith(b"RIFF") and head[8:12] == b"WAVE":
        return "a WAVE file"
    try:
        with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as data:
            if head.startswith(b"OggS"):
                return "an Ogg sound file" if _ogg_sound_alone(data) else None
            if head[4:8] == b"ftyp":  # each track's handler: soun, vide, ...
                tracks = {data[i + 12 : i + 16] for i in _all(data, b"hdlr")}
                only = b"soun" in tracks and b"vide" not in tracks
                return "an MP4 file of sound alone" if only else None
            if head.startswith(EBML_START):
                fh.seek(0)
                only = _matroska_track_types(fh, len(data)) == {2}
                return "a Matroska/WebM file of sound alone" if only else None
            if head.startswith(FLV_START):
                return "an FLV file of sound alone" if _flv_sound_alone(data) else None
            if counted_by_duration(head):  # MPEG-TS (Matroska and FLV are asked above)
                types = _ts_stream_types(data[:_TS_LOOK])
                only = bool(types) and types <= _TS_SOUND
                return "an MPEG-TS file of sound alone" if only else None
    except (OSError, ValueError):
        return None
    return None


_OGG_SOUND = (b"\x01vorbis", b"OpusHead", b"\x7fFLAC", b"Speex   ", b"\x01audio", b"CELT    ")
"""How the first packet of an Ogg stream of sound starts (Vorbis, Opus, FLAC, Speex, OGM's
audio, CELT)."""
_OGG_ASIDE = (b"fishead\x00", b"\x80kate", b"\x01text")
"""How the first packet of an Ogg stream that is neither sound nor video starts: a skeleton
(an index of the other streams, which a sound file may carry), subtitles."""


def _ogg_sound_alone(data: Any) -> bool:
    """Whether an Ogg file (its bytes ``data``) holds sound and no video: each stream's
    first page (flagged as its beginning; all of them come first) starts a stream of sound
    (:data:`_OGG_SOUND`) or of neither (:data:`_OGG_ASIDE`: a skeleton), and one is sound.
    A stream of any other kind (Theora, Daala, Dirac, VP8: video) or pages that cannot be
    read: not judged (False)."""
    at, kinds = 0, set()
    while data[at : at + 4] == b"OggS" and at + 27 <= len(data) and data[at + 5] & 0x02:
        lacing = data[at + 27 : at + 27 + data[at + 26]]
        first = data[at + 27 + len(lacing) : at + 27 + len(lacing) + 8]
        if first.startswith(_OGG_SOUND):
            kinds.add("sound")
        elif not first.startswith(_OGG_ASIDE):
            return False
        at += 27 + len(lacing) + sum(lacing)
    return kinds == {"sound"}


def _flv_sound_alone(data: Any) -> bool:
    """Whether an FLV file (its bytes ``data``) holds sound and no video: its header says it
    has no video and its first tags (up to :data:`_FLV_LOOK` of them) are sound or script
    data, one of them sound."""
    if len(data) < 13 or data[4] & 0x01:
        return False
    at, kinds = int.from_bytes(data[5:9], "big") + 4, set()
    for _ in range(_FLV_LOOK):
        if at + 11 > len(data):
            break
        kinds.add(data[at] & 0x1F)
        at += 11 + int.from_bytes(data[at + 1 : at + 4], "big") + 4
    return 8 in kinds and kinds <= {8, 18}


_FLV_LOOK = 64
"""How many of an FLV file's first tags :func:`_flv_sound_alone` reads."""
_TS_LOOK = 1 << 16
"""How much of an MPEG-TS file's start (bytes) :func:`_ts_stream_types` reads for its
programs' tables (written first, and every tenth of a second or so)."""
_TS_SOUND = frozenset({0x03, 0x04, 0x0F, 0x11, 0x1C, 0x81, 0x87})
"""The MPEG-TS stream types of sound: MPEG-1 and -2 audio, AAC (ADTS, LATM, raw), AC-3,
E-AC-3. Private data (0x06: DVB's AC-3, Opus, subtitles...) is not judged."""


def _ts_stream_types(data: Any) -> set[int]:
    """The stream types an MPEG-TS file's program tables (its PAT, then each PMT) list, read
    from its first bytes ``data`` (188-byte packets, or M2TS's 192); empty where none is
    found whole in one packet."""
    step, start = (192, 4) if data[4:5] == b"\x47" and data[:1] != b"\x47" else (188, 0)
    tables: dict[int, bytes] = {}
    for at in range(start, len(data) - 187, step):
        packet = data[at : at + 188]
        if packet[0] != 0x47 or not packet[1] & 0x40:  # no sync, or no section starts here
            continue
        pid = (packet[1] & 0x1F) << 8 | packet[2]
        body = 4 + (1 + packet[4] if packet[3] & 0x20 else 0)  # past an adaptation field
        if body >= 188:
            continue
        section = packet[body + 1 + packet[body] :]  # past the pointer field
        if len(section) >= 3 and pid not in tables:
            tables[pid] = bytes(section[: 3 + ((section[1] & 0x0F) << 8 | section[2])])
    pat = tables.get(0, b"")
    if len(pat) < 12 or pat[0] != 0:
        return set()
    types: set[int] = set()
    for i in range(8, len(pat) - 4, 4):
        if pat[i : i + 2] == b"\x00\x00":  # the network's table, no program
            continue
        pmt = tables.get((pat[i + 2] & 0x1F) << 8 | pat[i + 3], b"")
        if len(pmt) < 16 or pmt[0] != 2:
            return set()
        j = 12 + ((pmt[10] & 0x0F) << 8 | pmt[11])  # past the program's descriptors
        while j + 5 <= len(pmt) - 4:  # each stream: its type, PID and descriptors
            types.add(pmt[j])
            j += 5 + ((pmt[j + 3] & 0x0F) << 8 | pmt[j + 4])
    return types


def _all(data: Any, word: bytes) -> Iterator[int]:
    """Where ``word`` occurs in ``data``."""
    at = data.find(word)
    while at >= 0:
        yield at
        at = data.find(word, at + 1)


def _matroska_track_types(fh: Any, size: int) -> set[int]:
    """The kinds of a Matroska/WebM file's tracks (its TrackType values: 1 video, 2 sound,
    17 subtitles, ...), read from ``fh`` at its start; empty where they cannot be read."""
    kinds: set[int] = set()
    try:
        while fh.tell() < size:
            ident, _ = _ebml_number(fh, True)
            stated, unknown = _ebml_number(fh, False)
            if ident == _SEGMENT or (ident in (_TRACKS, _TRACK_ENTRY) and not unknown):
                continue  # step in: the tracks lie inside
            if unknown or ident == _CLUSTER:
                return kinds  # the frames: the tracks come before them
            if ident == _TRACK_TYPE:
                kinds.add(int.from_bytes(fh.read(stated), "big"))
            else:
                fh.seek(fh.tell() + stated)
    except (EOFError, ValueError):
        return set()
    return kinds


def counted_by_duration(head: bytes) -> bool:
    """Whether a video (its first bytes ``head``) states no frame count, so that OpenCV
    counts its duration (its longest track's) at its frame rate, and a cut short file
    shows otherwise than by that count: Matroska/WebM and FLV (their elements and tags state
    their sizes, an FLV's header its duration: :func:`cut_short`) and MPEG-TS (``.ts``, a
    camcorder's ``.mts``/``.m2ts``: its duration is read from the packets there are, cut
    short or not). Not MP4/MOV and AVI, which state their frames."""
    if head.startswith((EBML_START, FLV_START)):
        return True
    return any(
        len(head) > offset + 2 * step and all(head[offset + k * step] == 0x47 for k in range(3))
        for offset, step in ((0, 188), (4, 192))  # TS packets; M2TS: a 4-byte stamp first
    )


EBML_START = b"\x1a\x45\xdf\xa3"
"""The first bytes of a Matroska or WebM file (its EBML header's ID)."""
_SEGMENT, _CLUSTER = 0x18538067, 0x1F43B675


def _ebml_number(fh: Any, keep_marker: bool) -> tuple[int, bool]:
    """An EBML number (an ID with its length marker kept; a size without it, and
    whether it is unknown: all ones); raises EOFError where the file ends inside it,
    ValueError where its first byte is no number's."""
    first = fh.read(1)
    if not first:
        raise EOFError
    if first[0] == 0:
        raise ValueError
    n = 9 - first[0].bit_length()  # the leading zeros say how many bytes follow
    rest = fh.read(n - 1)
    if len(rest) < n - 1:
        raise EOFError
    value = first[0] if keep_marker else first[0] & ((1 << (8 - n)) - 1)
    for b in rest:
        value = (value << 8) | b
    return value, not keep_marker and value == (1 << (7 * n)) - 1


def matroska_end(path: Path) -> int | None:
    """Where a Matroska/WebM file's data ends as its elements state it (bytes;
    :func:`matroska_walk` of the file): beyond the file's size, the file is truncated."""
    with open(path, "rb") as fh:
        return matroska_walk(fh, path.stat().st_size)


def matroska_walk(fh: Any, size: int) -> int | None:
    """Where the data of a Matroska/WebM file of ``size`` bytes, read from ``fh`` at its
    start (forward only), ends as its elements state it (bytes): the end of its segment when
    the segment states its size; when it does not (a recording written as it went, as a
    browser's MediaRecorder writes it), the end of its last element, walked from the start
    (into clusters that do not state their size either, past the others whole). None where
    the walk meets anything it cannot read (bytes that are no element: padding, damage): not
    judged."""
    end = 0
    while fh.tell() < size:
        try:
            ident, _ = _ebml_number(fh, True)
            stated, unknown = _ebml_number(fh, False)
        except EOFError:  # the file ends inside an element's header
            return size + 1
        except ValueError:
            return None
        at = int(fh.tell())  # the element's data
        if ident == _SEGMENT and not unknown:
            return at + stated
        if ident in (_SEGMENT, _CLUSTER) and unknown:
            end = at  # its children follow, one by one
            continue
        if unknown:
            return None  # no other element may leave its size open
        end = at + stated
        if end < size:
            fh.seek(end)
        else:
            return end
    return end


def segment_end(head: bytes) -> int | None:
    """Where a Matroska/WebM file whose first bytes are ``head`` ends as its segment states
    (bytes from the file's start), or None when the segment leaves its size open or
    ``head`` holds no EBML header and segment header."""
    import io

    fh = io.BytesIO(head)
    try:
        for expected in (None, _SEGMENT):  # the EBML header, then the segment
            ident, _ = _ebml_number(fh, True)
            stated, unknown = _ebml_number(fh, False)
            if unknown or (expected is not None and ident != expected):
                return None
            if expected is None:
                fh.seek(fh.tell() + stated)
    except (EOFError, ValueError):
        return None
    return fh.tell() + stated
