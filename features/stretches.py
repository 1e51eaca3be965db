"""A recording labelled over time cut into one clip per labelled stretch, its label file checked
against the frames known before the recording is read."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

from .clips import POSE_SUFFIXES, VIDEO_SUFFIXES, Clip, clip_suffix, load_clip
from .label_tracks import (
    LabelTrack,
    assumed_rate,
    check_count,
    frame_labels,
    labelled_stretches,
    read_label_names,
    read_label_track,
)
from .poses import PoseSequence, pose_file_length, pose_file_metadata


def split_by_track(seq: PoseSequence, track: LabelTrack) -> list[tuple[PoseSequence, str]]:
    """One clip per labelled stretch of the recording ``seq``, with its label (frames shared
    with the recording, :func:`features.derived.stretch`)."""
    names = read_label_names(track.names) if track.names is not None else None
    labels = read_label_track(track.path, names)
    return split_by_labels(seq, labels, track.block_s, track.path)


def split_by_labels(
    seq: PoseSequence, labels: Sequence[str], block_s: float | None, where: str | Path
) -> list[tuple[PoseSequence, str]]:
    """One clip per labelled stretch of the recording ``seq`` labelled by ``labels`` (one per
    frame, or one per ``block_s`` seconds; a count that does not fit is a DataError naming
    ``where``), with its label (frames shared with the recording,
    :func:`features.derived.stretch`)."""
    from .derived import stretch

    recording = Path(seq.source).name if seq.source else ""
    rate = assumed_rate(seq.metadata)
    per_frame = frame_labels(list(labels), seq.n_frames, seq.fps, block_s, where, recording, rate)
    return [(stretch(seq, a, b), lab) for a, b, lab in labelled_stretches(per_frame)]


def check_track(path: Path, track: LabelTrack, fps: float | None = None) -> None:
    """What can be checked of a recording labelled over time before it is read: its label
    file (and names) read, and the count fitted to its frames where they are known
    (:func:`check_fits_before_read`). DataError naming the label file, as
    :func:`split_by_track`."""
    names = read_label_names(track.names) if track.names is not None else None
    labels = read_label_track(track.path, names)
    check_fits_before_read(path, len(labels), track.block_s, track.path, path.name, fps)


def check_fits_before_read(
    path: Path,
    n_labels: int,
    block_s: float | None,
    where: str | Path,
    recording: str = "",
    fps: float | None = None,
) -> None:
    """Refuse ``n_labels`` labels (one per frame, or per ``block_s`` seconds) that do not fit
    the recording ``path`` where its frames are known before it is read, in the words
    :func:`frame_labels` gives once it is (naming ``where`` and ``recording``): a pose
    file's (the header's frame count and rate, :func:`features.poses.pose_file_length`),
    and a constant-rate video's (its container's count and rate,
    :func:`features.pose_estimation.video.frames_before_decoding`: the pose model not run
    for minutes first). ``fps``: the rate it is read at (``--fps``). Other recordings (a
    variable-frame-rate video, mocap) are checked once read."""
    if clip_suffix(path) in POSE_SUFFIXES:
        n_frames, rate = pose_file_length(path)
        said = assumed_rate(pose_file_metadata(path)) if fps is None else ""
        check_count(n_labels, (n_frames, n_frames), rate if fps is None else fps, block_s,
                    where, recording, said)  # fmt: skip
    elif clip_suffix(path) in VIDEO_SUFFIXES:
        try:
            from features.pose_estimation.video import frames_before_decoding
        except ImportError:
            return  # no pose estimator: refused as such when read
        known = frames_before_decoding(path)
        if known is not None:
            fewest, most, rate = known
            check_count(n_labels, (fewest, most), rate if fps is None else fps, block_s,
                        where, recording)  # fmt: skip


def iter_recording(
    path: str | Path, track: LabelTrack, subject: str | None = None
) -> Iterator[Clip]:
    """The labelled stretches of one recording (anything :func:`load_clip` reads) as clips."""
    return recording_clips(load_clip(path), track, subject)


def recording_clips(
    seq: PoseSequence, track: LabelTrack, subject: str | None = None
) -> Iterator[Clip]:
    """The labelled stretches of the recording ``seq`` as clips."""
    return stretch_clips(split_by_track(seq, track), subject)


def stretch_clips(
    stretches: Iterable[tuple[PoseSequence, str]], subject: str | None = None
) -> Iterator[Clip]:
    """Labelled stretches (:func:`split_by_track`, :func:`split_by_labels`) as clips of
    ``subject``, each with its label in its metadata."""
    for part, label in stretches:
        part = part.with_metadata(label=label, subject=subject)
        yield Clip(seq=part, label=label, subject=subject, extras={})
