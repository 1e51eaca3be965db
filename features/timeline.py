"""What a person is doing, in words, over time: runs of frames with the same states, and a
fluent timeline picture."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .fileio import atomic_path
from .fluents import FluentResult


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
    return result.steady | far


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


def _clean(on: np.ndarray, min_run: int) -> np.ndarray:
    """Each state's on/off track with a running median over ``min_run`` frames (flicker at a
    threshold shorter than about half of that is not news for a reader)."""
    if min_run <= 1 or on.shape[0] <= 1:
        return on
    from scipy.ndimage import median_filter  # scipy loads only when there is flicker to clean

    size = min_run if min_run % 2 else min_run + 1
    return median_filter(on.astype(np.uint8), size=(size, 1), mode="nearest").astype(bool)


def _mean_runs(result: FluentResult, spans: dict[tuple[int, int], list[int]]) -> list[Run]:
    runs = []
    for (s, e), states in sorted(spans.items()):
        means = np.nanmean(result.confidence[s : e + 1, states], axis=0) if states else []
        runs.append(Run(s, e, tuple(
            StateInRun(result.state_names[i], result.words[i], float(m))
            for i, m in zip(states, means, strict=True)
        )))  # fmt: skip
    return runs


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
    on = _clean(holding(result, threshold, include_background), min_run)
    frames = on.shape[0]
    spans: dict[tuple[int, int], list[int]] = {}
    padded = np.zeros((frames + 2, on.shape[1]), dtype=np.int8)
    padded[1:-1] = on
    edges = np.diff(padded, axis=0)
    for state in np.flatnonzero(on.any(axis=0)):
        starts = np.flatnonzero(edges[:, state] == 1)
        ends = np.flatnonzero(edges[:, state] == -1) - 1
        for s, e in zip(starts.tolist(), ends.tolist(), strict=True):
            if e - s + 1 >= min_run or frames < min_run:
                spans.setdefault((s, e), []).append(int(state))
    return _mean_runs(result, spans)


def frame_states(
    result: FluentResult, threshold: float = 0.8, include_background: bool = False
) -> list[Run]:
    """The states that hold in each frame, one entry per frame."""
    on = holding(result, threshold, include_background)
    return _mean_runs(result, {(f, f): np.flatnonzero(on[f]).tolist() for f in range(on.shape[0])})


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
    """Names of fluents with no defined value in any frame (their joints are missing)."""
    avail = result.available()
    out: list[str] = []
    for i, spec in enumerate(result.table.specs):
        cols = result.fluent == i
        if not avail[cols].any():
            out.append(spec.name)
    return out


def runs_to_json(runs: list[Run], fps: float) -> list[dict[str, Any]]:
    return [
        {
            "start_frame": r.start,
            "end_frame": r.end,
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
    """A stretch of time drawn above a timeline: seconds ``start_s`` to ``end_s``, its text and
    a colour key (bands with the same key share a colour; None: grey, for "unknown")."""

    start_s: float
    end_s: float
    text: str
    key: str | None = None


def plot_timeline(
    result: FluentResult,
    path: str | Path,
    threshold: float = 0.8,
    title: str = "",
    max_rows: int = 60,
    bands: Sequence[Band] = (),
    band_title: str = "",
) -> Path:
    """A fluent timeline: one row per state that holds at some time, shaded by confidence;
    with ``bands``, a strip above it marks stretches of time (activities, repetitions)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    on = holding(result, threshold)
    share = on.mean(axis=0)
    rows = np.flatnonzero(share > 0)
    if rows.size > max_rows:
        rows = np.sort(rows[np.argsort(-share[rows], kind="stable")[:max_rows]])
    conf = np.nan_to_num(result.confidence[:, rows], nan=0.0).T
    frames = result.confidence.shape[0]
    height = max(2.5, 0.22 * max(len(rows), 1) + 1.2) + (0.8 if bands else 0.0)
    if bands:
        fig, (top, ax) = plt.subplots(
            2, 1, figsize=(11, height), dpi=110, sharex=True,
            gridspec_kw={"height_ratios": [0.8, height - 0.8]},
        )  # fmt: skip
        _draw_bands(top, bands, band_title)
    else:
        fig, ax = plt.subplots(figsize=(11, height), dpi=110)
    if len(rows):
        ax.imshow(
            conf,
            aspect="auto",
            interpolation="nearest",
            cmap="Blues",
            vmin=0,
            vmax=1,
            extent=(0, frames / result.fps, len(rows) - 0.5, -0.5),
        )
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels([result.words[i] for i in rows], fontsize=8)
        for k, i in enumerate(rows):  # mark temporal states so they read apart from postures
            if result.temporal[i]:
                ax.get_yticklabels()[k].set_color("#b35900")
    else:
        ax.text(0.5, 0.5, f"no state holds with confidence >= {threshold}", ha="center",
                transform=ax.transAxes)  # fmt: skip
        ax.set_yticks([])
    ax.set_xlim(0, frames / result.fps)
    ax.set_xlabel("time (s)")
    (top if bands else ax).set_title(
        title or "fluent timeline (shade = confidence; orange labels = motion)", fontsize=10
    )
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, format=out.suffix.lstrip(".").lower() or "png")
    plt.close(fig)
    return out


def _draw_bands(ax: Any, bands: Sequence[Band], title: str) -> None:
    """Coloured spans with their text on an axis of their own."""
    import matplotlib.pyplot as plt

    keys = sorted({b.key for b in bands if b.key is not None})
    palette = plt.get_cmap("tab10")
    colour = {k: palette(i % 10) for i, k in enumerate(keys)}
    for b in bands:
        c = colour.get(b.key, (0.75, 0.75, 0.75, 1.0)) if b.key is not None else "0.8"
        ax.axvspan(b.start_s, b.end_s, ymin=0.05, ymax=0.95, color=c, alpha=0.8, lw=0.5,
                   ec="white")  # fmt: skip
        ax.text(0.5 * (b.start_s + b.end_s), 0.5, b.text, ha="center", va="center",
                fontsize=7, clip_on=True)  # fmt: skip
    ax.set_yticks([])
    ax.set_ylabel(title, fontsize=8, rotation=0, ha="right", va="center")
