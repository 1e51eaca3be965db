"""What a person is doing, in words, over time: runs of frames with the same states, and a
fluent timeline picture."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

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


def state_runs(
    result: FluentResult,
    threshold: float = 0.8,
    min_run: int = 1,
    include_background: bool = False,
) -> list[Run]:
    """Merge consecutive frames holding the same set of states into runs.

    Runs shorter than ``min_run`` frames are absorbed into the run before them (flicker at a
    threshold is not news for a reader); a merged run lists the states that hold in at least
    half of its frames, with their mean confidence over the run.
    """
    on = holding(result, threshold, include_background)
    frames = on.shape[0]
    if frames == 0:
        return []
    change = np.any(on[1:] != on[:-1], axis=1)
    starts = np.concatenate([[0], np.flatnonzero(change) + 1])
    ends = np.concatenate([starts[1:] - 1, [frames - 1]])
    spans: list[list[int]] = []
    for s, e in zip(starts.tolist(), ends.tolist(), strict=True):
        if spans and (e - s + 1) < min_run:
            spans[-1][1] = e
        else:
            spans.append([s, e])
    runs = []
    for s, e in spans:
        active = np.flatnonzero(on[s : e + 1].mean(axis=0) >= 0.5)
        means = np.nanmean(result.confidence[s : e + 1, active], axis=0) if active.size else []
        runs.append(
            Run(
                s,
                e,
                tuple(
                    StateInRun(result.state_names[i], result.words[i], float(m))
                    for i, m in zip(active, means, strict=True)
                ),
            )
        )
    return runs


def phrase_list(states: tuple[StateInRun, ...], result: FluentResult) -> str:
    """"left knee bent 0.97, bending 0.88, right knee bent 0.95": the subject said once."""
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


def plot_timeline(
    result: FluentResult,
    path: str | Path,
    threshold: float = 0.8,
    title: str = "",
    max_rows: int = 60,
) -> Path:
    """A fluent timeline: one row per state that holds at some time, shaded by confidence."""
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
    height = max(2.5, 0.22 * max(len(rows), 1) + 1.2)
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
    ax.set_xlabel("time (s)")
    ax.set_title(title or "fluent timeline (shade = confidence; orange labels = motion)",
                 fontsize=10)  # fmt: skip
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(out)
    return out
