"""Pose sequences and the project's pose file format.

File format (``.npz``, written with :func:`save_pose`, read with :func:`load_pose`):

- ``positions``: float array ``(frames, joints, 3)``, metres, right-handed, y up; NaN = missing
- ``joint_names``: string array ``(joints,)`` (canonical: the 33 BlazePose names)
- ``fps``: scalar float, frames per second
- ``confidence`` (optional): float array ``(frames, joints)`` in [0, 1]
- ``skeleton`` (optional): string, the source skeleton (default ``blazepose33``)
- ``metadata`` (optional): a JSON string (object) with anything else: ``label``, ``subject``,
  ``source``, ``correct``, ...
- ``extra_<name>`` (optional): further arrays a producer keeps beside the pose, e.g.
  ``extra_image_landmarks`` ``(frames, 33, 5)`` from the video pose estimator; written with
  ``save_pose(..., extra_arrays=...)``, read with :func:`load_pose_arrays`.
"""

from __future__ import annotations

import json
import os
import tempfile
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import PoseFileError

from .skeleton import BLAZEPOSE_33, CANONICAL_SKELETON, KNOWN_SKELETONS


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
        pos = np.asarray(self.positions, dtype=np.float64)
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "joint_names", tuple(str(j) for j in self.joint_names))
        where = self.source or None
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
        if not np.isfinite(self.fps) or self.fps <= 0:
            raise PoseFileError(f"fps must be a positive number, got {self.fps!r}", where)
        if np.isinf(pos).any():
            raise PoseFileError("positions contain infinite values (use NaN for missing)", where)
        if self.confidence is not None:
            conf = np.asarray(self.confidence, dtype=np.float64)
            if conf.shape != pos.shape[:2]:
                raise PoseFileError(
                    f"confidence must have shape {pos.shape[:2]}, got {conf.shape}", where
                )
            object.__setattr__(self, "confidence", conf)
        if self.skeleton not in KNOWN_SKELETONS:
            raise PoseFileError(
                f"unknown skeleton {self.skeleton!r} (known: {', '.join(sorted(KNOWN_SKELETONS))})",
                where,
            )
        object.__setattr__(self, "metadata", dict(self.metadata))

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
        """The same sequence on the 33 BlazePose joints, in canonical order (NaN where absent)."""
        if self.joint_names == BLAZEPOSE_33:
            return self
        unknown = [n for n in self.joint_names if n not in BLAZEPOSE_33]
        if unknown:
            raise PoseFileError(
                "joint names are not BlazePose landmark names: " + ", ".join(unknown[:5]),
                self.source or None,
            )
        conf = None
        if self.confidence is not None:
            index = {n: i for i, n in enumerate(self.joint_names)}
            conf = np.zeros((self.n_frames, len(BLAZEPOSE_33)))
            for k, n in enumerate(BLAZEPOSE_33):
                if n in index:
                    conf[:, k] = self.confidence[:, index[n]]
        return replace(
            self, positions=self.joints(BLAZEPOSE_33), joint_names=BLAZEPOSE_33, confidence=conf
        )

    def slice_frames(self, start: int, stop: int) -> PoseSequence:
        """Frames ``start`` (inclusive) to ``stop`` (exclusive)."""
        conf = None if self.confidence is None else self.confidence[start:stop]
        meta = dict(self.metadata)
        meta["frame_offset"] = int(meta.get("frame_offset", 0)) + start
        return replace(self, positions=self.positions[start:stop], confidence=conf, metadata=meta)

    def with_metadata(self, **updates: Any) -> PoseSequence:
        meta = dict(self.metadata)
        meta.update(updates)
        return replace(self, metadata=meta)


EXTRA_PREFIX = "extra_"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


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
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz") if path.suffix else path.with_suffix(".npz")
    arrays: dict[str, Any] = {
        "positions": seq.positions.astype(dtype),
        "joint_names": np.array(seq.joint_names, dtype=str),
        "fps": np.float64(seq.fps),
        "skeleton": np.array(seq.skeleton),
        "metadata": np.array(json.dumps({"source": seq.source, **dict(seq.metadata)})),
    }
    if seq.confidence is not None:
        arrays["confidence"] = seq.confidence.astype(dtype)
    for name, value in (extra_arrays or {}).items():
        arrays[EXTRA_PREFIX + name] = np.asarray(value)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise PoseFileError(f"cannot write: {exc.strerror or exc}", path) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez_compressed(fh, **arrays)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a pose file is an ordinary file
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def load_pose(path: str | Path) -> PoseSequence:
    """Read a pose file written by :func:`save_pose` (or by another tool in that format)."""
    path = Path(path)
    if not path.exists():
        raise PoseFileError("no such file", path)
    if path.is_dir():
        raise PoseFileError("is a folder, not a pose file", path)
    try:
        with np.load(path, allow_pickle=False) as data:
            names = set(data.files)
            missing = {"positions", "joint_names", "fps"} - names
            if missing:
                raise PoseFileError("not a pose file: missing " + ", ".join(sorted(missing)), path)
            positions = np.asarray(data["positions"], dtype=np.float64)
            joint_names = tuple(str(j) for j in np.atleast_1d(data["joint_names"]))
            fps = float(np.asarray(data["fps"]).reshape(-1)[0])
            confidence = data["confidence"] if "confidence" in names else None
            skeleton = str(data["skeleton"]) if "skeleton" in names else CANONICAL_SKELETON
            metadata: dict[str, Any] = {}
            if "metadata" in names:
                metadata = json.loads(str(data["metadata"]))
                if not isinstance(metadata, dict):
                    raise PoseFileError("metadata must be a JSON object", path)
    except PoseFileError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, KeyError) as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None
    source = str(metadata.pop("source", "") or path)
    try:
        return PoseSequence(
            positions=positions,
            joint_names=joint_names,
            fps=fps,
            confidence=confidence,
            skeleton=skeleton,
            source=source,
            metadata=metadata,
        )
    except PoseFileError as exc:
        raise PoseFileError(exc.message, path) from None


def load_pose_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """The ``extra_<name>`` arrays of a pose file, by ``name`` (empty if it has none)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            return {
                k[len(EXTRA_PREFIX) :]: np.asarray(data[k])
                for k in data.files
                if k.startswith(EXTRA_PREFIX)
            }
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, KeyError) as exc:
        raise PoseFileError(f"cannot read pose file ({type(exc).__name__}: {exc})", path) from None
