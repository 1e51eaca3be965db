"""Hunt 35g: container and stream leftovers in video reading. A sound-only Ogg file with a
skeleton track (refused as "not a video"), an FLV file whose sound runs on after its last
frame, a browser's WebM served over HTTP and cut short mid-cluster."""

from __future__ import annotations

import json
import struct
import time
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused, small_case_base
from tests.media import mux_frames_and_silence, silence_file
from tests.test_hunt34c import _encode, _Quiet, _serving
from tests.test_hunt34h import _sound, assert_read_by_its_120_frames

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


# --- a browser's WebM served over HTTP and cut short --------------------------------------


def _live_webm(path: Path) -> Path:
    """A WebM written as it went, as a browser's MediaRecorder writes it (no duration, no
    frame count for OpenCV to know), 100 VP8 frames at a steady 25 fps."""
    return _encode(path, [40 * k for k in range(100)], "libvpx", 25, {"live": "1"})


def _nobody_posed(monkeypatch: pytest.MonkeyPatch) -> None:
    """The pose model, loaded as ever, answers every frame at once with nobody in view (what
    it finds in these grey frames). A frame must come within ``--stall`` of the one before:
    the model's own work on a busy machine (one core at load 16) took longer now and then
    (3 runs of 12 with 0.5 s, 3 of 22 with 1.5 s), and the watch stalled by chance."""
    from features.pose_estimation.tracker import FramePose, PoseEstimator

    monkeypatch.setattr(PoseEstimator, "process", lambda *_a, **_k: FramePose.missing(True))


def _watched(source: str, case_base: Path, capsys: pytest.CaptureFixture[str]) -> list[dict]:
    """``watch SOURCE --speed 0``'s segments, printed as they finish; its grey frames hold
    nobody, so it must end refusing the video as having nobody in view in any frame (exit
    1, as segment refuses it: tests/test_hunt45u.py), read to its end (no other error)."""
    capsys.readouterr()
    code = main(["watch", source, "--db", str(case_base), "--speed", "0"])
    got = capsys.readouterr()
    assert code == 1 and got.err.endswith(
        "with nobody in view in any of them: no activity to label\n"
    ), got.err
    return [json.loads(line) for line in got.out.splitlines()]


def test_watch_of_a_served_live_webm_cut_mid_cluster_is_refused_as_truncated(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A WebM without a duration, as a browser's (OpenCV knows no frame count), served whole by
    Python's own server (its length stated), cut at half its bytes, inside a cluster: it
    was watched to the cut as the whole file, exit 0. Now refused as the same file here is,
    the line naming the URL and the same byte where it ends and the element runs on to,
    exit 1, nothing printed. The whole file is watched whole (100 frames); cut where its
    last cluster starts, it is a recording stopped there, watched to it, as the file here."""
    from features.errors import DataError
    from features.pose_estimation import open_video

    folder = tmp_path / "served"
    folder.mkdir()
    data = _live_webm(folder / "whole.webm").read_bytes()
    (folder / "cut.webm").write_bytes(data[: len(data) // 2])
    clusters = [i for i in range(len(data)) if data.startswith(b"\x1f\x43\xb6\x75", i)]
    (folder / "stopped.webm").write_bytes(data[: clusters[-1]])
    with pytest.raises(DataError) as here:
        open_video(folder / "cut.webm")
    said_here = str(here.value).split(": ", 1)[1]  # "truncated Matroska/WebM: the file ..."
    with _serving(folder, _Quiet) as address:
        segments = _watched(f"{address}/whole.webm", case_base, capsys)
        assert segments[-1]["end_frame"] == 100
        stopped = _watched(f"{address}/stopped.webm", case_base, capsys)
        assert 0 < stopped[-1]["end_frame"] < 100
        url = f"{address}/cut.webm"
        argv = ["watch", url, "--db", str(case_base), "--speed", "0"]
        served_words = said_here.replace("the file ends", "the served file ends")
        assert f"ends at byte {len(data) // 2:,}, inside an element that runs to" in served_words
        refused(argv, tmp_path, capsys, f"{url}: {served_words}")


class _Dropping(_Quiet):
    """States a file's whole length and sends its first half, then hangs up (a connection
    lost mid-file)."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        data = Path(self.translate_path(self.path)).read_bytes()
        self.send_response(200)
        self.send_header("Content-Type", "video/webm")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data[: len(data) // 2])
        self.close_connection = True


def test_a_served_webm_whose_server_hangs_up_mid_file_is_refused_as_truncated(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """That whole WebM, its length stated, but the server hangs up after half its
    bytes: the frames before were watched as the whole file, exit 0. Now refused, one line
    saying how many of the bytes the server stated came."""
    folder = tmp_path / "served"
    folder.mkdir()
    size = _live_webm(folder / "whole.webm").stat().st_size
    with _serving(folder, _Dropping) as address:
        url = f"{address}/whole.webm"
        argv = ["watch", url, "--db", str(case_base), "--speed", "0"]
        refused(
            argv,
            tmp_path,
            capsys,
            f"{url}: truncated: the server sent {size // 2:,} of the {size:,} bytes it stated",
        )


class _SlowToProbes(_Quiet):
    """Gives FFmpeg its files at once, and any other client (the probes, Python's urllib)
    the first 4,096 bytes at once and the rest 200 bytes at a time, 0.15 s apart."""

    def do_GET(self) -> None:  # noqa: N802 (the base's name)
        if not self.headers.get("User-Agent", "").startswith("Python-urllib"):
            super().do_GET()
            return
        data = Path(self.translate_path(self.path)).read_bytes()
        self.send_response(200)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data[:4096])
        for at in range(4096, len(data), 200):
            self.wfile.flush()
            time.sleep(0.15)
            self.wfile.write(data[at : at + 200])


def test_a_served_file_read_again_slowly_at_its_end_is_no_stall(
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A served WebM read again at its end for a cut, slowly (its 9 kB over about 4 s; no
    part more than 0.15 s after the one before), with ``--stall 1.5``: watched whole, exit 0,
    not "the stream stalled: no frame for 1.5 s" (no frame comes while it is read)."""
    folder = tmp_path / "served"
    folder.mkdir()
    path = _encode(folder / "long.webm", [40 * k for k in range(250)], "libvpx", 25, {"live": "1"})
    assert path.stat().st_size > 4096 + 200 * 15  # more than 2 s of parts
    _nobody_posed(monkeypatch)
    with _serving(folder, _SlowToProbes) as address:
        capsys.readouterr()
        url = f"{address}/long.webm"
        code = main(["watch", url, "--db", str(case_base), "--speed", "0", "--stall", "1.5"])
        got = capsys.readouterr()
    # watched to its end, no stall: refused there as nobody is in it (tests/test_hunt45u.py)
    assert code == 1 and got.err.endswith(
        "with nobody in view in any of them: no activity to label\n"
    ), got.err
    assert [json.loads(line)["end_frame"] for line in got.out.splitlines()][-1] == 250


def test_a_pose_model_slow_to_load_is_no_stall(
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The pose model taking longer to load than ``--stall`` (each of its two parts 1 s here;
    on a busy machine it took more than 8 s): ``watch`` of a whole file said "the stream
    stalled: no frame for 0.5 s", exit 1 (and the process could abort at exit, a thread still
    loading the model). The model is loaded before the stall clock runs: watched whole."""
    import features.pose_estimation.tracker as tracker

    loading = tracker.make_session

    def slow(*args: object, **kwargs: object) -> object:
        time.sleep(1.0)
        return loading(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(tracker, "make_session", slow)
    _nobody_posed(monkeypatch)
    video = _live_webm(tmp_path / "clip.webm")
    capsys.readouterr()
    code = main(["watch", str(video), "--db", str(case_base), "--speed", "0", "--stall", "0.5"])
    got = capsys.readouterr()
    # watched to its end, no stall: refused there as nobody is in it (tests/test_hunt45u.py)
    assert code == 1 and got.err.endswith(
        "with nobody in view in any of them: no activity to label\n"
    ), got.err
    assert [json.loads(line)["end_frame"] for line in got.out.splitlines()][-1] == 100


# --- FLV: sound running on after the last frame, cut short ---------------------------------


def _flv(path: Path, frames: int, sound_s: float) -> Path:
    """``frames`` grey frames at 30 fps (Sorenson H.263, FLV's own) and silent MP3 sound
    (44.1 kHz, mono, 1152 samples a packet) of ``sound_s`` seconds, interleaved by time."""
    av = pytest.importorskip("av", reason="PyAV writes the FLV files")
    out = av.open(str(path), "w", format="flv")
    video = out.add_stream("flv", rate=30)
    video.width, video.height, video.pix_fmt = 64, 48, "yuv420p"
    sound = out.add_stream("libmp3lame", rate=44100)
    mux_frames_and_silence(out, video, sound, frames, sound_s, "s16p", 1152)
    return path


def _flv_tags(data: bytes) -> list[tuple[int, int, int]]:
    """An FLV file's tags as this test reads them: (kind, where the tag ends with the 4
    bytes after it, time in ms)."""
    tags, at = [], int.from_bytes(data[5:9], "big") + 4
    while at + 11 <= len(data):
        end = at + 11 + int.from_bytes(data[at + 1 : at + 4], "big") + 4
        tags.append((data[at] & 0x1F, end, int.from_bytes(data[at + 4 : at + 7], "big")))
        at = end
    return tags


def test_an_flv_whose_sound_runs_on_is_counted_by_its_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 4-s FLV, 120 frames at 30 fps, whose sound runs on to 4.3 s: OpenCV counts the
    duration its header states at 30 fps, 130 frames, and ``extract`` refused it as
    "truncated or corrupt: decoded 120 of 130 frames". Its frames are its 120 video
    packets, as a WebM's are: all decode, ``extract`` writes 120 poses."""
    clip = _flv(tmp_path / "clip.flv", 120, 4.3)
    tags = _flv_tags(clip.read_bytes())
    assert sum(kind == 9 for kind, _end, _ms in tags) == 120
    assert_read_by_its_120_frames(clip, 130, tmp_path, capsys)


def _cut_flvs(folder: Path) -> tuple[bytes, dict[str, tuple[Path, str]]]:
    """The 4.3-s FLV's bytes and two cuts of it with what each is refused as: at half its
    bytes (inside a tag), and where a tag ends two thirds in (its tags stop short of the
    4.33 s its header states)."""
    data = _flv(folder / "whole.flv", 120, 4.3).read_bytes()
    tags = _flv_tags(data)
    half = folder / "half.flv"
    half.write_bytes(data[: len(data) // 2])
    inside = next(end for _k, end, _ms in tags if end > len(data) // 2) - 4
    cut_at = next(end for _k, end, _ms in tags if end >= 2 * len(data) // 3)
    last_ms = max(ms for kind, end, ms in tags if end <= cut_at and kind in (8, 9))
    boundary = folder / "boundary.flv"
    boundary.write_bytes(data[:cut_at])
    return data, {
        "half": (
            half,
            f"truncated FLV: the file ends at byte {len(data) // 2:,}, inside a tag that runs"
            f" to byte {inside:,}",
        ),
        "boundary": (
            boundary,
            f"truncated FLV: the file's last packet is at {last_ms / 1000:.2f} s, its header"
            f" states {130 / 30:.2f} s",
        ),
    }


@pytest.mark.parametrize("command", ["extract", "watch"])
def test_an_flv_cut_short_is_refused_as_truncated(
    command: str, case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """That FLV cut inside a tag or where a tag ends: refused, one line naming the file and
    where it was cut, exit 1, nothing written, though its frames are now counted by their
    packets (a cut file's packets are the frames before the cut)."""
    _data, cuts = _cut_flvs(tmp_path)
    for path, words in cuts.values():
        argv = {
            "extract": ["extract", str(path), "--out", str(tmp_path / "poses")],
            "watch": ["watch", str(path), "--db", str(case_base), "--speed", "0"],
        }[command]
        refused(argv, tmp_path, capsys, f"{path}: {words}")


def test_watch_of_a_served_flv_reads_it_whole_and_refuses_it_cut(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The FLV whose sound runs on, served over HTTP: ``watch`` refused it as "truncated or
    corrupt: decoded 120 of 130 frames", exit 1; now watched whole, 120 frames, 0-4 s.
    Its cuts served are refused as the files here are, "the served file" named."""
    folder = tmp_path / "served"
    folder.mkdir()
    _data, cuts = _cut_flvs(folder)
    with _serving(folder, _Quiet) as address:
        segments = _watched(f"{address}/whole.flv", case_base, capsys)
        assert [(s["start_frame"], s["end_frame"], s["end_s"]) for s in segments] == [(0, 120, 4.0)]
        for path, words in cuts.values():
            url = f"{address}/{path.name}"
            argv = ["watch", url, "--db", str(case_base), "--speed", "0"]
            served = words.replace("the file", "the served file")
            refused(argv, tmp_path, capsys, f"{url}: {served}")


def test_an_flv_is_a_video_to_every_command_that_takes_one(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract clip.flv`` read it, but ``segment clip.flv`` (and ``describe``, ``classify``)
    said "unknown clip format (expected ... a video: .3gp, ... .wmv)", and ``extract`` of a
    folder of FLV files "no videos or images found". Now the folder's FLV is extracted (its
    120 frames) and ``segment`` takes it as a video (its grey frames hold nobody to follow)."""
    from features.poses import load_pose

    folder = tmp_path / "videos"
    folder.mkdir()
    clip = _flv(folder / "clip.flv", 120, 4.0)
    out = tmp_path / "poses"
    assert main(["extract", str(folder), "--out", str(out)]) == 0, capsys.readouterr().err
    (written,) = out.glob("*.npz")
    assert load_pose(written).n_frames == 120
    capsys.readouterr()
    main(["segment", str(clip), "--db", str(case_base)])
    err = capsys.readouterr().err
    assert "unknown clip format" not in err and "shows no person" in err, err


# --- FLV and MPEG-TS files of sound alone ----------------------------------------------------

SOUND_ONLY = {
    # file name: (container, codec, sample format, samples a packet, what the line calls it);
    # the M2TS (a Blu-ray's layout) holds AC-3: its other sound is "private data", not judged
    "radio.flv": ("flv", "libmp3lame", "s16p", 1152, "an FLV file of sound alone"),
    "radio.ts": ("mpegts", "libmp3lame", "s16p", 1152, "an MPEG-TS file of sound alone"),
    "radio-aac.ts": ("mpegts", "aac", "fltp", 1024, "an MPEG-TS file of sound alone"),
    "radio.m2ts": ("mpegts", "ac3", "fltp", 1536, "an MPEG-TS file of sound alone"),
}


def _sound_in(path: Path) -> Path:
    """About a second of silence (44.1 kHz, mono) in the container the table names."""
    pytest.importorskip("av", reason="PyAV writes the sound files")
    container, codec, fmt, n, _kind = SOUND_ONLY[path.name]
    return silence_file(path, codec, fmt, n, 44100, container)


@pytest.mark.parametrize("name", list(SOUND_ONLY))
def test_an_flv_or_mpeg_ts_of_sound_alone_is_refused_as_sound(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An FLV or MPEG-TS (M2TS) file holding sound alone (a radio recording) given to
    ``extract``: it said "not a video OpenCV can decode (unknown format, truncated or
    corrupt)", as the Ogg with a skeleton did. Now "sound alone, no video (an FLV file of
    sound alone)", one line, exit 1, nothing written."""
    sound = _sound_in(tmp_path / name)
    argv = ["extract", str(sound), "--out", str(tmp_path / "poses")]
    line = refused(argv, tmp_path, capsys, f"{sound}: sound alone, no video")
    assert line.endswith(f"({SOUND_ONLY[name][4]})"), line


def test_an_flv_or_mpeg_ts_with_video_is_not_sound(tmp_path: Path) -> None:
    """Their videos (FLV with MP3 sound; MPEG-TS of MPEG-2 video) are not called sound."""
    from features.pose_estimation.containers import sound_only

    flv = _flv(tmp_path / "clip.flv", 30, 1.0)
    pytest.importorskip("av")
    from tests.test_hunt34h import _with_longer_audio

    ts = _with_longer_audio(tmp_path / "clip.ts", 30, 1.0)
    for path in (flv, ts):
        assert sound_only(path, path.read_bytes()[:512]) is None
