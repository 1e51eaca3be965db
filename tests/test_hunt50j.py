"""Hunt 50j: ``segment --overlay DIR`` writes one ``DIR/<recording>.mp4`` per video recording,
as ``segment --plot DIR`` writes pictures and ``extract --overlay DIR`` overlays.

Before, a folder was refused ("the overlay is a folder: name the .mp4 file to write in it")
and so were several recordings ("--overlay takes one recording"). The clips here are 12
frames (2.4 s at 5 fps) of the bundled squat video, shrunk to 180x320; each overlay ends
with an MP4 ``uuid`` box naming segment and a digest of its recording's resolved path, which
the tests build by hand (hashlib) from the box's layout (ISO/IEC 14496-12: size, "uuid", the
16-byte user type, the mark).
"""

from __future__ import annotations

import hashlib
import json
import struct
from pathlib import Path

import cv2
import pytest

from features.interrupts import INTERRUPTED_STATUS
from posecbr.cli import main
from tests.badinput import assert_unchanged, refused, small_case_base, snapshot

# the user type of the box extract's and segment's overlays end with (hunt 46f)
MARK_TYPE = bytes.fromhex("cab5aa21f4394e688342e23fd7fa5c39")


def _clip(source: Path, path: Path, start: int) -> Path:
    """Frames ``start`` to ``start + 11`` of ``source``, 180x320 at 5 fps (MP4, mp4v)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    cap = cv2.VideoCapture(str(source))
    out = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), 5.0, (180, 320))
    k = 0
    while k < start + 12:
        ok, frame = cap.read()
        assert ok
        if k >= start:
            out.write(cv2.resize(frame, (180, 320)))
        k += 1
    cap.release()
    out.release()
    return path


def _mark_box(command: str, recording: Path) -> bytes:
    """The box ``command``'s overlay of ``recording`` ends with, built by hand."""
    digest = hashlib.sha256(str(recording.resolve()).encode()).hexdigest()[:16]
    body = MARK_TYPE + f"{command} {digest}".encode()
    return struct.pack(">I", 8 + len(body)) + b"uuid" + body


def _frames(video: Path) -> tuple[int, int, int]:
    cap = cv2.VideoCapture(str(video))
    got = (
        int(cap.get(cv2.CAP_PROP_FRAME_COUNT)),
        int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
        int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)),
    )
    cap.release()
    return got


@pytest.fixture
def clips(shared_data: Path, tmp_path: Path) -> tuple[Path, Path, Path]:
    """Two clips of one name in two folders (``in/squat.mp4``, ``in/b/squat.mp4``: other
    frames of the video) and the small case base."""
    source = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    first = _clip(source, tmp_path / "in" / "squat.mp4", 0)
    second = _clip(source, tmp_path / "in" / "b" / "squat.mp4", 20)
    return first, second, small_case_base(tmp_path)


def test_several_videos_overlay_folder_holds_one_marked_overlay_each(
    clips: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Into a folder to be made: squat.mp4 and squat_2.mp4 (the second of the name numbered,
    as --plot DIR numbers pictures), each the clip's 12 frames at its size, marked as
    segment's of its clip, named in --json; the clips in the other order, the first overlay
    is the other clip's: refused, nothing changed."""
    first, second, db = clips
    folder = tmp_path / "ov"
    argv = ["segment", str(first), str(second), "--db", str(db), "--overlay", str(folder)]
    capsys.readouterr()
    assert main([*argv, "--json"]) == 0
    captured = capsys.readouterr()
    written = [folder / "squat.mp4", folder / "squat_2.mp4"]
    assert [doc["overlay"] for doc in json.loads(captured.out)] == [str(p) for p in written]
    said = [line for line in captured.err.splitlines() if line.startswith("overlay")]
    assert said == [f"overlay written to {p}" for p in written]
    assert sorted(folder.iterdir()) == written
    for overlay, clip in zip(written, (first, second), strict=True):
        assert _frames(overlay) == (12, 180, 320)
        assert overlay.read_bytes().endswith(_mark_box("segment", clip))
    swapped = ["segment", str(second), str(first), *argv[3:]]
    refused(swapped, tmp_path, capsys,
            f"{folder}/squat.mp4: is already there, not an overlay posecbr segment drew of"
            f" {second}: --overlay {folder} would replace it")  # fmt: skip


def test_an_overlay_folder_is_refused_before_any_work(
    clips: tuple[Path, Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each refused in one line naming the file, before the pose model runs, nothing
    written: extract's overlay of the clip, a file of the user's at an overlay's place, a
    clip in the folder (an input), a pose file among the recordings (no video to draw on),
    one video's name for several recordings. Segment's own overlay of the clip there (a
    rerun) is no reason to refuse: the pose model runs, and a Ctrl-C in it (one recording,
    its folder written ending in "/") leaves the folder as it was."""
    import features.pose_estimation as estimation

    posed: list[Path] = []

    def stopped(video: Path, *_args: object, **_kwargs: object) -> None:
        posed.append(video)
        raise KeyboardInterrupt

    monkeypatch.setattr(estimation, "estimate_video", stopped)
    first, second, db = clips
    folder = tmp_path / "ov"
    folder.mkdir()
    theirs = folder / "squat.mp4"
    argv = ["segment", str(first), "--db", str(db), "--overlay", str(folder)]
    # extract's overlay of this very clip: an MP4 that ends with extract's mark
    theirs.write_bytes(first.read_bytes() + _mark_box("extract", first))
    refused(argv, tmp_path, capsys,
            f"{theirs}: is already there, not an overlay posecbr segment drew of"
            f" {first}")  # fmt: skip
    theirs.write_bytes(b"my own video")
    refused([*argv[:2], str(second), *argv[2:]], tmp_path, capsys, f"{theirs}: is already there")
    named = tmp_path / "both.mp4"
    refused(["segment", str(second), str(first), "--db", str(db), "--overlay", str(named)],
            tmp_path, capsys,
            f"{named}: with several recordings --overlay names the folder for their overlays"
            " (<recording>.mp4 each), not one video file")  # fmt: skip
    theirs.write_bytes(first.read_bytes() + _mark_box("segment", first))
    pose = next((tmp_path / "train").glob("*/*.npz"))
    refused(["segment", str(first), str(pose), *argv[2:]], tmp_path, capsys,
            f"{pose}: --overlay needs a video recording")  # fmt: skip
    inside = folder / "in"
    inside.mkdir()
    clip = first.rename(inside / "squat.mp4")  # not the overlay's place: the folder's own
    refused(["segment", str(clip), "--db", str(db), "--overlay", str(inside)], tmp_path, capsys,
            f"{clip}: the overlay would overwrite an input ({clip})")  # fmt: skip
    clip.rename(first)
    assert posed == []
    before = snapshot(tmp_path)
    assert main([*argv[:-1], f"{folder}/"]) == INTERRUPTED_STATUS
    assert capsys.readouterr().err.splitlines()[-1] == "posecbr segment: interrupted"
    assert posed == [first]
    assert_unchanged(tmp_path, before)
