"""Bad pose files: every one is refused by ``posecbr describe`` with one line naming the file
and the problem, exit status 1, and every file left as it was (issue 15)."""

from __future__ import annotations

import io
import json
import shutil
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.errors import PoseFileError
from features.poses import load_pose
from features.skeleton import BLAZEPOSE_33
from posecbr.cli import main
from tests.badinput import (
    good_arrays,
    good_pose_file,
    pose_file,
    refused,
    refused_in_process,
    snapshot,
)


def _npy_member(shape: tuple[int, ...], payload: bytes) -> bytes:
    """An .npy member whose header declares ``shape`` (float64) followed by ``payload``."""
    buf = io.BytesIO()
    header = {"descr": "<f8", "fortran_order": False, "shape": shape}
    np.lib.format.write_array_header_1_0(buf, header)
    return buf.getvalue() + payload


def _npy_with_header(text: str) -> bytes:
    """An .npy member (format 1.0) whose header is ``text``, padded as numpy pads it."""
    header = text + " " * ((64 - (len(text) + 11) % 64) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode("latin-1")


def _zip_with(path: Path, members: dict[str, bytes], compress: bool = False) -> Path:
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with zipfile.ZipFile(path, "w", method) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return path


def _arrays_as_members(**changes: bytes) -> dict[str, bytes]:
    """The members of a good pose file (each an .npy), some replaced by raw bytes."""
    members = {}
    for key, value in good_arrays().items():
        buf = io.BytesIO()
        np.save(buf, np.asarray(value))
        members[f"{key}.npy"] = buf.getvalue()
    members.update({f"{k}.npy": v for k, v in changes.items()})
    return members


def _truncated(path: Path) -> Path:
    path.write_bytes(path.read_bytes()[:-40])
    return path


def _unknown_compression(path: Path) -> Path:
    """A zip whose member claims compression method 99 (AES, which zipfile cannot read)."""
    _zip_with(path, _arrays_as_members())
    data = bytearray(path.read_bytes())
    for sig, offset in ((b"PK\x03\x04", 8), (b"PK\x01\x02", 10)):
        start = 0
        while (at := data.find(sig, start)) >= 0:
            data[at + offset : at + offset + 2] = (99).to_bytes(2, "little")
            start = at + 4
    path.write_bytes(bytes(data))
    return path


def _bad_crc(path: Path) -> Path:
    """One byte of the stored positions changed: the member's CRC no longer matches."""
    _zip_with(path, _arrays_as_members())
    data = bytearray(path.read_bytes())
    at = data.find(b"positions.npy") + 200  # inside the stored array data
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))
    return path


P = good_arrays()["positions"]
assert isinstance(P, np.ndarray)
NAMES = np.array(BLAZEPOSE_33)

# (case, build the bad file in a folder, words the one line must hold)
CASES: list[tuple[str, Callable[[Path], Path], str]] = [
    # the kinds named in issue 15
    ("confidence stored as strings",
     lambda d: pose_file(d / "c.npz", confidence=np.full(P.shape[:2], "high")),
     "confidence must be real numbers, got text"),
    ("numeric strings as confidence",
     lambda d: pose_file(d / "c.npz", confidence=np.full(P.shape[:2], "0.5")),
     "confidence must be real numbers, got text"),
    ("fps an empty array", lambda d: pose_file(d / "f.npz", fps=np.array([])),
     "fps must be one number, got an empty array"),
    ("fps several values", lambda d: pose_file(d / "f.npz", fps=np.array([30.0, 25.0])),
     "fps must be one number, got 2 values"),
    ("a .npy renamed .npz",
     lambda d: (np.save(d / "p.npy", P), (d / "p.npy").rename(d / "p.npz"), d / "p.npz")[-1],
     "is a single NumPy array (.npy), not a pose file"),
    ("complex positions", lambda d: pose_file(d / "x.npz", positions=P + 1j),
     "positions must be real numbers, got complex numbers"),
    ("positions of 1e300", lambda d: pose_file(d / "x.npz", positions=P * 1e300),
     "not metres of a person's pose"),
    ("positions of 1e5 m (a wrong unit)", lambda d: pose_file(d / "x.npz", positions=P * 1e5),
     "limit 10000 m"),
    ("metadata frame_offset not an integer",
     lambda d: pose_file(d / "m.npz", metadata=json.dumps({"frame_offset": "abc"})),
     "metadata frame_offset must be a whole number >= 0, got 'abc'"),
    ("metadata frame_offset negative",
     lambda d: pose_file(d / "m.npz", metadata=json.dumps({"frame_offset": -3})),
     "frame_offset must be a whole number >= 0, got -3"),
    ("negative confidences",
     lambda d: pose_file(d / "c.npz", confidence=np.full(P.shape[:2], -0.5)),
     "confidence must lie in [0, 1], found -0.5"),
    ("fps of 1e9", lambda d: pose_file(d / "f.npz", fps=1e9),
     "fps must be between 0.01 and 10000 frames per second, got 1e+09"),
    # more kinds
    ("confidence above 1", lambda d: pose_file(d / "c.npz", confidence=np.full(P.shape[:2], 3.0)),
     "confidence must lie in [0, 1], found 3"),
    ("complex confidence",
     lambda d: pose_file(d / "c.npz", confidence=np.full(P.shape[:2], 0.5 + 0.5j)),
     "confidence must be real numbers, got complex numbers"),
    ("confidence of the wrong shape", lambda d: pose_file(d / "c.npz", confidence=np.ones((3, 3))),
     "confidence must have shape (8, 33), got (3, 3)"),
    ("infinite positions",
     lambda d: pose_file(d / "x.npz", positions=np.where(P > 1.6, np.inf, P)),
     "positions contain infinite values (use NaN for missing)"),
    ("positions as text", lambda d: pose_file(d / "x.npz", positions=P.astype(str)),
     "positions must be real numbers, got text"),
    ("positions as true/false", lambda d: pose_file(d / "x.npz", positions=P > 1),
     "positions must be real numbers, got true/false values"),
    ("positions in two dimensions", lambda d: pose_file(d / "x.npz", positions=P.reshape(8, 99)),
     "positions must have shape (frames, joints, 3), got (8, 99)"),
    ("positions pickled as Python objects",
     lambda d: (np.savez(d / "o.npz", positions=P.astype(object), joint_names=NAMES, fps=30.0),
                d / "o.npz")[-1],
     "positions holds Python objects (not read, for safety)"),
    ("more joints than names", lambda d: pose_file(d / "j.npz", joint_names=NAMES[:30]),
     "33 joints in positions but 30 joint names"),
    ("joint names repeated",
     lambda d: pose_file(d / "j.npz", joint_names=np.array(["nose"] * 33)),
     "joint names are not unique"),
    ("joint names as numbers", lambda d: pose_file(d / "j.npz", joint_names=np.arange(33)),
     "joint_names must be text, got numbers"),
    ("joint names in two dimensions",
     lambda d: pose_file(d / "j.npz", joint_names=NAMES.reshape(3, 11)),
     "joint_names must be a list of names, got shape (3, 11)"),
    ("joints that are not BlazePose landmarks",
     lambda d: pose_file(d / "j.npz", joint_names=np.array([f"j{i}" for i in range(33)])),
     "joint names are not BlazePose landmark names: j0"),
    ("nobody in any frame",  # it printed every state unavailable, exit 0
     lambda d: pose_file(d / "n.npz", positions=np.full((8, 33, 3), np.nan)),
     "shows no person (every joint missing in every frame): nothing to describe"),
    ("fps zero", lambda d: pose_file(d / "f.npz", fps=0.0), "fps must be a positive number"),
    ("fps negative", lambda d: pose_file(d / "f.npz", fps=-30.0), "fps must be a positive number"),
    ("fps NaN", lambda d: pose_file(d / "f.npz", fps=np.nan), "fps must be a positive number"),
    ("fps as text", lambda d: pose_file(d / "f.npz", fps="30"), "fps must be a number, got text"),
    ("fps true/false", lambda d: pose_file(d / "f.npz", fps=True),
     "fps must be a number, got true/false values"),
    ("fps of one frame in 1000 s", lambda d: pose_file(d / "f.npz", fps=0.001),
     "fps must be between 0.01 and 10000"),
    ("metadata not JSON", lambda d: pose_file(d / "m.npz", metadata="{label: squat"),
     "metadata is not JSON"),
    ("metadata a JSON list", lambda d: pose_file(d / "m.npz", metadata="[1, 2]"),
     "metadata must be a JSON object"),
    ("metadata nested a hundred thousand deep",
     lambda d: pose_file(d / "m.npz", metadata="[" * 100_000 + "]" * 100_000),
     "metadata is not JSON (nested too deeply)"),
    ("metadata label a list", lambda d: pose_file(d / "m.npz", metadata='{"label": [1, 2]}'),
     "metadata label must be text"),
    ("metadata as numbers", lambda d: pose_file(d / "m.npz", metadata=np.arange(3)),
     "metadata must be text, got numbers"),
    ("metadata two strings", lambda d: pose_file(d / "m.npz", metadata=np.array(["{}", "{}"])),
     "metadata must be one string, got 2"),
    ("metadata not UTF-8",
     lambda d: pose_file(d / "m.npz", metadata=np.array(b'{"label": "\xff"}')),
     "metadata is not UTF-8 text"),
    ("skeleton unknown", lambda d: pose_file(d / "s.npz", skeleton="octopus8"),
     "unknown skeleton 'octopus8'"),
    ("skeleton as a number", lambda d: pose_file(d / "s.npz", skeleton=np.float64(3)),
     "skeleton must be text, got numbers"),
    ("no positions", lambda d: pose_file(d / "n.npz", positions=None),
     "not a pose file: missing positions"),
    ("an empty file", lambda d: (d / "e.npz").write_bytes(b"") and d / "e.npz" or d / "e.npz",
     "cannot read pose file: the file is empty (0 bytes)"),
    ("a text file named .npz",
     lambda d: ((d / "t.npz").write_text("positions,fps\n1,2\n"), d / "t.npz")[-1],
     "cannot read pose file: not an .npz archive"),
    ("an array header that promises a billion frames",
     lambda d: _zip_with(
         d / "h.npz",
         _arrays_as_members(positions=_npy_member((10**9, 33, 3), b"\0" * 64)),
     ),
     "positions declares shape (1000000000, 33, 3) but holds only"),
    ("an array header cut short (the tokenizer's error)",
     lambda d: _zip_with(d / "h.npz", _arrays_as_members(
         positions=_npy_with_header("{'descr': '<f8', 'fortran_order': False, 'shape': (8, 33,"))),
     "cannot read pose file (TokenError"),
    ("an array header that is not a dictionary",
     lambda d: _zip_with(d / "h.npz", _arrays_as_members(positions=_npy_with_header("[1, 2]"))),
     "cannot read pose file (ValueError: Header is not a dictionary"),
    ("a member that is not an array",
     lambda d: _zip_with(d / "r.npz", _arrays_as_members(positions=b"just some bytes")),
     "positions is not a NumPy array"),
    ("an unknown compression method", lambda d: _unknown_compression(d / "u.npz"),
     "cannot read pose file (NotImplementedError"),
    ("a damaged member (bad CRC)", lambda d: _bad_crc(d / "b.npz"),
     "cannot read pose file (BadZipFile: Bad CRC-32"),
    ("a truncated archive",
     lambda d: _truncated(good_pose_file(d / "t.npz")),
     "cannot read pose file"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "build", "needle"), CASES, ids=[c[0] for c in CASES])
def test_bad_pose_file_is_one_clear_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    case: str,
    build: Callable[[Path], Path],
    needle: str,
) -> None:
    path = build(tmp_path)
    line = refused(["describe", str(path)], tmp_path, capsys, needle)
    assert str(path) in line


def test_a_folder_named_like_a_pose_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "clip.npz").mkdir()
    refused(["describe", str(tmp_path / "clip.npz")], tmp_path, capsys, "is a folder")


def _many_frames(path: Path, frames: int) -> Path:
    pos = np.zeros((frames, 33, 3))
    np.savez_compressed(path, positions=pos, joint_names=NAMES, fps=30.0)
    return path


def test_frame_limit_is_checked_before_decompressing_and_can_be_raised(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _many_frames(tmp_path / "long.npz", 5000)
    monkeypatch.setenv("POSECBR_MAX_FRAMES", "1000")
    refused(["describe", str(path)], tmp_path, capsys,
            "5000 frames, over the limit of 1000 (raise it with POSECBR_MAX_FRAMES=N)")  # fmt: skip
    monkeypatch.setenv("POSECBR_MAX_FRAMES", "5000")
    assert load_pose(path).n_frames == 5000


def test_size_limit_refuses_a_file_that_expands_too_far(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # 20000 frames of zeros: 15.8 MB of positions in a file of a few tens of kilobytes
    path = _many_frames(tmp_path / "bomb.npz", 20_000)
    assert path.stat().st_size < 100_000
    monkeypatch.setenv("POSECBR_MAX_POSE_BYTES", "10000000")
    refused(["describe", str(path)], tmp_path, capsys,
            "expands to 15.8 MB, over the limit of 10.0 MB",
            "(raise it with POSECBR_MAX_POSE_BYTES=BYTES)")  # fmt: skip
    monkeypatch.setenv("POSECBR_MAX_POSE_BYTES", "abc")
    refused(["describe", str(path)], tmp_path, capsys,
            "POSECBR_MAX_POSE_BYTES: must be a whole number >= 1, got 'abc'")  # fmt: skip


def test_bad_file_in_a_real_process_exits_1_with_one_line(tmp_path: Path) -> None:
    path = pose_file(tmp_path / "x.npz", positions=P * 1e300)
    refused_in_process(["describe", str(path)], tmp_path, "not metres of a person's pose")


def test_nan_stays_missing_and_is_described(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """NaN is a missing joint, not a bad file: described, with the fluents that need it
    unavailable (the refusal of infinities and huge values leaves NaN alone)."""
    pos = P.copy()
    pos[:, BLAZEPOSE_33.index("left_wrist")] = np.nan
    path = pose_file(tmp_path / "nan.npz", positions=pos, confidence=None)
    before = snapshot(tmp_path)
    assert main(["describe", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "left_arm_bent" in doc["unavailable"] and "right_arm_bent" not in doc["unavailable"]
    assert snapshot(tmp_path) == before


def test_good_file_still_reads_after_the_checks(tmp_path: Path) -> None:
    """The checks refuse only what is wrong: a file at the limits reads."""
    pos = P.copy()
    pos[0, 0] = [9999.0, -9999.0, 0.0]  # within 10 km
    path = pose_file(tmp_path / "ok.npz", positions=pos, fps=10_000.0,
                     confidence=np.where(np.ones(P.shape[:2]) > 0, 1.0, 0.0))  # fmt: skip
    seq = load_pose(path)
    assert seq.fps == 10_000.0 and seq.positions[0, 0, 0] == 9999.0
    with pytest.raises(PoseFileError, match="positions reach 1e"):
        pose_file(tmp_path / "far.npz", positions=np.where(P > 1.6, 10_001.0, P))
        load_pose(tmp_path / "far.npz")


def test_copy_of_a_pose_file_under_an_awkward_name_reads(tmp_path: Path) -> None:
    src = good_pose_file(tmp_path / "a.npz")
    dst = tmp_path / "clip with spaces é.npz"
    shutil.copy(src, dst)
    assert load_pose(dst).n_frames == 8
