"""Hunt 35g: container and stream leftovers in video reading. A sound-only Ogg file with a
skeleton track (refused as "not a video"), an FLV file whose sound runs on after its last
frame, a browser's WebM served over HTTP and cut short mid-cluster."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from tests.badinput import refused, small_case_base
from tests.test_hunt34h import _sound

SKELETON = 0x5C5C5C5C
"""The skeleton stream's serial number."""
SKELETON_BYTES = struct.pack("<I", SKELETON)


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


# --- Ogg pages written by hand ---------------------------------------------------------------


def _ogg_crc(data: bytes) -> int:
    """Ogg's page checksum: CRC-32, polynomial 0x04C11DB7, not reflected, starting at 0."""
    crc = 0
    for byte in data:
        crc ^= byte << 24
        for _ in range(8):
            crc = ((crc << 1) ^ 0x04C11DB7 if crc & 0x80000000 else crc << 1) & 0xFFFFFFFF
    return crc


def _ogg_page(serial: int, sequence: int, packet: bytes, flags: int) -> bytes:
    """One Ogg page holding one whole packet (flags: 2 a stream's first page, 4 its last)."""
    lacing = [255] * (len(packet) // 255) + [len(packet) % 255]
    header = b"OggS" + bytes([0, flags]) + struct.pack("<qIII", 0, serial, sequence, 0)
    page = header + bytes([len(lacing), *lacing]) + packet
    return page[:22] + struct.pack("<I", _ogg_crc(page)) + page[26:]


def _ogg_pages(data: bytes) -> list[bytes]:
    """An Ogg file's pages, in order."""
    pages, at = [], 0
    while at < len(data):
        lacing = data[at + 27 : at + 27 + data[at + 26]]
        size = 27 + len(lacing) + sum(lacing)
        pages.append(data[at : at + size])
        at += size
    return pages


def test_the_hand_written_ogg_pages_check_as_a_writers_do(tmp_path: Path) -> None:
    """The checksum computed here is the one PyAV's Ogg writer puts on its pages."""
    data = _sound(tmp_path / "talk.ogg").read_bytes()
    for page in _ogg_pages(data):
        assert _ogg_crc(page[:22] + bytes(4) + page[26:]) == struct.unpack("<I", page[22:26])[0]


def _with_skeleton(sound: bytes, first_packet: bytes = b"") -> bytes:
    """An Ogg file's bytes with a skeleton stream added, as ffmpeg2theora or oggz-chop add
    one: its fishead page first, the file's first page, a fisbone page describing the file's
    stream, the rest, and the skeleton's empty last page. ``first_packet``: the first packet
    of a stream put in the file's place (a video's header) instead."""
    pages = _ogg_pages(sound)
    serial = struct.unpack("<I", pages[0][14:18])[0]
    if first_packet:
        pages[0] = _ogg_page(serial, 0, first_packet, 2)
    fishead = b"fishead\0" + struct.pack("<HH4q", 4, 0, 0, 1000, 0, 1000) + bytes(20)
    fisbone = b"fisbone\0" + struct.pack("<IIIqqqIB3x", 52, serial, 2, 48000, 1, 0, 2, 0)
    fisbone += b"Content-Type: audio/opus\r\n"
    return b"".join(
        [
            _ogg_page(SKELETON, 0, fishead, 2),
            pages[0],
            _ogg_page(SKELETON, 1, fisbone, 0),
            pages[1],
            _ogg_page(SKELETON, 2, b"", 4),
            *pages[2:],
        ]
    )


@pytest.mark.parametrize("command", ["extract", "watch"])
def test_a_sound_only_ogg_with_a_skeleton_is_refused_as_sound(
    command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An Ogg Opus file carrying a skeleton stream (FFmpeg: a data stream and a sound
    stream, no video): it was refused as "not a video OpenCV can decode (unknown format,
    truncated or corrupt)", the skeleton taken for a video's sign. Now as the same file
    without it: "sound alone, no video (an Ogg sound file)", one line, exit 1."""
    av = pytest.importorskip("av", reason="PyAV reads the file")
    folder = tmp_path / "in"
    folder.mkdir()
    plain = _sound(folder / "talk.ogg")
    skeletal = folder / "skeletal.ogg"
    skeletal.write_bytes(_with_skeleton(plain.read_bytes()))
    with av.open(str(skeletal)) as got:  # what FFmpeg makes of it
        assert sorted(s.type for s in got.streams) == ["audio", "data"]
    for sound in (plain, skeletal):
        argv = {
            "extract": ["extract", str(sound), "--out", str(tmp_path / "poses")],
            "watch": ["watch", str(sound), "--db", str(case_base), "--speed", "0"],
        }[command]
        refused(argv, tmp_path, capsys, f"{sound}: sound alone, no video (an Ogg sound file)")


@pytest.mark.parametrize(
    ("first", "sound"),
    [
        (b"\x80theora" + bytes(34), False),  # Theora: video
        (b"BBCD\x00" + bytes(20), False),  # Dirac: video
        (b"\x80daala" + bytes(20), False),
        (b"\x01vorbis" + bytes(22), True),
        (b"Speex   " + bytes(72), True),
        (b"\x7fFLAC" + bytes(20), True),
        (b"XYZW" + bytes(20), False),  # a kind not known: not judged
    ],
    ids=["theora", "dirac", "daala", "vorbis", "speex", "flac", "unknown"],
)
def test_an_ogg_file_is_sound_by_its_streams_first_packets(
    first: bytes, sound: bool, tmp_path: Path
) -> None:
    """The skeleton beside a stream of each kind: sound when the stream is one of sound,
    else not judged (None). A Dirac stream's file was called a sound file before."""
    from features.pose_estimation.containers import sound_only

    data = _with_skeleton(_sound(tmp_path / "talk.ogg").read_bytes(), first)
    path = tmp_path / "mixed.ogg"
    path.write_bytes(data)
    assert sound_only(path, data[:512]) == ("an Ogg sound file" if sound else None)
    bare = tmp_path / "bare.ogg"  # without the skeleton, the same
    bare.write_bytes(b"".join(p for p in _ogg_pages(data) if p[14:18] != SKELETON_BYTES))
    assert sound_only(bare, bare.read_bytes()[:512]) == ("an Ogg sound file" if sound else None)
