"""The pictures of a comparison (matplotlib, Agg): accuracy with Wilson intervals, confusion
matrices, feature prevalence before and after trimming (paper fig. 4), and fluent timelines.

Every picture is drawn on its own: one that fails is reported (``picture X failed: ...``) and
the others are still drawn, because a picture is never worth the results it shows.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from features.errors import DataError
from features.fileio import atomic_path
from features.progress import progress

from .data import example_clips
from .results import (
    CompareResults,
    ConfusionPicture,
    MethodResult,
    Pictures,
    Prevalence,
    Scores,
    TimelinePicture,
)

if TYPE_CHECKING:  # a type alone: the comparison's modules (its methods, scikit-learn's
    # estimators among them) are not for report, which draws from the results
    from .compare import CompareRun

T = TypeVar("T")


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, path: Path) -> Path:
    """Write ``fig`` to ``path`` as PNG, atomically."""
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", bbox_inches="tight")
    finally:
        _pyplot().close(fig)
    return path


def short(name: str, n: int) -> str:
    """``name`` cut to ``n`` characters keeping both ends (class names often differ at the end:
    "standing_shoulder_abduction" vs "standing_shoulder_extension")."""
    if len(name) <= n:
        return name
    head = (n - 1) // 3
    return name[:head] + "…" + name[-(n - 1 - head) :]


def safe_name(s: str) -> str:
    """``s`` as a file-name stem: letters, digits, '-' and '_' only, at most 60 characters."""
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in s)[:60]


def plot_accuracy(results: CompareResults, path: str | Path) -> Path:
    """Horizontal bars: accuracy of every method that ran, with its Wilson 95 % interval;
    interpretable methods blue, peers grey, the best interpretable one outlined."""
    plt = _pyplot()
    ok = results.scored()
    if not ok:
        raise DataError("no method produced results", "results")
    acc = np.array([s.accuracy for _, s in ok]) * 100
    # Bars never reach below zero, even for an interval written by an older version that
    # excluded its own proportion by rounding.
    lo = np.maximum(acc - np.array([s.accuracy_ci[0] for _, s in ok]) * 100, 0.0)
    hi = np.maximum(np.array([s.accuracy_ci[1] for _, s in ok]) * 100 - acc, 0.0)
    fig, ax = plt.subplots(figsize=(8, 0.42 * len(ok) + 1.3), dpi=110)
    y = np.arange(len(ok))
    colours = ["#3b6fb6" if m.interpretable else "#9a9a9a" for m, _ in ok]
    bars = ax.barh(y, acc, xerr=np.vstack([lo, hi]), color=colours, capsize=3)
    for bar, (m, _) in zip(bars, ok, strict=True):
        if m.name == results.best_interpretable:
            bar.set_edgecolor("black")
            bar.set_linewidth(1.6)
    for yi, a in zip(y, acc, strict=True):  # inside the bar's base, clear of the CI whisker
        ax.text(1.5, yi, f"{a:.1f}", va="center", fontsize=8, color="white", weight="bold")
    ax.set_yticks(y)
    ax.set_yticklabels([m.name for m, _ in ok], fontsize=9)
    ax.invert_yaxis()
    ax.set_xlim(0, 108)
    ax.set_xlabel("accuracy (%) with 95 % Wilson interval")
    ax.set_title(
        f"accuracy by configuration ({results.cv.scheme}, {results.cv.n_folds} folds)",
        fontsize=10,
    )
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    return _save(fig, Path(path))


def _annotate_counts(ax: Any, cm: np.ndarray, norm: np.ndarray) -> None:
    n = cm.shape[0]
    for i in range(n):
        for j in range(n):
            if cm[i, j]:
                colour = "white" if norm[i, j] > 0.5 else "black"
                ax.text(j, i, f"{int(cm[i, j])}", ha="center", va="center", fontsize=7,
                        color=colour)  # fmt: skip


def plot_confusion(name: str, scores: Scores, classes: Sequence[str], path: str | Path) -> Path:
    """Row-normalised confusion matrix ``(classes, classes)`` of one method (counts in the
    cells)."""
    plt = _pyplot()
    cm = np.asarray(scores.confusion, dtype=float)
    rows = cm.sum(axis=1, keepdims=True)
    norm = np.divide(cm, rows, out=np.zeros_like(cm), where=rows > 0)
    n = len(classes)
    size = max(4.0, 0.5 * n + 2.5)
    fig, ax = plt.subplots(figsize=(size + 1.0, size), dpi=110)
    im = ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
    _annotate_counts(ax, cm, norm)
    labels = [short(c, 26) for c in classes]
    ax.set_xticks(range(n))
    ax.set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(n))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(f"{name}: accuracy {100 * scores.accuracy:.1f} %", fontsize=10)
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="share of the true class")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_prevalence(prev: Prevalence, path: str | Path) -> Path:
    """Feature prevalence per activity, initial and trimmed case base side by side (heatmaps
    ``(features, activities)``, shared colour scale)."""
    plt = _pyplot()
    acts, feats = prev.activities, prev.features
    height = max(3.5, 0.2 * len(feats) + 2.2)
    width = max(9.0, 0.9 * len(acts) + 6.0)
    fig, axes = plt.subplots(1, 2, figsize=(width, height), dpi=110, sharey=True)
    labels = [short(a, 24) for a in acts]
    im = None
    for ax, mat, title, counts in (
        (axes[0], prev.initial, "initial case base", prev.cases_initial),
        (axes[1], prev.trimmed, f"trimmed (keep {100 * prev.trim:.0f} %)", prev.cases_trimmed),
    ):
        values = np.nan_to_num(np.asarray(mat, dtype=float).T)
        im = ax.imshow(values, aspect="auto", cmap="viridis", vmin=0, vmax=1)
        ax.set_xticks(range(len(acts)))
        ticks = [f"{s} ({c})" for s, c in zip(labels, counts, strict=True)]
        ax.set_xticklabels(ticks, rotation=60, ha="right", fontsize=7)
        ax.set_title(title, fontsize=10)
    axes[0].set_yticks(range(len(feats)))
    axes[0].set_yticklabels(feats, fontsize=7)
    fig.suptitle(f"feature prevalence per activity ({prev.method}; cases in brackets)", fontsize=10)
    fig.colorbar(im, ax=axes, fraction=0.025, pad=0.02, label="prevalence")
    return _save(fig, Path(path))


def confusion_methods(results: CompareResults) -> list[tuple[MethodResult, Scores]]:
    """Whose confusion matrix to draw: the best case-base configuration, whatever beats it,
    DAD, and the best peer for the contrast."""
    chosen: list[str] = []
    best_cbr = results.best_cbr()
    if best_cbr is not None:
        chosen.append(best_cbr[0].name)
    chosen += [n for n in (results.best_interpretable, results.best) if n is not None]
    chosen += [m.name for m, _ in results.scored() if m.kind == "dad"]
    peers = [(m, s) for m, s in results.scored() if m.kind == "peer"]
    if peers:
        chosen.append(max(peers, key=lambda ms: ms[1].accuracy)[0].name)
    scored = {m.name: (m, s) for m, s in results.scored()}
    names = dict.fromkeys(chosen)  # in order of first mention, no repeats
    return [scored[n] for n in names if n in scored]


_NO_GLYPH = re.compile(r"^Glyph (\d+) .*missing from font")


class Drawing:
    """Draws pictures one at a time; a failure becomes a line in ``failures``, not an
    exception. Characters the font lacks (an activity named in a script DejaVu Sans does not
    cover) are drawn as boxes: matplotlib warns of each, twice per picture, in several lines
    of Python's warnings; they are one line in ``failures`` instead, naming the characters."""

    def __init__(self) -> None:
        self.failures: list[str] = []
        self._lacking: dict[str, None] = {}  # the characters, in the order met
        self._lacking_line: int | None = None  # where their line is in failures
        #: the file of the picture being drawn (None between pictures): an interrupt that
        #: came after it was written, before its caller named it, leaves it unnamed
        self.drawing: Path | None = None

    def attempt(self, name: str, draw: Callable[[], T], path: Path | None = None) -> T | None:
        """``draw()``, which writes the picture ``path`` (if any); None when it failed."""
        result: T | None = None
        self.drawing = path
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                result = draw()
            except Exception as exc:  # any library error: the results matter more than it
                self.failures.append(f"picture {name} failed: {exc}")
        self.drawing = None  # not on an interrupt (KeyboardInterrupt is no Exception)
        for w in caught:  # every other warning as it would have been
            if not self._no_glyph(w):
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return result

    def _no_glyph(self, w: warnings.WarningMessage) -> bool:
        """Whether ``w`` is matplotlib's "Glyph N missing from font(s)"; if so its character
        is noted in the one line that names them all."""
        found = _NO_GLYPH.match(str(w.message))
        if found is None:
            return False
        self._lacking.setdefault(chr(int(found.group(1))), None)
        line = (
            "pictures: the font has no glyph for "
            + ", ".join(self._lacking)
            + " (in names drawn): drawn as boxes"
        )
        if self._lacking_line is None:
            self._lacking_line = len(self.failures)
            self.failures.append(line)
        else:
            self.failures[self._lacking_line] = line
        return True


def result_pictures(
    results: CompareResults, out_dir: str | Path, drawing: Drawing, into: Pictures | None = None
) -> Pictures:
    """The pictures that need only the results (accuracy, confusion matrices), into
    ``out_dir``; names relative to it. Each is named in ``into`` (a new one when None) as soon
    as it is on disk: a run interrupted meanwhile names those drawn."""
    out = Path(out_dir)
    pics = Pictures() if into is None else into
    if not results.scored():
        return pics
    acc = drawing.attempt(
        "accuracy", lambda: plot_accuracy(results, out / "accuracy.png"), out / "accuracy.png"
    )
    pics.accuracy = None if acc is None else acc.name
    classes = results.dataset.classes
    for m, s in confusion_methods(results):
        dest = out / f"confusion_{safe_name(m.name)}.png"
        drawn = drawing.attempt(
            f"confusion {m.name}", partial(plot_confusion, m.name, s, classes, dest), dest
        )
        if drawn is not None:
            pics.confusion.append(ConfusionPicture(m.name, drawn.name))
    return pics


def _timeline(act: str, seq: Any, path: Path) -> TimelinePicture:
    from features.fluents import evaluate
    from features.timeline import plot_timeline

    clip = Path(seq.source).name if seq.source else act
    plot_timeline(evaluate(seq.to_canonical()), path, title=f"{act}: {clip}")
    return TimelinePicture(act, clip, path.name)


def data_pictures(
    run: CompareRun,
    out_dir: str | Path,
    trim: float | None,
    drawing: Drawing,
    into: Pictures | None = None,
) -> Pictures:
    """The pictures that need the clips and an estimator, into ``out_dir``: feature
    prevalence (initial vs trimmed case base; also stored in ``run.results.prevalence``) and
    one fluent timeline per activity. Each is named in ``into`` (a new one when None) as soon
    as it is on disk."""
    from .prevalence import prevalence

    out = Path(out_dir)
    pics = Pictures() if into is None else into
    keep = trim if trim is not None and trim < 1.0 else 0.5
    prev = drawing.attempt("prevalence", lambda: prevalence(run, trim=keep))
    if prev is not None:
        run.results.prevalence = prev
        dest = out / "prevalence.png"
        drawn = drawing.attempt("prevalence", partial(plot_prevalence, prev, dest), dest)
        pics.prevalence = None if drawn is None else drawn.name
    examples = example_clips(run.data)
    for i, (act, seq) in enumerate(
        progress(examples.items(), "timelines", total=len(examples), unit="clip")
    ):
        path = out / f"timeline_{i:02d}.png"
        timeline = drawing.attempt(f"timeline {act}", partial(_timeline, act, seq, path), path)
        if timeline is not None:
            pics.timelines.append(timeline)
    return pics
