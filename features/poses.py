"""Pose sequences and the project's pose file format.

File format (``.npz``, written with :func:`save_pose`, read with :func:`load_pose`):

- ``positions``: float array ``(frames, joints, 3)``, metres, right-handed, y up; NaN = missing
- ``joint_names``: string array ``(joints,)`` (canonical: the 33 BlazePose names; a ``kinect_v2``
  file may name Kinect's 25 joints, mapped by :data:`features.skeleton.SKELETON_JOINTS`)
- ``fps``: scalar float, frames per second
- ``confidence`` (optional): float array ``(frames, joints)`` in [0, 1]
- ``skeleton`` (optional): string, the source skeleton (default ``blazepose33``)
- ``metadata`` (optional): a JSON string (object) with anything else: ``label``, ``subject``,
  ``source`` (what the file was made from, e.g. the video), ``correct``, ... A loaded
  sequence's ``source`` is the file's path; a different ``source`` in the file becomes
  ``metadata["made_from"]``. Saved, the sequence's ``source`` is the file's ``source``; a
  different ``metadata["source"]`` is kept as ``metadata_source``.
- ``extra_<name>`` (optional): further arrays a producer keeps beside the pose, e.g.
  ``extra_image_landmarks`` ``(frames, 33, 5)`` from the video pose estimator; written with
  ``save_pose(..., extra_arrays=...)``, read with :func:`load_pose_arrays`.
"""

from __future__ import annotations

import json
import math
import os
import tokenize
import zipfile
import zlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import ConfigError, DataError, InputError, PoseFileError
from features.fileio import GZIP_MAGIC, SQLITE_MAGIC, as_path, atomic_path, file_head
from features.text import size_words
from features.values import is_number

from .skeleton import (
    BLAZEPOSE_33,
    CANONICAL_SKELETON,
    JOINT_INDEX,
    KNOWN_SKELETONS,
    SKELETON_JOINTS,
)

# What a pose can physically be. A coordinate beyond MAX_COORDINATE_M (10 km) is no person's
# joint in metres but a wrong unit or garbage, and would overflow the geometry into a confident
# but meaningless answer; frame rates outside [MIN_FPS, MAX_FPS] are no camera's or
# motion capture system's.
MAX_COORDINATE_M = 1e4
MIN_FPS = 0.01
MAX_FPS = 10_000.0
# The frames a clip's metadata places it at in its recording (frame_offset, and the frames
# after it) end by 2**53: the whole numbers float64 and JSON readers hold exactly (9e15
# frames, 9,500 years at 30 fps); beyond, the frames stored with its cases (64-bit integers)
# overflowed.
MAX_FRAME_INDEX = 2**53

EXTRACTION_VERSION = 4
"""How ``features.pose_estimation.estimate_video`` turns a video's frames into poses, written
into each pose file's metadata (``extraction_version``) and bumped when that changes for some
videos. None (absent): before it was written, when a variable-frame-rate video was timed as
evenly spaced frames or (once its frame times were read) had every grid time blended from
the frames around it; 2: frames before the first one off the grid taken as they are (as
``posecbr watch`` does); 3: grid times inside a gap of more than a quarter second between
two decoded frames left missing, not blended across it; 4: a landmark the model places inside
the frame but judges not in the picture (presence below 0.5) stored missing, as one placed
outside the frame is. A constant-rate video's frames have been timed the same throughout."""


# Reading limits, checked from the archive's directory and the arrays' headers before anything
# is decompressed (a small compressed file can expand to gigabytes). Raise them with the
# environment variables for a genuinely long recording.
MAX_FRAMES_ENV = "POSECBR_MAX_FRAMES"
MAX_BYTES_ENV = "POSECBR_MAX_POSE_BYTES"
DEFAULT_MAX_FRAMES = 1_000_000  # 9.3 h at 30 fps
DEFAULT_MAX_BYTES = 2 * 1024**3  # uncompressed bytes of the arrays one read decompresses

_KIND_WORDS = {
    "b": "true/false values",
    "c": "complex numbers",
    "O": "Python objects",
    "S": "bytes",
    "U": "text",
    "M": "dates",
    "m": "time spans",
    "V": "raw records",
}


def _real_array(value: Any, what: str, where: str | None) -> np.ndarray:
    """``value`` as a read-only float64 array; PoseFileError unless it holds real numbers. A
    numpy masked array's masked values are missing, NaN (``np.asarray`` would keep the values
    under the mask, read as a joint where the tracker lost it).

    A sequence is frozen and what is worked out from it is cached by the sequence
    (:mod:`features.derived`), so its arrays must not change under it: an array the caller
    could still write to (itself or the memory it views) is copied; a read-only one (a slice
    of another sequence's) is kept as it is.
    """
    try:
        arr = np.asarray(value)
    except ValueError:  # nested lists of different lengths
        raise PoseFileError(
            f"{what} must be an array, got rows of different lengths", where
        ) from None
    if arr.dtype.kind not in "fiu":
        got = _KIND_WORDS.get(arr.dtype.kind, str(arr.dtype))
        raise PoseFileError(f"{what} must be real numbers, got {got}", where)
    out = arr.astype(np.float64, copy=False)
    if np.ma.isMaskedArray(value) and np.ma.getmaskarray(value).any():
        out = np.where(np.ma.getmaskarray(value), np.nan, out)  # masked: missing, not the data
    if out is arr and _writable(arr):
        out = arr.copy()
    out.flags.writeable = False
    return out


def _writable(arr: np.ndarray) -> bool:
    """True when ``arr`` or any array whose memory it views can be written to."""
    base: Any = arr
    while isinstance(base, np.ndarray):
        if base.flags.writeable:
            return True
        base = base.base
    return False


def _check_fps(fps: Any, where: str | None) -> float:
    """``fps`` as a float: a real number (numpy's included, and the 0-d array a pose file's
    ``fps`` reads as), not text that reads as one ("30": as ``LiveSegmenter`` refuses it)."""
    if isinstance(fps, np.ndarray) and fps.ndim == 0 and fps.dtype.kind in "fiu":
        fps = fps[()]
    if not is_number(fps):
        raise PoseFileError(f"fps must be a number, got {fps!r}", where)
    value = float(fps)
    if not (np.isfinite(value) and value > 0):
        raise PoseFileError(f"fps must be a positive number, got {value:g}", where)
    if not MIN_FPS <= value <= MAX_FPS:
        raise PoseFileError(
            f"fps must be between {MIN_FPS:g} and {MAX_FPS:g} frames per second, got {value:g}",
            where,
        )
    return value


def _check_magnitude(pos: np.ndarray, where: str | None) -> None:
    """Refuse infinite or non-physical coordinates (NaN, missing, is fine).

    fmax/fmin reductions skip NaN and allocate nothing the size of ``pos``.
    """
    if pos.size == 0:
        return
    hi = float(np.fmax.reduce(pos, axis=None))
    lo = float(np.fmin.reduce(pos, axis=None))
    if np.isinf(hi) or np.isinf(lo):
        raise PoseFileError("positions contain infinite values (use NaN for missing)", where)
    biggest = max(abs(hi), abs(lo))
    if biggest > MAX_COORDINATE_M:
        raise PoseFileError(
            f"positions reach {biggest:.3g}: not metres of a person's pose (limit "
            f"{MAX_COORDINATE_M:g} m; wrong unit or corrupt data?)",
            where,
        )


def _check_confidence(conf: np.ndarray, where: str | None) -> None:
    """Confidences lie in [0, 1]; NaN (unknown) is allowed."""
    if conf.size == 0:
        return
    hi = float(np.fmax.reduce(conf, axis=None))
    lo = float(np.fmin.reduce(conf, axis=None))
    if lo < 0.0 or hi > 1.0:
        bad = lo if lo < 0.0 else hi
        raise PoseFileError(f"confidence must lie in [0, 1], found {bad:g}", where)


def _unseen_missing(seq: PoseSequence) -> PoseSequence:
    """``seq`` with the positions of joints of confidence exactly 0 set to NaN (missing)."""
    if seq.confidence is None:
        return seq
    unseen = seq.confidence == 0
    if not unseen.any():
        return seq
    pos = seq.positions.copy()
    pos[unseen] = np.nan
    return replace(seq, positions=pos)


@dataclass(frozen=True, eq=False)
class PoseSequence:
    """A 3D stick figure over time.

    positions: ``(frames, joints, 3)`` float64 metres, right-handed, y up; NaN = missing joint.
    confidence: ``(frames, joints)`` in [0, 1] or None where the source gives none.
    """

    positions: np.ndarray
    joint_names: tuple[str, ...]
    fps: float
    confidence: np.ndarray | None = None
    skeleton: str = CANONICAL_SKELETON
    source: str = ""
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "source", _source_text(self.source))
        where = self.source or None
        pos = _real_array(self.positions, "positions", where)
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "joint_names", _joint_names(self.joint_names, where))
        if pos.ndim != 3 or pos.shape[2] != 3:
            raise PoseFileError(
                f"positions must have shape (frames, joints, 3), got {pos.shape}", where
            )
        if pos.shape[0] < 1:
            raise PoseFileError("pose sequence has no frames", where)
        if pos.shape[1] != len(self.joint_names):
            raise PoseFileError(
                f"{pos.shape[1]} joints in positions but {len(self.joint_names)} joint names",
                where,
            )
        if len(set(self.joint_names)) != len(self.joint_names):
            raise PoseFileError("joint names are not unique", where)
        object.__setattr__(self, "fps", _check_fps(self.fps, where))
        _check_magnitude(pos, where)
        if self.confidence is not None:
            conf = _real_array(self.confidence, "confidence", where)
            if conf.shape != pos.shape[:2]:
                raise PoseFileError(
                    f"confidence must have shape {pos.shape[:2]}, got {conf.shape}", where
                )
            _check_confidence(conf, where)
            object.__setattr__(self, "confidence", conf)
        object.__setattr__(self, "skeleton", _skeleton(self.skeleton, where))
        if not isinstance(self.metadata, Mapping):
            raise PoseFileError(
                f"metadata must be a mapping of names, not {type(self.metadata).__name__}",
                where,
            )
        meta = {k: _plain(v) for k, v in self.metadata.items()}
        object.__setattr__(self, "metadata", meta)
        offset = meta.get("frame_offset", 0)
        if isinstance(offset, bool) or not isinstance(offset, int) or offset < 0:
            raise PoseFileError(
                f"metadata frame_offset must be a whole number >= 0, got {offset!r}", where
            )
        if offset + pos.shape[0] > MAX_FRAME_INDEX:
            raise PoseFileError(
                f"metadata frame_offset {offset:.3g} puts the clip's frames past {MAX_FRAME_INDEX}"
                " (2**53), which no recording reaches",
                where,
            )

    @property
    def n_frames(self) -> int:
        return int(self.positions.shape[0])

    @property
    def duration_s(self) -> float:
        return self.n_frames / self.fps

    @property
    def label(self) -> str | None:
        value = self.metadata.get("label")
        return None if value is None else str(value)

    def joint(self, name: str) -> np.ndarray:
        """Positions of one joint, ``(frames, 3)``; all NaN when the skeleton lacks it."""
        try:
            return self.positions[:, self.joint_names.index(name), :]
        except ValueError:
            return np.full((self.n_frames, 3), np.nan)

    def joints(self, names: Sequence[str]) -> np.ndarray:
        """Positions of several joints, ``(frames, len(names), 3)``; NaN where absent."""
        index = {n: i for i, n in enumerate(self.joint_names)}
        out = np.full((self.n_frames, len(names), 3), np.nan)
        for k, n in enumerate(names):
            i = index.get(n)
            if i is not None:
                out[:, k, :] = self.positions[:, i, :]
        return out

    def to_canonical(self) -> PoseSequence:
        """The same sequence on the 33 BlazePose joints, in canonical order (NaN where absent).

        Joint names are BlazePose landmark names, in any case (MediaPipe's ``PoseLandmark``
        names are ``LEFT_SHOULDER``, ...); a skeleton with a declared joint map (Kinect v2,
        :data:`SKELETON_JOINTS`) may name its own joints. PoseFileError for other names, or two
        names for one joint.

        A joint the source says it did not see (confidence exactly 0: OpenPose and COCO-style
        files write such joints as (0, 0, 0)) is missing here, NaN, so no feature reads the
        placeholder as a position; the sequence itself keeps what the file holds."""
        if self.joint_names == BLAZEPOSE_33:
            return _unseen_missing(self)
        own, joint_map = SKELETON_JOINTS.get(self.skeleton, ((), {}))
        mapped = {theirs: blazepose for blazepose, theirs in joint_map.items()}
        index: dict[str, int] = {}  # BlazePose joint -> the file's joint for it
        unknown = []
        for i, name in enumerate(self.joint_names):
            target = name if name in JOINT_INDEX else name.lower()
            if target not in JOINT_INDEX:
                if name not in own:
                    unknown.append(name)
                    continue
                if name not in mapped:
                    continue  # a joint of the skeleton with no BlazePose twin
                target = mapped[name]
            if target in index:
                raise PoseFileError(
                    f"joint names {self.joint_names[index[target]]!r} and {name!r} are both"
                    f" BlazePose's {target}",
                    self.source or None,
                )
            index[target] = i
        if unknown:
            also = f" nor {self.skeleton} joint names" if own else ""
            # another skeleton's own names (a Kinect's by its SDK): say how to declare it
            hint = "".join(
                f' (these are {name} joint names: give skeleton="{name}")'
                for name, (joints, _) in SKELETON_JOINTS.items()
                if name != self.skeleton and set(unknown) <= set(joints)
            )
            raise PoseFileError(
                f"joint names are not BlazePose landmark names{also}: "
                + ", ".join(unknown[:5])
                + hint,
                self.source or None,
            )
        # NaN (positions) and unknown (confidence) for the joints the file lacks
        pos = np.full((self.n_frames, len(BLAZEPOSE_33), 3), np.nan)
        conf = None if self.confidence is None else np.full(pos.shape[:2], np.nan)
        for target, i in index.items():
            k = JOINT_INDEX[target]
            pos[:, k] = self.positions[:, i]
            if conf is not None and self.confidence is not None:
                conf[:, k] = self.confidence[:, i]
        return _unseen_missing(
            replace(self, positions=pos, joint_names=BLAZEPOSE_33, confidence=conf)
        )

    def slice_frames(self, start: int, stop: int | None) -> PoseSequence:
        """Frames ``start`` (inclusive) to ``stop`` (exclusive; None: the end), as Python
        slices them."""
        start = _frame_index(start, "start")
        stop = None if stop is None else _frame_index(stop, "stop")
        start = range(self.n_frames)[start:stop].start
        conf = None if self.confidence is None else self.confidence[start:stop]
        meta = dict(self.metadata)
        meta["frame_offset"] = int(meta.get("frame_offset", 0)) + start
        return replace(self, positions=self.positions[start:stop], confidence=conf, metadata=meta)

    def with_metadata(self, **updates: Any) -> PoseSequence:
        """The sequence with the metadata keys ``updates`` set. ``source`` among them is a
        metadata key (a labels CSV's column of that name), not the recording's own
        :attr:`source`, which names it to the case base (its held-out checks group cases by
        it): name the recording with ``dataclasses.replace(seq, source=...)``."""
        meta = dict(self.metadata)
        meta.update(updates)
        return replace(self, metadata=meta)


def recorded_gaps(meta: Mapping[str, Any]) -> list[tuple[float, float, int, int]]:
    """The gaps left missing that a pose file's metadata records (``gaps_left_missing``):
    (start, end: s; the first row inside and one past the last) each; none when it records
    none, or none it can read."""
    vfr = meta.get("variable_frame_rate")
    record = vfr.get("gaps_left_missing") if isinstance(vfr, Mapping) else None
    out = []
    for gap in record.get("gaps", []) if isinstance(record, Mapping) else []:
        try:
            rows = gap["rows"] or (0, 0)
            out.append((float(gap["start_s"]), float(gap["end_s"]), int(rows[0]), int(rows[1])))
        except (KeyError, TypeError, ValueError, IndexError):
            continue
    return out


def gap_rows(seq: PoseSequence) -> np.ndarray:
    """``(n_frames,)`` bool: the frames of ``seq`` inside a gap of its video left missing
    (:func:`recorded_gaps`: no decoded frame there at all, not a frame without a person), its
    ``frame_offset`` (a slice of the extracted video) taken off the recorded rows."""
    out = np.zeros(seq.n_frames, dtype=bool)
    try:
        offset = int(seq.metadata.get("frame_offset", 0))
    except (TypeError, ValueError):
        offset = 0
    for _start, _end, first, end in recorded_gaps(seq.metadata):
        out[max(0, first - offset) : max(0, end - offset)] = True
    return out


def expect_sequence(seq: Any, name: str = "seq") -> PoseSequence:
    """``seq`` when it is a :class:`PoseSequence`; anything else (an array of positions, a
    list of clips) is an :class:`~features.errors.InputError` naming the argument ``name``
    and saying how to make one, not an AttributeError from inside the computation."""
    if not isinstance(seq, PoseSequence):
        raise InputError(
            f"a PoseSequence is expected, got {type(seq).__name__} (PoseSequence(xyz, names,"
            " fps) makes one of an array)",
            name,
        )
    return seq


def _skeleton(name: Any, where: str | None) -> str:
    """A known skeleton's name, as the project spells it ("Kinect_V2" is ``kinect_v2``);
    PoseFileError for any other."""
    if isinstance(name, str) and name.strip().lower() in KNOWN_SKELETONS:
        return name.strip().lower()
    raise PoseFileError(
        f"unknown skeleton {name!r} (known: {', '.join(sorted(KNOWN_SKELETONS))})", where
    )


def _source_text(source: Any) -> str:
    """``source`` as text: a path (the video a sequence was made from) as its text, as a
    loaded sequence's source is; PoseFileError for anything else, which no reader of the
    source (errors, ``save_pose``'s JSON, the store) could use."""
    if isinstance(source, os.PathLike):
        return os.fspath(source)  # type: ignore[no-any-return]
    if not isinstance(source, str):
        raise PoseFileError(f"source must be text or a path, got {source!r}")
    return source


def _joint_names(names: Any, where: str | None) -> tuple[str, ...]:
    """``names`` as a tuple of text; PoseFileError for one string or names that are not text
    (bytes would become ``"b'nose'"`` and match no joint)."""
    if isinstance(names, str | bytes):
        raise PoseFileError("joint_names must be a sequence of names, got one string", where)
    if not isinstance(names, Iterable):
        raise PoseFileError(
            f"joint_names must be a sequence of names, got {type(names).__name__}", where
        )
    out = []
    for name in names:
        if isinstance(name, bytes):
            name = name.decode("utf-8", "replace")
        elif not isinstance(name, str | np.str_):
            raise PoseFileError(f"joint names must be text, got {name!r}", where)
        out.append(str(name))
    return tuple(out)


def _plain(value: Any) -> Any:
    """A numpy scalar in metadata as the Python number or text it holds (JSON can store it)."""
    return value.item() if isinstance(value, np.generic) else value


def _frame_index(value: Any, what: str) -> int:
    """A frame index given as any whole number (``np.int64`` too); ConfigError otherwise."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        raise ConfigError(f"must be a whole number of frames, got {value!r}", what)
    return int(value)


EXTRA_PREFIX = "extra_"


def save_pose(
    seq: PoseSequence,
    path: str | Path,
    *,
    extra_arrays: Mapping[str, np.ndarray] | None = None,
    float32: bool = False,
) -> Path:
    """Write ``seq`` as a pose file, atomically (a temporary name renamed into place).

    ``extra_arrays``: optional named arrays stored beside the pose as ``extra_<name>``.
    ``float32``: store positions and confidence in single precision (half the size; readers
    cast back to float64).
    """
    dtype = np.float32 if float32 else np.float64
    path = as_path(path, "path")
    if path.is_dir():
        raise PoseFileError("is a folder: give a file name for the pose file", path)
    if path.suffix.lower() != ".npz":  # x.NPZ keeps its name, as casebase export's
        path = path.with_suffix(path.suffix + ".npz") if path.suffix else path.with_suffix(".npz")
    arrays: dict[str, Any] = {
        "positions": seq.positions.astype(dtype),
        "joint_names": np.array(seq.joint_names, dtype=str),
        "fps": np.float64(seq.fps),
        "skeleton": np.array(seq.skeleton),
        "metadata": np.array(_metadata_text(seq, path)),
    }
    if seq.confidence is not None:
        arrays["confidence"] = seq.confidence.astype(dtype)
    for name, value in (extra_arrays or {}).items():
        arrays[EXTRA_PREFIX + name] = np.asarray(value)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return path


def _metadata_text(seq: PoseSequence, path: Path) -> str:
    """The metadata JSON: the sequence's ``source`` under "source" (what the file was made
    from); a different ``metadata["source"]`` is kept apart as "metadata_source", not let
    hide it."""
    meta = dict(seq.metadata)
    other = meta.pop("source", None)
    if other is not None and other != seq.source and "metadata_source" not in meta:
        meta["metadata_source"] = other
    try:
        return json.dumps({**meta, "source": seq.source}, default=_plain_json)
    except (TypeError, ValueError) as exc:
        raise PoseFileError(f"metadata cannot be stored as JSON ({exc})", path) from None


def _plain_json(value: Any) -> Any:
    """What JSON cannot store as it is: numpy numbers and arrays as Python's."""
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def read_limits() -> tuple[int, int]:
    """(max frames, max uncompressed bytes) for reading a pose file, from the environment
    (:data:`MAX_FRAMES_ENV`, :data:`MAX_BYTES_ENV`) or the defaults."""
    out = []
    for env, default in ((MAX_FRAMES_ENV, DEFAULT_MAX_FRAMES), (MAX_BYTES_ENV, DEFAULT_MAX_BYTES)):
        text = os.environ.get(env, "").strip()
        if not text:
            out.append(default)
            continue
        try:
            value = int(text)
        except ValueError:
            value = 0
        if value < 1:
            raise ConfigError(f"must be a whole number >= 1, got {text!r}", env)
        out.append(value)
    return out[0], out[1]


_NPY_MAGIC = b"\x93NUMPY"
_READ_ERRORS = (
    OSError,
    ValueError,
    EOFError,
    KeyError,
    RuntimeError,  # an encrypted member
    NotImplementedError,  # an unknown compression method
    OverflowError,
    tokenize.TokenError,  # numpy re-reads a malformed array header with the tokenizer
    zipfile.BadZipFile,
    zlib.error,
)


def _member(zf: zipfile.ZipFile, names: set[str], key: str) -> zipfile.ZipInfo | None:
    """The archive member ``np.load`` reads for ``key`` (``key`` itself or ``key.npy``);
    ``names``: the archive's member names."""
    for name in (key, key + ".npy"):
        if name in names:
            return zf.getinfo(name)
    return None


def _npy_header(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path: Path) -> tuple[Any, ...]:
    """Shape of one ``.npy`` member, read from its header alone; refused when the header
    promises more data than the member holds (numpy would allocate the promised size)."""
    key = info.filename.removesuffix(".npy")
    with zf.open(info) as fh:
        if fh.read(len(_NPY_MAGIC)) != _NPY_MAGIC:
            raise PoseFileError(f"{key} is not a NumPy array", path)
        fh.seek(0)
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise PoseFileError(f"{key}: unsupported .npy format version {version}", path)
        header = fh.tell()
    if dtype.hasobject:
        raise PoseFileError(f"{key} holds Python objects (not read, for safety)", path)
    need = math.prod(shape) * dtype.itemsize
    if header + need > info.file_size:
        raise PoseFileError(
            f"{key} declares shape {shape} but holds only {info.file_size} bytes (corrupt?)",
            path,
        )
    return tuple(shape)


def _not_a_zip(head: bytes) -> str:
    """Why a pose file that is no zip archive, its first bytes ``head``, cannot be read: an
    empty file and a gzip-compressed one said as such, where both were "truncated, or another
    format?"."""
    if not head:
        return "cannot read pose file: the file is empty (0 bytes)"
    if head.startswith(GZIP_MAGIC):  # clip.npz.gz, or gzip clip.npz kept as its name
        return "cannot read pose file: it is gzip-compressed (gunzip it first)"
    return "cannot read pose file: not an .npz archive (truncated, or another format?)"


def check_archive(path: Path, keys: Sequence[str] | None = None) -> None:
    """Check a pose file before decompressing anything: a zip archive (not a renamed
    ``.npy``), whose arrays ``keys`` (None: all) are well-formed ``.npy`` members within the
    frame and size limits (:func:`read_limits`). Raises PoseFileError naming the file."""
    max_frames, max_bytes = read_limits()
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(_NPY_MAGIC))
        if head == _NPY_MAGIC:
            raise PoseFileError(
                "is a single NumPy array (.npy), not a pose file (an .npz archive of"
                " positions, joint_names, fps)",
                path,
            )
        if not zipfile.is_zipfile(path):
            raise PoseFileError(_not_a_zip(head), path)
        with zipfile.ZipFile(path) as zf:
            members = set(zf.namelist())
            wanted = [n.removesuffix(".npy") for n in members] if keys is None else keys
            infos = [i for i in (_member(zf, members, k) for k in wanted) if i is not None]
            total = sum(i.file_size for i in infos)
            if total > max_bytes:
                raise PoseFileError(
                    f"expands to {size_words(total)}, over the limit of {size_words(max_bytes)}"
                    f" (raise it with {MAX_BYTES_ENV}=BYTES)",
                    path,
                )
            for info in infos:
                shape = _npy_header(zf, info, path)
                if info.filename.removesuffix(".npy") == "positions" and shape:
                    if shape[0] > max_frames:
                        raise PoseFileError(
                            f"{shape[0]} frames, over the limit of {max_frames}"
                            f" (raise it with {MAX_FRAMES_ENV}=N)",
                            path,
                        )
    except PoseFileError:
        raise
    except _READ_ERRORS as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None


_POSE_KEYS = ("positions", "joint_names", "fps", "confidence", "skeleton", "metadata")


def holds_poses(path: str | Path) -> bool:
    """Whether ``path`` is an archive holding a pose file's ``positions`` (read from its zip
    directory alone): a recording that an output of another kind must not replace."""
    try:
        if not Path(path).is_file() or not zipfile.is_zipfile(path):
            return False
        with zipfile.ZipFile(path) as zf:
            return _member(zf, set(zf.namelist()), "positions") is not None
    except _READ_ERRORS:
        return False


def check_not_poses(path: str | Path, what: str) -> None:
    """Refuse ``path`` for an output of another kind (``what``: "report", "JSON output")
    when it holds a pose file or a SQLite database (a case base store): a recording, as
    likely one the output was made from, or a case base would be replaced by a page or a
    table (a slip for ``report.html``), as ``casebase export`` refuses a pose file."""
    if holds_poses(path):
        raise DataError(
            f"is a pose file: the {what} would replace that recording (name another file)", path
        )
    if Path(path).is_file() and file_head(path, len(SQLITE_MAGIC)) == SQLITE_MAGIC:
        raise DataError(
            f"is a SQLite database (a case base file?): the {what} would replace it (name"
            " another file)",
            path,
        )


def _text_array(value: np.ndarray, what: str, path: Path) -> np.ndarray:
    """A text array (``str``, or UTF-8 ``bytes``) as ``str``."""
    if value.dtype.kind == "S":
        try:
            return np.char.decode(value, "utf-8")
        except UnicodeDecodeError:
            raise PoseFileError(f"{what} is not UTF-8 text", path) from None
    if value.dtype.kind != "U":
        got = _KIND_WORDS.get(value.dtype.kind, "numbers")
        raise PoseFileError(f"{what} must be text, got {got}", path)
    return value


def _one_text(value: np.ndarray, what: str, path: Path) -> str:
    text = _text_array(value, what, path)
    if text.size != 1:
        raise PoseFileError(f"{what} must be one string, got {text.size}", path)
    return str(text.reshape(-1)[0])


def _one_fps(value: np.ndarray, path: Path) -> float:
    if value.size != 1:
        got = "an empty array" if value.size == 0 else f"{value.size} values"
        raise PoseFileError(f"fps must be one number, got {got}", path)
    if value.dtype.kind not in "fiu":
        got = _KIND_WORDS.get(value.dtype.kind, str(value.dtype))
        raise PoseFileError(f"fps must be a number, got {got}", path)
    return _check_fps(value.reshape(-1)[0], str(path))


def _metadata(value: np.ndarray, path: Path) -> dict[str, Any]:
    text = _one_text(value, "metadata", path)
    try:
        meta = json.loads(text)
    except (ValueError, RecursionError) as exc:
        reason = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise PoseFileError(f"metadata is not JSON ({reason})", path) from None
    if not isinstance(meta, dict):
        raise PoseFileError("metadata must be a JSON object", path)
    for key in ("label", "subject", "source"):
        v = meta.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, str | int | float)):
            raise PoseFileError(f"metadata {key} must be text, got {json.dumps(v)[:40]}", path)
    return meta


def _read_arrays(path: Path) -> dict[str, np.ndarray]:
    check_archive(path, _POSE_KEYS)
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = {"positions", "joint_names", "fps"} - set(data.files)
            if missing:
                raise PoseFileError("not a pose file: missing " + ", ".join(sorted(missing)), path)
            return {k: np.asarray(data[k]) for k in _POSE_KEYS if k in data.files}
    except PoseFileError:
        raise
    except _READ_ERRORS as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None


def load_pose(path: str | Path) -> PoseSequence:
    """Read a pose file written by :func:`save_pose` (or by another tool in that format).

    Every problem (not an archive, a renamed ``.npy``, arrays of the wrong kind or shape,
    an fps that is not one number, non-physical positions, malformed metadata, a file that
    would expand past the limits of :func:`read_limits`) raises PoseFileError naming the file.
    """
    path = as_path(path, "path")
    if not path.exists():
        raise PoseFileError("no such file", path)
    if path.is_dir():
        raise PoseFileError("is a folder, not a pose file", path)
    arrays = _read_arrays(path)
    names = _text_array(arrays["joint_names"], "joint_names", path)
    if names.ndim != 1:
        raise PoseFileError(f"joint_names must be a list of names, got shape {names.shape}", path)
    fps = _one_fps(arrays["fps"], path)
    skeleton = CANONICAL_SKELETON
    if "skeleton" in arrays:
        skeleton = _one_text(arrays["skeleton"], "skeleton", path)
    metadata = _metadata(arrays["metadata"], path) if "metadata" in arrays else {}
    metadata = _as_loaded(metadata, path)
    source = str(path)
    try:
        return PoseSequence(
            positions=arrays["positions"],
            joint_names=tuple(str(j) for j in names),
            fps=fps,
            confidence=arrays.get("confidence"),
            skeleton=skeleton,
            source=source,
            metadata=metadata,
        )
    except PoseFileError as exc:
        raise PoseFileError(exc.message, path) from None


def pose_file_length(path: str | Path) -> tuple[int, float]:
    """A pose file's frame count and frame rate, from the header of ``positions`` and the
    ``fps`` array alone (the positions are not decompressed): what a label file must fit,
    checked before the recording is read. Raises PoseFileError naming the file, as
    :func:`load_pose` would, for a file it cannot read that far."""
    path = Path(path)
    if not path.is_file():
        raise PoseFileError("no such file", path)
    check_archive(path, ("positions", "fps"))
    try:
        with zipfile.ZipFile(path) as zf:
            members = set(zf.namelist())
            positions, fps = _member(zf, members, "positions"), _member(zf, members, "fps")
            missing = [k for k, m in (("positions", positions), ("fps", fps)) if m is None]
            if positions is None or fps is None:
                raise PoseFileError("not a pose file: missing " + ", ".join(missing), path)
            shape = _npy_header(zf, positions, path)
        with np.load(path, allow_pickle=False) as data:
            rate = _one_fps(np.asarray(data["fps"]), path)
    except PoseFileError:
        raise
    except _READ_ERRORS as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None
    if len(shape) != 3 or shape[2] != 3:
        raise PoseFileError(f"positions must have shape (frames, joints, 3), got {shape}", path)
    if shape[0] < 1:
        raise PoseFileError("pose sequence has no frames", path)
    return int(shape[0]), rate


def pose_file_metadata(path: str | Path) -> dict[str, Any]:
    """A pose file's metadata alone (the positions are not decompressed); ``{}`` when it has
    none. Raises PoseFileError naming the file, as :func:`load_pose` would, for a file it
    cannot read that far."""
    path = Path(path)
    if not path.is_file():
        raise PoseFileError("no such file", path)
    check_archive(path, ("metadata",))
    try:
        with np.load(path, allow_pickle=False) as data:
            if "metadata" not in data.files:
                return {}
            value = np.asarray(data["metadata"])
    except _READ_ERRORS as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None
    return _metadata(value, path)


def loaded_metadata(path: str | Path) -> dict[str, Any]:
    """:func:`pose_file_metadata` as the sequence :func:`load_pose` reads holds it (the
    file's positions not decompressed)."""
    return _as_loaded(pose_file_metadata(path), Path(path))


def _as_loaded(metadata: dict[str, Any], path: Path) -> dict[str, Any]:
    """A pose file's stored metadata as its sequence holds it: the file is the clip's name,
    what it was made from (a video: the ``source`` stored) its provenance, ``made_from``."""
    made_from = str(metadata.pop("source", "") or "")
    if made_from and made_from != str(path) and "made_from" not in metadata:
        metadata["made_from"] = made_from
    return metadata


def load_pose_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """The ``extra_<name>`` arrays of a pose file, by ``name`` (empty if it has none)."""
    path = Path(path)
    if not path.is_file():
        raise PoseFileError("no such file", path)
    check_archive(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            return {
                k[len(EXTRA_PREFIX) :]: np.asarray(data[k])
                for k in data.files
                if k.startswith(EXTRA_PREFIX)
            }
    except _READ_ERRORS as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None
