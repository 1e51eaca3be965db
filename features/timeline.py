"""What a person is doing, in words, over time: runs of frames with the same states, and a
fluent timeline picture.

:func:`describe_clip` evaluates a clip's fluents a piece at a time
(:func:`features.fluents.evaluate_chunks`) and keeps only the runs, which fluents are
available and a picture's worth of columns, so a clip of a million frames needs about the
memory of its poses; :func:`state_runs` and :func:`frame_states` do the same for a result in
memory.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .errors import ConfigError, DataError
from .fileio import atomic_path
from .fluents import CHUNK_FRAMES, Backend, FluentResult, FluentTable, evaluate_chunks
from .poses import PoseSequence

PLOT_COLUMNS = 2_000  # a picture is about a thousand pixels wide
#: the timeline's shade where a state is unknown (its joints missing): not the white of 0
UNSEEN = "#d9d9d9"


@dataclass(frozen=True)
class StateInRun:
    name: str
    words: str
    confidence: float  # mean over the run


@dataclass(frozen=True)
class Run:
    """Frames ``start``..``end`` (inclusive) in which the same states hold."""

    start: int
    end: int
    states: tuple[StateInRun, ...]


def background(result: FluentResult) -> np.ndarray:
    """``(n_states,)`` bool: states that hold most of the time and say little on their own —
    no motion ("bend steady") and two joints "far from" each other."""
    far = np.array([n.endswith(".far_from") for n in result.state_names])
    quiet: np.ndarray = result.steady | far
    return quiet


def holding(
    result: FluentResult, threshold: float = 0.8, include_background: bool = False
) -> np.ndarray:
    """``(frames, n_states)`` bool: the state holds with confidence >= ``threshold``.

    Background states (:func:`background`) are left out unless asked for.
    """
    with np.errstate(invalid="ignore"):
        on = result.confidence >= threshold
    if not include_background:
        on &= ~background(result)
    return on


def _median_size(min_run: int) -> int:
    return min_run if min_run % 2 else min_run + 1


def _clean(on: np.ndarray, min_run: int, defined: np.ndarray | None = None) -> np.ndarray:
    """Each state's on/off track with a running median over ``min_run`` frames (flicker at a
    threshold shorter than about half of that is not news for a reader), of the frames where
    the state is ``defined`` (all when None): a frame whose joints are missing is no vote
    against the state (a knee tracked every other frame was a state that never held for
    five frames, and vanished from the description). A frame with no defined frame near it
    stays off."""
    if min_run <= 1 or on.shape[0] <= 1:
        return on
    if defined is None:
        defined = np.ones_like(on, dtype=bool)
    # The median of 0/1 votes is their majority (scipy's median_filter, which cannot leave
    # out the undefined frames): counted over the defined frames alone, the ends repeated.
    half = _median_size(min_run) // 2
    votes = np.pad(
        np.stack([on & defined, defined]).astype(np.int32),
        ((0, 0), (half, half), (0, 0)),
        mode="edge",
    )
    sums = np.cumsum(votes, axis=1)
    sums = np.concatenate([np.zeros_like(sums[:, :1]), sums], axis=1)
    window = sums[:, 2 * half + 1 :] - sums[:, : -(2 * half + 1)]
    cleaned = 2 * window[0] > window[1]
    # An undefined frame is shown only inside a run: with a defined frame holding the state
    # after cleaning within the window's half on either side (never at the edge of a stretch
    # in which the person, or the joint, was not seen).
    n = on.shape[0]
    frames = np.arange(n)[:, None]
    before = np.maximum.accumulate(np.where(defined, frames, -1), axis=0)
    after = np.minimum.accumulate(np.where(defined, frames, n)[::-1], axis=0)[::-1]
    cols = np.arange(on.shape[1])[None, :]
    near = (before >= 0) & (frames - before <= half) & (after < n) & (after - frames <= half)
    inside = near & cleaned[before.clip(0), cols] & cleaned[after.clip(max=n - 1), cols]
    return np.asarray(cleaned & (defined | inside))


@dataclass
class Timeline:
    """What :func:`describe_clip` finds in a clip.

    ``runs``: spans of frames with the states holding over exactly that span (empty when the
    runs went to a per-frame callback); ``available`` ``(n_states,)``: the state is defined in
    some frame; ``share`` ``(n_states,)``: the fraction of frames in which it holds
    (background states left out); ``columns`` ``(bins, n_states)``: the mean confidence over
    the frames the state is defined in, in each of up to :data:`PLOT_COLUMNS` equal stretches
    of the clip, NaN where it is defined in none (missing stays missing), for the picture;
    ``layout``: the states' names and words (a result with no frames).
    """

    n_frames: int
    fps: float
    layout: FluentResult
    runs: list[Run]
    available: np.ndarray
    share: np.ndarray
    columns: np.ndarray

    def unavailable(self) -> list[str]:
        """Names of fluents with no defined value in any frame: their joints are missing, or the
        angle is undefined (an arm held exactly sideways has no projection on the sagittal plane,
        SPEC.md), in every frame."""
        return [
            spec.name
            for i, spec in enumerate(self.layout.table.specs)
            if not self.available[self.layout.fluent == i].any()
        ]


class _RunTracker:
    """Runs of each state's cleaned on/off track, fed in consecutive pieces.

    An open run carries its start and the sum and count of its defined confidences, so a run
    over many pieces is averaged as if the track were whole.
    """

    def __init__(self, n_states: int, n_frames: int, min_run: int) -> None:
        self.start = np.full(n_states, -1)
        self.total = np.zeros(n_states)
        self.count = np.zeros(n_states)
        self.n_frames = n_frames
        self.min_run = min_run
        self.spans: dict[tuple[int, int], list[tuple[int, float]]] = {}

    def add(self, first: int, on: np.ndarray, conf: np.ndarray) -> None:
        """Frames ``first``.. of the tracks: ``on`` and ``conf`` ``(frames, n_states)``."""
        frames = on.shape[0]
        defined = ~np.isnan(conf)
        csum = np.zeros((frames + 1, on.shape[1]))
        np.cumsum(np.where(defined, conf, 0.0), axis=0, out=csum[1:])
        ccount = np.zeros((frames + 1, on.shape[1]))
        np.cumsum(defined, axis=0, out=ccount[1:])
        was_open = self.start >= 0
        track = np.concatenate([was_open[None].astype(np.int8), on.astype(np.int8)])
        edges = np.diff(track, axis=0)  # +1: a run starts at that frame; -1: ended before it
        for state in np.flatnonzero(on.any(axis=0) | was_open):
            starts = np.flatnonzero(edges[:, state] == 1).tolist()
            ends = (np.flatnonzero(edges[:, state] == -1) - 1).tolist()
            if was_open[state]:
                starts.insert(0, -1)  # goes on from the last piece
            if len(ends) < len(starts):
                ends.append(frames - 1)  # goes on into the next piece, or ends the clip
            for s, e in zip(starts, ends, strict=True):
                total = csum[e + 1, state] - csum[max(s, 0), state]
                count = ccount[e + 1, state] - ccount[max(s, 0), state]
                begin = first + s
                if s < 0:
                    total += self.total[state]
                    count += self.count[state]
                    begin = int(self.start[state])
                if e == frames - 1 and on[-1, state]:
                    self.start[state] = begin
                    self.total[state], self.count[state] = total, count
                else:
                    self.start[state] = -1
                    self._close(int(state), begin, first + e, total, count)

    def finish(self) -> None:
        """Close the runs still open at the end of the clip."""
        for state in np.flatnonzero(self.start >= 0):
            s = int(self.start[state])
            self._close(int(state), s, self.n_frames - 1, self.total[state], self.count[state])
            self.start[state] = -1

    def _close(self, state: int, s: int, e: int, total: float, count: float) -> None:
        if e - s + 1 >= self.min_run:
            mean = float(total / count) if count else float("nan")
            self.spans.setdefault((s, e), []).append((state, mean))

    def runs(self, layout: FluentResult) -> list[Run]:
        """Every run, by span; within a span, states in table order."""
        out = []
        for (s, e), states in sorted(self.spans.items()):
            out.append(Run(s, e, tuple(
                StateInRun(layout.state_names[i], layout.words[i], m) for i, m in sorted(states)
            )))  # fmt: skip
        return out


def _frame_runs(
    first: int, on: np.ndarray, conf: np.ndarray, layout: FluentResult
) -> Iterator[Run]:
    for k in range(on.shape[0]):
        yield Run(first + k, first + k, tuple(
            StateInRun(layout.state_names[i], layout.words[i], float(conf[k, i]))
            for i in np.flatnonzero(on[k])
        ))  # fmt: skip


def timeline_of(seq: PoseSequence, threshold: float = 0.8) -> FluentResult | Timeline:
    """What :func:`plot_timeline` draws for ``seq`` (states holding at ``threshold``): its
    fluents when they are computed already, or the clip is no longer than
    :data:`~features.fluents.CHUNK_FRAMES` frames; else its timeline computed that many frames
    at a time (:func:`describe_clip`: the same picture in the memory of one piece; a
    503-s recording at 120 fps took 1.6 GB to draw whole, three times what segmenting it
    took)."""
    from .derived import fluents_of, is_cached

    canonical = seq.to_canonical()
    if seq.n_frames <= CHUNK_FRAMES or is_cached(canonical, "fluents"):
        return fluents_of(canonical)
    return describe_clip(
        canonical, threshold=threshold, chunk_frames=CHUNK_FRAMES, progress_desc="fluent timeline"
    )


def _pieces(
    clip: PoseSequence | FluentResult,
    table: FluentTable | None,
    margin: int,
    chunk_frames: int,
    backend: Backend,
) -> Iterator[tuple[int, int, int, FluentResult]]:
    """Pieces of the fluents of a clip, or an evaluated result as one piece."""
    if isinstance(clip, FluentResult):
        yield 0, clip.n_frames, 0, clip
    else:
        yield from evaluate_chunks(clip, table, chunk_frames, margin, backend)


def _check_options(threshold: float, min_run: int) -> None:
    """A state holds at confidence >= ``threshold``, in (0, 1] (the command's
    ``--min-confidence``); ``min_run``: a whole number of frames >= 1."""
    if (
        isinstance(threshold, bool)
        or not isinstance(threshold, int | float | np.integer | np.floating)
        or not 0.0 < float(threshold) <= 1.0
    ):
        raise ConfigError(f"must be in (0, 1], got {threshold!r}", "threshold")
    if isinstance(min_run, bool) or not isinstance(min_run, int | np.integer) or min_run < 1:
        raise ConfigError(f"must be a whole number >= 1, got {min_run!r}", "min_run")


def describe_clip(
    clip: PoseSequence | FluentResult,
    table: FluentTable | None = None,
    threshold: float = 0.8,
    min_run: int = 1,
    include_background: bool = False,
    per_frame: Callable[[Run], None] | None = None,
    chunk_frames: int = CHUNK_FRAMES,
    backend: Backend = "numba",
    progress_desc: str | None = None,
) -> Timeline:
    """When each fluent state of ``clip`` holds, ``chunk_frames`` frames at a time.

    The runs are those of :func:`state_runs`; with ``per_frame``, each frame's states go to
    it in order instead (as :func:`frame_states` lists them) and ``runs`` stays empty.
    ``backend``: of :func:`features.fluents.evaluate`; ``progress_desc``: a progress bar of
    the pieces, so described (none when None).
    """
    _check_options(threshold, min_run)
    n = clip.n_frames
    min_run = max(1, min(min_run, n))  # a state holding the whole clip is a run of it
    margin = 0 if per_frame is not None or min_run <= 1 else _median_size(min_run) // 2
    bins = max(1, min(n, PLOT_COLUMNS))
    tracker: _RunTracker | None = None
    pieces = _pieces(clip, table, margin, chunk_frames, backend)
    if progress_desc is not None:
        from .progress import progress

        pieces = progress(pieces, progress_desc, math.ceil(n / chunk_frames), "piece", False)
    for start, stop, first, result in pieces:
        if tracker is None:
            layout = replace(result, confidence=result.confidence[:0])
            n_states = len(result.state_names)
            tracker = _RunTracker(n_states, n, min_run)
            available = np.zeros(n_states, dtype=bool)
            held = np.zeros(n_states)
            sums, counts = np.zeros((bins, n_states)), np.zeros((bins, n_states))
        own = slice(start - first, stop - first)
        conf = result.confidence[own]
        on = holding(result, threshold, include_background)
        available |= ~np.all(np.isnan(conf), axis=0)
        held += holding(result, threshold)[own].sum(axis=0)
        column = np.arange(start, stop) * bins // n
        defined = ~np.isnan(conf)  # a frame where the state is unknown is no frame of 0
        np.add.at(sums, column, np.where(defined, conf, 0.0))
        np.add.at(counts, column, defined)
        if per_frame is not None:
            for run in _frame_runs(start, on[own], conf, layout):
                per_frame(run)
        else:
            raw = on[own]  # a run's confidence: its mean where the state held, not in the
            # flicker the cleaning filled (a state shown is one that held)
            known = ~np.isnan(result.confidence)
            tracker.add(start, _clean(on, min_run, known)[own], np.where(raw, conf, np.nan))
    assert tracker is not None  # a clip has at least one frame
    tracker.finish()
    return Timeline(
        n_frames=n,
        fps=layout.fps,
        layout=layout,
        runs=[] if per_frame is not None else tracker.runs(layout),
        available=available,
        share=held / n,
        columns=np.where(counts > 0, sums / np.maximum(counts, 1.0), np.nan),
    )


def state_runs(
    result: FluentResult,
    threshold: float = 0.8,
    min_run: int = 1,
    include_background: bool = False,
) -> list[Run]:
    """When each state holds: one entry per span of frames, listing the states that hold over
    exactly that span ("frames 17–61: left knee bent 1.00, right knee bent 1.00"), ordered by
    start frame. Spans shorter than ``min_run`` frames are dropped after cleaning each state's
    track with a running median of ``min_run`` frames.
    """
    return describe_clip(result, None, threshold, min_run, include_background).runs


def frame_states(
    result: FluentResult, threshold: float = 0.8, include_background: bool = False
) -> list[Run]:
    """The states that hold in each frame, one entry per frame."""
    runs: list[Run] = []
    describe_clip(result, None, threshold, 1, include_background, per_frame=runs.append)
    return runs


def phrase_list(states: tuple[StateInRun, ...], result: FluentResult) -> str:
    """ "left knee bent 0.97, bending 0.88, right knee bent 0.95": the subject said once."""
    parts: list[str] = []
    last_subject = None
    specs = result.table.specs
    index = {n: i for i, n in enumerate(result.state_names)}
    for st in states:
        spec = specs[int(result.fluent[index[st.name]])]
        if spec.kind == "angle" and spec.subject == last_subject:
            text = st.words[len(spec.subject) + 1 :]
        else:
            text = st.words
        last_subject = spec.subject if spec.kind == "angle" else None
        parts.append(f"{text} {st.confidence:.2f}")
    return ", ".join(parts)


def unavailable_fluents(result: FluentResult) -> list[str]:
    """Names of fluents with no defined value in any frame: their joints are missing, or the
    angle is undefined (an arm held exactly sideways has no projection on the sagittal plane,
    SPEC.md), in every frame."""
    avail = result.available()
    out: list[str] = []
    for i, spec in enumerate(result.table.specs):
        cols = result.fluent == i
        if not avail[cols].any():
            out.append(spec.name)
    return out


def runs_to_json(runs: list[Run], fps: float) -> list[dict[str, Any]]:
    """The spans for machines: frames ``[start_frame, end_frame)``, end exclusive (as
    ``segment``'s, ``reps``' and a labels CSV's; the text's "frames 0–12" is inclusive), and
    seconds ``[start_s, end_s)``."""
    return [
        {
            "start_frame": r.start,
            "end_frame": r.end + 1,
            "start_s": round(r.start / fps, 4),
            "end_s": round((r.end + 1) / fps, 4),
            "states": [
                {"name": s.name, "words": s.words, "confidence": round(s.confidence, 4)}
                for s in r.states
            ],
        }
        for r in runs
    ]


@dataclass(frozen=True)
class Band:
    """A stretch of time drawn above a timeline: seconds ``start_s`` to ``end_s``, its text, a
    colour key (bands with the same key share a colour; None: grey, for "unknown") and a
    moment marked within it."""

    start_s: float
    end_s: float
    text: str
    key: str | None = None
    mark_s: float | None = None
    """A moment within the band marked by a small black triangle at its foot (a
    repetition's far point), or None."""


def picture_format(path: str | Path) -> str:
    """The format a picture named ``path`` is written in, from its suffix (``png``, ``svg``,
    ``pdf``, ...: what matplotlib writes). A name whose suffix matplotlib does not write
    (``timeline.txt``, none at all) is refused naming the file: the picture would be a PNG
    under a name that says otherwise."""
    from matplotlib.backend_bases import FigureCanvasBase

    fmt = Path(path).suffix.lower().lstrip(".")
    formats = FigureCanvasBase.get_supported_filetypes()
    if fmt not in formats:
        raise DataError(
            "the picture must be a file name ending in a format matplotlib writes"
            f" (.png, .svg, .pdf, ...; got {Path(path).suffix or 'no suffix'!r})",
            path,
        )
    return fmt


PICTURE_KEY = "posecbr"
"""The PNG text chunk that says which command drew a picture of which recording
(:func:`picture_mark`)."""


def picture_mark(command: str, recording: str | Path) -> str:
    """What a PNG picture ``command`` draws of ``recording`` is marked with (its
    :data:`PICTURE_KEY` text chunk): the command and a digest of the recording's resolved
    path (not the path itself, which a picture passed on would give away). ``--plot DIR``
    replaces a picture so marked, drawn before by the same command of the same recording,
    and refuses any other file at that name (:func:`posecbr.arguments.check_folder_pictures`)."""
    from .fileio import path_digest

    return f"{command} {path_digest(recording)}"


def png_mark(path: Path) -> str | None:
    """The :data:`PICTURE_KEY` text chunk of the PNG file ``path`` (Pillow reads the chunks
    before the image data on opening, not the image): None when it is no PNG, has none, or
    cannot be read."""
    from PIL import Image

    try:
        with Image.open(path) as picture:
            if picture.format != "PNG":
                return None
            mark = picture.info.get(PICTURE_KEY)
    except (OSError, ValueError, Image.DecompressionBombError):
        return None
    return mark if isinstance(mark, str) else None


def plot_timeline(
    result: FluentResult | Timeline,
    path: str | Path,
    threshold: float = 0.8,
    title: str = "",
    max_rows: int = 60,
    bands: Sequence[Band] = (),
    band_title: str = "",
    band_keys: Sequence[str] = (),
    band_legend: Literal["never", "hidden", "always"] = "never",
    mark: str | None = None,
) -> Path:
    """A fluent timeline: one row per state that holds at some time, shaded by confidence (a
    long clip's frames averaged into up to :data:`PLOT_COLUMNS` columns); with ``bands``, a
    strip above it marks stretches of time (activities, repetitions), each key in its colour
    of :func:`band_colours` (``band_keys``: every key in the order that fixes their colours, a
    case base's activities, so an activity has one colour in every picture of that case
    base); ``band_legend``: a legend beside the strip names every key's colour, "always" or
    when a band is too narrow for its text ("hidden"). ``title`` is followed by what the
    shades and colours mean (:func:`_key`). Written atomically, in the format of the file's
    suffix (a suffix matplotlib does not know:
    :func:`picture_format` refuses it); a PNG holds ``mark`` (:func:`picture_mark`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tl = result if isinstance(result, Timeline) else describe_clip(result, threshold=threshold)
    rows = np.flatnonzero(tl.share > 0)
    if rows.size > max_rows:
        rows = np.sort(rows[np.argsort(-tl.share[rows], kind="stable")[:max_rows]])
    conf = tl.columns[:, rows].T
    height = max(2.5, 0.22 * max(len(rows), 1) + 1.2) + (0.8 if bands else 0.0)
    if bands:
        fig, (top, ax) = plt.subplots(
            2, 1, figsize=(11, height), dpi=110, sharex=True,
            gridspec_kw={"height_ratios": [0.8, height - 0.8]},
        )  # fmt: skip
        placed = _draw_bands(top, bands, band_title, band_keys)
    else:
        fig, ax = plt.subplots(figsize=(11, height), dpi=110)
    if len(rows):
        ax.imshow(
            conf,
            aspect="auto",
            interpolation="nearest",
            cmap=matplotlib.colormaps["Blues"].with_extremes(bad=UNSEEN),
            vmin=0,
            vmax=1,
            extent=(0, tl.n_frames / tl.fps, len(rows) - 0.5, -0.5),
        )
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels([tl.layout.words[i] for i in rows], fontsize=8)
        for k, i in enumerate(rows):  # mark temporal states so they read apart from postures
            if tl.layout.temporal[i]:
                ax.get_yticklabels()[k].set_color("#b35900")
    else:
        ax.text(0.5, 0.5, f"no state holds with confidence >= {threshold}", ha="center",
                transform=ax.transAxes)  # fmt: skip
        ax.set_yticks([])
    ax.set_xlim(0, tl.n_frames / tl.fps)
    ax.set_xlabel("time (s)")
    heading = (top if bands else ax).set_title(
        f"{title or 'fluent timeline'} ({'; '.join(_key(tl, rows))})", fontsize=10
    )
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    if fit_title(heading):
        fig.tight_layout()  # room for its lines
    if bands:
        fit_texts(top, placed)
        if band_legend != "never" and _legend(top, placed, band_keys, band_legend == "always"):
            fig.tight_layout()  # room for it, the bands narrower: their texts fitted again
            fit_texts(top, placed)
    out = Path(path)
    fmt = picture_format(out)
    try:
        with atomic_path(out) as tmp:
            marks = {PICTURE_KEY: mark} if mark is not None and fmt == "png" else None
            fig.savefig(tmp, format=fmt, metadata=marks)
    finally:
        plt.close(fig)
    return out


def band_colours(bands: Sequence[Band], keys: Sequence[str] = ()) -> dict[str, Any]:
    """The colour of every key of ``bands``: its place in ``keys`` (the keys of ``bands``
    not among them after those, sorted) in :func:`band_palette`. Before, the keys of one
    picture were numbered among themselves: of two recordings segmented by one case base,
    jumping jacks were blue beside squats and orange beside incline push-ups, and the eighth
    activity of a picture was tab10's grey, read as the grey of unknown."""
    given = list(dict.fromkeys(keys))
    rest = sorted({b.key for b in bands if b.key is not None} - set(given))
    palette = band_palette()
    return {k: palette[i % len(palette)] for i, k in enumerate(given + rest)}


UNKNOWN_COLOUR = "0.8"
"""The colour of a band with no key (unknown, nobody in view): a light grey, no key's (the
overlays box an unknown stretch's word in it too)."""


def band_palette() -> list[tuple[float, float, float, float]]:
    """The colours of bands: matplotlib's tab10, then tab20's lighter shades, with no grey
    (grey is unknown's): 18 colours, and a 19th key takes the first again."""
    import matplotlib.pyplot as plt

    dark = [plt.get_cmap("tab10")(i) for i in range(10) if i != 7]
    light = [plt.get_cmap("tab20")(i) for i in range(1, 20, 2) if i != 15]
    return dark + light


def _draw_bands(
    ax: Any, bands: Sequence[Band], title: str, keys: Sequence[str] = ()
) -> list[tuple[Any, Band]]:
    """Coloured spans with their text on an axis of their own; each text with its band."""
    colour = band_colours(bands, keys)
    placed = []
    for b in bands:
        c = colour[b.key] if b.key is not None else UNKNOWN_COLOUR
        ax.axvspan(b.start_s, b.end_s, ymin=0.05, ymax=0.95, color=c, alpha=0.8, lw=0.5,
                   ec="white")  # fmt: skip
        text = ax.text(0.5 * (b.start_s + b.end_s), 0.5, b.text, ha="center", va="center",
                       fontsize=7, clip_on=True)  # fmt: skip
        placed.append((text, b))
    marks = [b.mark_s for b in bands if b.mark_s is not None]
    if marks:  # at the strip's foot, below the texts
        ax.plot(marks, [0.13] * len(marks), ls="none", marker="^", ms=5, color="black",
                clip_on=True, gid="band marks")  # fmt: skip
    ax.set_ylim(0, 1)
    ax.set_yticks([])
    ax.set_ylabel(title, fontsize=8, rotation=0, ha="right", va="center")
    return placed


def fit_texts(ax: Any, placed: Sequence[tuple[Any, Band]]) -> None:
    """Each band's text as drawn on ``ax`` (its limits and size final) kept within its band:
    on one line, else broken at spaces into two or three, each at the usual size then one
    smaller; hidden where none fits (neighbouring texts of short bands would run into each
    other)."""
    renderer = ax.figure.canvas.get_renderer()
    for text, band in placed:
        text.set_visible(True)
        left, right = ax.transData.transform([(band.start_s, 0.0), (band.end_s, 0.0)])[:, 0]
        tries = [(_in_lines(band.text, lines), size) for lines in (1, 2, 3) for size in (7, 6)]
        for words, size in tries:
            text.set_text(words)
            text.set_fontsize(size)
            if text.get_window_extent(renderer).width <= abs(right - left):
                break
        else:
            text.set_visible(False)


def _legend(
    ax: Any, placed: Sequence[tuple[Any, Band]], keys: Sequence[str], always: bool = False
) -> bool:
    """A legend of the keys' colours beside the band strip ``ax`` when the text of a band
    with a key is hidden (:func:`fit_texts`: too narrow for it), or ``always``; True when
    drawn. Before, a
    long recording's short segments were bands of colour with nothing to tell which
    activity each colour is: in 5 minutes, a segment under about 10 s lost its name."""
    from matplotlib.patches import Patch

    hidden = not all(text.get_visible() or band.key is None for text, band in placed)
    if not (always or hidden) or all(band.key is None for _, band in placed):
        return False
    drawn = [b for _, b in placed]
    colour = band_colours(drawn, keys)
    shown_keys = {b.key for b in drawn}
    handles = [Patch(color=c, alpha=0.8, label=k) for k, c in colour.items() if k in shown_keys]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.05), fontsize=7,
              frameon=False, ncol=max(1, math.ceil(len(handles) / 5)), borderaxespad=0.0,
              handlelength=1.2, labelspacing=0.2)  # fmt: skip
    return True


def _key(tl: Timeline, rows: np.ndarray) -> list[str]:
    """What the shades and colours of a timeline picture mean, for its title: "orange labels
    = motion" only when a motion state's row is drawn. Before, a picture given a title of its
    own (``segment``'s, ``reps``', ``describe``'s: the recording's name) lost the key of the
    untitled picture: ``reps --plot`` drew its row labels in orange, unexplained."""
    key = ["shade = confidence", "grey = unknown"]
    if any(tl.layout.temporal[i] for i in rows):
        key.append("orange labels = motion")
    return key


def fit_title(title: Any) -> bool:
    """The title ``title`` (its figure laid out) kept within the figure: broken at spaces
    into as few lines as fit, a word too long for any line (a file name) broken within
    itself; True when it was broken. Before, a long file name ran the title off the picture:
    "...tuesday_morning.npz: activities and repetition counts over the fluent timeline
    (grey = u"."""
    fig = title.figure
    renderer = fig.canvas.get_renderer()
    whole = title.get_text()

    def fits() -> bool:
        box = title.get_window_extent(renderer)
        return bool(box.x0 >= 0 and box.x1 <= fig.bbox.width)

    if fits():
        return False
    for lines in range(2, 6):
        for hard in (False, True):
            width = math.ceil(len(whole) / lines)
            title.set_text("\n".join(textwrap.wrap(whole, width, break_long_words=hard)))
            if fits():
                return True
    return True


def _in_lines(text: str, lines: int) -> str:
    """``text`` broken at spaces into about ``lines`` lines of one length (a word unbroken)."""
    width = math.ceil(len(text) / lines)
    return "\n".join(textwrap.wrap(text, width, break_long_words=False))
