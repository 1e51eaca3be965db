"""Reading one recording for ``reps``, ``segment`` and ``watch``: any clip the loaders read
(pose file, video, BVH, UI-PRMD file) or an AMC file with its skeleton; the frame rate may be
given (an AMC file carries none); and the options that say how to read recordings."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from features.errors import ConfigError, DataError
from features.fileio import path_exists
from posecbr.arguments import path_arg

# A command evaluating one clip in a new process (describe, reps): below this many frames the
# numpy reference computes the fluents and joint angles sooner than numba loads its compiled
# kernels (measured for the whole describe command: 73 frames 0.3 s vs 0.7 s of CPU, 5000
# frames 0.72 s vs 0.81 s, 10000 frames 1.04 s vs 0.93 s). Both give the same confidences
# (tests/test_fluents_fast.py).
NUMPY_BELOW_FRAMES = 5000


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """``--asf`` and ``--fps`` for recordings that need them."""
    p.add_argument(
        "--asf",
        type=path_arg,
        metavar="FILE.asf",
        help="skeleton of an .amc recording (default: the one beside it)",
    )
    p.add_argument(
        "--fps",
        type=float,
        help="frame rate of the recording, frames per second: the rate its frames were taken"
        " at, not a resampling (a recording thinned to every 60th frame of 120 fps: --fps 2;"
        " default: the file's; an AMC file carries none: the rate its HDM05 name states, else"
        " 120)",
    )


def add_sensor_option(p: argparse.ArgumentParser) -> None:
    """``--sensor``: which of a UI-PRMD folder's two recordings to read."""
    p.add_argument(
        "--sensor",
        choices=("kinect", "vicon"),
        default=None,
        help="a UI-PRMD folder's sensor (default kinect)",
    )


def sensor_for(sensor: str | None, sources: list[Path]) -> str:
    """``--sensor`` (kinect when not given); refused when given for data of which no source
    is a UI-PRMD folder (it chooses nothing there: it was taken without a word)."""
    from features.datasets import is_uiprmd_folder

    if sensor is not None and not any(is_uiprmd_folder(p) for p in sources):
        raise DataError(
            f"chooses a UI-PRMD folder's sensor; {sources[0] if sources else 'the data'} is not"
            " one",
            "--sensor",
        )
    return sensor or "kinect"


def check_fps(fps: float | None) -> None:
    """``--fps`` within the frame rates a pose sequence takes (refused as the option's, not
    blamed on the file it would be given to)."""
    from features.poses import MAX_FPS, MIN_FPS

    if fps is not None and not (MIN_FPS <= fps <= MAX_FPS):
        raise DataError(f"must be a frame rate in [{MIN_FPS:g}, {MAX_FPS:g}], got {fps:g}", "--fps")


def check_asf(asf: Path | None, recordings: list[Path]) -> None:
    """``--asf`` refused when no recording is an AMC file (it would be ignored)."""
    if asf is not None and not any(p.suffix.lower() == ".amc" for p in recordings):
        raise ConfigError(f"goes with an AMC recording, not {recordings[0].name}", "--asf")


def load_recording(path: Path, asf: Path | None = None, fps: float | None = None) -> Any:
    """The recording at ``path`` as a canonical PoseSequence (frame rate ``fps`` if given)."""
    from features.readers.asfamc import read_asf_amc

    check_fps(fps)
    if not path_exists(path):
        raise DataError("no such file", path)
    if not path.is_file() and not path.is_dir():  # reading a pipe waits for a writer
        raise DataError("is a pipe, socket or device, not a recording", path)
    if path.suffix.lower() == ".amc" and asf is not None:
        seq = read_asf_amc(asf, path, fps=fps)
    else:
        seq = load_clip_naming_asf(path)
    # messages name the file the user gave (a pose file remembers the clip it came from)
    seq = dataclasses.replace(seq, source=str(path))
    if fps is not None:  # the rate given, not the one a file's reader assumed
        seq = dataclasses.replace(seq, fps=float(fps)).with_metadata(fps_source="given")
    return seq.to_canonical()


def load_clip_as_asked(path: Path, asf: Path | None, fps: float | None) -> Any:
    """The clip at ``path`` as ``describe`` and ``dad`` read it: as every clip is read
    (:func:`features.clips.load_clip`), or, given ``--asf`` or ``--fps``, as
    :func:`load_recording` reads a recording with them."""
    if asf is None and fps is None:
        return load_clip_naming_asf(path)
    return load_recording(path, asf, fps)


def load_clip_naming_asf(path: Path) -> Any:
    """:func:`features.clips.load_clip` for a command that takes ``--asf``: an AMC file
    with no skeleton to be found beside it is refused with the way to give it one here
    (``--asf FILE.asf``), not with ``convert``'s."""
    from features.clips import NoSkeletonError, load_clip

    try:
        return load_clip(path)
    except NoSkeletonError as e:
        raise e.naming("--asf") from None


#: a rate assumed, told how to state it: ``--fps`` (how one recording file is read), or for
#: a dataset's files, which the commands read as they are, converting them with it
GIVE_FPS = "--fps"


def give_fps_by_converting(data: Any) -> str:
    """How a dataset ``data``'s recordings are given their frame rate: converted with it
    (``train``, ``compare`` and ``classify`` take no ``--fps`` for a folder or labels CSV)."""
    import shlex

    from features.text import shown

    named = shown(shlex.quote(str(data)))  # as pasted into a shell
    return f"posecbr convert {named} --fps N --out DIR (then use its pose files)"


#: a recording whose reader assumed its rate: (its source, the rate, where from)
Assumed = tuple[str, float, str]


def assumed_rates(seqs: Iterable[Any]) -> list[Assumed]:
    """The clips of ``seqs`` (pose sequences) whose reader assumed the frame rate
    (:func:`features.label_tracks.assumed_rate`), for :func:`assumed_rates_note` (which
    counts a recording's labelled stretches as the one recording)."""
    from features.label_tracks import assumed_rate

    return [(str(s.source), float(s.fps), assumed_rate(s.metadata)) for s in seqs
            if assumed_rate(s.metadata)]  # fmt: skip


def assumed_rates_note(found: Iterable[Assumed], how: str = GIVE_FPS) -> str | None:
    """The note saying that the frame rate of recordings read was assumed by the reader of
    their files, not read from them or given (an AMC file carries none: read at the CMU and
    HDM05 rate), as ``convert`` says it: their times, periods, speeds and repetitions per
    second all stand on it; ``how``: how to give another (``--fps``, or converting a
    dataset, :func:`give_fps_by_converting`). Once for a command, however many files: one
    names it, several are counted with one named (a folder of 200 AMC files is one line).
    A pose file's assumption stays in its metadata, said when ``convert`` wrote it, and
    not again at every read. None when no rate was assumed."""
    from features.clips import POSE_SUFFIXES
    from features.text import shown

    named: dict[str, tuple[float, str]] = {}
    for source, fps, why in found:
        if Path(source).suffix.lower() not in POSE_SUFFIXES:
            named.setdefault(source, (fps, why))
    if not named:
        return None
    source, (fps, why) = next(iter(named.items()))
    if len(named) == 1:
        return (
            f"note: {shown(source)}: read at {fps:g} fps ({why}); give its rate with {how} if"
            " it was recorded at another"
        )
    return (
        f"note: {len(named)} recordings read at a frame rate assumed, not stated in their"
        f" files (e.g. {shown(source)}: {fps:g} fps, {why}); give theirs with {how} if they"
        " were recorded at another"
    )


def note_assumed_rates(found: Iterable[Assumed], how: str = GIVE_FPS) -> None:
    """Say :func:`assumed_rates_note` on stderr, if anything (``segment``, ``reps``,
    ``describe``, ``dad``, ``classify`` and ``compare`` say it; ``train`` once it has
    trained, with its other notes)."""
    note = assumed_rates_note(found, how)
    if note is not None:
        print(note, file=sys.stderr)


def note_low_rate(source: Any, fps: float, estimated: bool) -> None:
    """Say on stderr when the frame rate ``fps`` of the recording or video ``source`` is too
    low to follow every movement a repetition can be: one repeating in less than two frames'
    time (the shortest, :data:`features.repetitions.MIN_PERIOD_S`, needs 5 fps) is seen as a
    slower one or not at all (a mocap recording of jogging read at 2 fps counted 2 of its 7
    steps without a word). ``segment`` and ``reps`` say it, and ``watch`` of a video before it
    plays.

    Below 10 fps (:func:`features.repetitions.glitch_free_fps`), though followed, a quick
    repetition's far point is held for less than the two frames a running median of three
    keeps: where the counter reads one (:func:`features.repetitions.median_width`: always
    for poses a pose model ``estimated``, whose one-frame glitches it drops; for others,
    motion capture, from 7.5 fps), the counts are noted as well; motion capture, read below
    7.5 fps with no median and no glitch to drop, counts about as well as at 30 fps: not
    noted (docs/measurements.md, "Figures behind the code's rules: Repetitions counted below
    10 fps")."""
    from features.repetitions import MIN_PERIOD_S, glitch_free_fps, median_width
    from features.text import shown

    shortest = 2.0 / fps
    if shortest > MIN_PERIOD_S + 1e-9:
        print(
            f"note: {shown(source)}: at {fps:g} fps a movement that repeats within"
            f" {shortest:.2g} s (two frames) is not followed: its repetitions may be"
            f" miscounted (the shortest, {MIN_PERIOD_S:g} s, needs {2.0 / MIN_PERIOD_S:g} fps)",
            file=sys.stderr,
        )
    elif fps < glitch_free_fps() - 1e-9 and median_width(fps, estimated) > 1:
        print(
            f"note: {shown(source)}: at {fps:g} fps the running median of three frames that"
            " drops a one-frame glitch of a pose model drops a quick repetition's far point"
            f" as well (the shortest repetition, {MIN_PERIOD_S:g} s, stays out there"
            f" {MIN_PERIOD_S / 2:g} s: two frames need {glitch_free_fps():g} fps): its"
            " repetitions may be miscounted",
            file=sys.stderr,
        )
