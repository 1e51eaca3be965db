"""Explanations in words: which features matched the retrieved cases, which did not, and what
separates the clip from the nearest case of another activity.

A feature (fluent state or QMP) is *seen* in a problem when its confidence is at least 0.5 in
at least :data:`SEEN_FRACTION` of the (resampled) frames; for a QMP vector, when its value is
at least 0.5. Features seen in almost every case say little, so each list is ordered by how
distinctive the feature is in the case base (1 - the share of cases that show it).

Clip summaries (``FeatureConfig.summary``): a fluent state is seen when its mean confidence
over the clip (about the share of frames it holds) is at least :data:`SEEN_FRACTION`; the
lists use the plain state words. With learned feature weights (:mod:`cbr.weights`) the
explanation also names the features the case base weights most and the ones that, weighted,
set the clip apart from the nearest case of another activity.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .casebase import CaseBase
from .problem import ANGLE_PREFIX, POSITION_PREFIX, Problem
from .retrieve import Retrieval, nearest_of_other_label
from .reuse import Solution
from .weights import MIRROR_FLAG

SEEN_FRACTION = 0.15
MAX_LISTED = 6
_PREVALENCE_SAMPLE = 2000


def presence(values: np.ndarray) -> np.ndarray:
    """Share of frames where each feature's confidence >= 0.5.

    values: ``(..., frames, n_features)`` fluent sequences -> ``(..., n_features)``, or
    ``(..., n_features)`` QMP vectors (pass ``values[..., None, :]``).
    """
    return np.asarray(np.asarray(values) >= 0.5, dtype=np.float64).mean(axis=-2)


@dataclass(frozen=True)
class Contrast:
    """The nearest case of another activity and what would have to change."""

    label: str
    case_id: int
    source: str
    distance: float
    would_need: tuple[str, ...]
    would_lose: tuple[str, ...]


@dataclass(frozen=True)
class Explanation:
    label: str
    confidence: float
    neighbours: tuple[dict[str, Any], ...]
    matched: tuple[str, ...]
    not_seen: tuple[str, ...]
    only_here: tuple[str, ...]
    contrast: Contrast | None
    text: str = field(default="")
    weighted_most: tuple[str, ...] = ()
    differs_most: tuple[str, ...] = ()
    # for each of differs_most: {"feature", "here", "there", "unit"} in the feature's own units
    differences: tuple[dict[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "confidence": self.confidence,
            "neighbours": list(self.neighbours),
            "matched": list(self.matched),
            "not_seen": list(self.not_seen),
            "only_here": list(self.only_here),
            "contrast": None
            if self.contrast is None
            else {
                "label": self.contrast.label,
                "case_id": self.contrast.case_id,
                "source": self.contrast.source,
                "distance": self.contrast.distance,
                "would_need": list(self.contrast.would_need),
                "would_lose": list(self.contrast.would_lose),
            },
            "text": self.text,
            "weighted_most": list(self.weighted_most),
            "differs_most": list(self.differs_most),
            "differences": list(self.differences),
        }


def _presence_of(cb: CaseBase, values: np.ndarray) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == cb.problems.ndim - 1:  # one problem
        v = v[None]
    if v.ndim == 2:  # vectors (QMP): one "frame"
        v = v[:, None, :]
    elif v.ndim > 3:  # unknown layout: flatten per case
        v = v.reshape(len(v), 1, -1)
    return presence(v)


def state_columns(names: tuple[str, ...]) -> tuple[np.ndarray, bool] | None:
    """The columns "seen" is judged on, and whether they are clip-summary means: the fluent
    states (not joint angles or positions, which are no yes/no features); None when that is
    every column."""
    summary = any("@" in n for n in names)
    keep = [
        i
        for i, n in enumerate(names)
        if not n.startswith((ANGLE_PREFIX, POSITION_PREFIX))
        and n != MIRROR_FLAG
        and (not summary or n.endswith("@mean"))
    ]
    if not summary and len(keep) == len(names):
        return None
    return np.array(keep, dtype=np.int64), summary


def _weighted_terms(cb: CaseBase, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """Per-column weighted squared differences of two vector problems (None: no weights)."""
    mult = getattr(cb.measure, "multiplier", None)
    if mult is None or a.ndim != 1:
        return None
    m = np.asarray(mult, dtype=np.float64)
    return np.asarray(((a - b) * m) ** 2, dtype=np.float64)


def _ranked(mask: np.ndarray, score: np.ndarray, words: tuple[str, ...]) -> tuple[str, ...]:
    idx = np.flatnonzero(mask)
    idx = idx[np.argsort(-score[idx], kind="stable")][:MAX_LISTED]
    return tuple(words[i] for i in idx)


def quantity(name: str, value: float) -> tuple[float, str]:
    """A problem column's value in its own unit: joint angles in degrees (stored as radians /
    pi), positions in torso lengths; a fluent state's mean (over the clip or a phase of it) is
    about the share of the frames it holds ("share"), its lowest and highest values are
    confidences, its variation a plain number."""
    base, _, stat = name.partition("@")
    if base.startswith(ANGLE_PREFIX):
        return float(value) * 180.0, "degrees"
    if base.startswith(POSITION_PREFIX):
        return float(value), "torso lengths"
    if stat == "mean" or stat.startswith("phase"):
        return float(value), "share"
    if stat == "std":
        return float(value), ""  # the spread of a confidence
    return float(value), "confidence"


def _said(value: float, unit: str) -> str:
    if unit == "degrees":
        return f"{value:.0f}°"
    if unit == "share":
        return f"{100.0 * value:.0f} % of the time"
    if unit == "confidence":
        return f"confidence {value:.2f}"
    return f"{value:.2f} {unit}".rstrip()


def _join(words: tuple[str, ...]) -> str:
    return ", ".join(words) if words else "none"


def explain(
    cb: CaseBase, problem: Problem, retrieval: Retrieval, solution: Solution
) -> Explanation:
    """Explain one classification in words built from the feature names."""
    all_words = problem.words if problem.words else cb.words
    if len(all_words) != cb.problems.shape[-1]:
        all_words = tuple(f"feature {i}" for i in range(cb.problems.shape[-1]))
    picked = state_columns(cb.names)
    if picked is not None and picked[1]:
        cols = picked[0]
        words = tuple(all_words[i] for i in cols)

        def seen(v: np.ndarray) -> np.ndarray:
            # mean confidence ~ share of frames: compared with SEEN_FRACTION like a presence
            return np.atleast_2d(np.asarray(v, dtype=np.float64))[:, cols]
    elif picked is not None:
        cols = picked[0]
        words = tuple(all_words[i] for i in cols)

        def seen(v: np.ndarray) -> np.ndarray:
            return _presence_of(cb, v)[:, cols]
    else:
        words = all_words

        def seen(v: np.ndarray) -> np.ndarray:
            return _presence_of(cb, v)

    q = seen(problem.values)[0]
    sample = cb.problems
    if len(sample) > _PREVALENCE_SAMPLE:
        pick = np.random.default_rng(0).choice(len(sample), _PREVALENCE_SAMPLE, replace=False)
        sample = sample[np.sort(pick)]
    distinct = 1.0 - (seen(sample) >= SEEN_FRACTION).mean(axis=0)

    win = retrieval.indices[retrieval.labels.astype(str) == solution.label]
    if len(win) == 0:
        win = retrieval.indices
    r = (seen(cb.problems[win]) >= SEEN_FRACTION).mean(axis=0)
    q_seen = q >= SEEN_FRACTION
    r_seen = r >= 0.5
    matched = _ranked(q_seen & r_seen, distinct * np.minimum(q, 1.0), words)
    not_seen = _ranked(~q_seen & r_seen, distinct * r, words)
    only_here = _ranked(q_seen & ~r_seen, distinct * q, words)

    contrast = None
    differs: tuple[str, ...] = ()
    differences: list[dict[str, Any]] = []
    weighted_most: tuple[str, ...] = ()
    mult = getattr(cb.measure, "multiplier", None)
    if mult is not None and len(mult) == len(all_words):
        # |multiplier| x spread = sqrt(learned weight); the mirror flag is a penalty, not a weight
        score = np.abs(np.asarray(mult)) * np.asarray(cb.problems).std(axis=0)
        score[[i for i, n in enumerate(cb.names) if n == MIRROR_FLAG]] = 0.0
        weighted_most = tuple(all_words[i] for i in np.argsort(-score)[:MAX_LISTED] if score[i] > 0)
    other = nearest_of_other_label(cb, problem, solution.label)
    if other is not None:
        pos, dist = other
        o = seen(cb.problems[pos])[0] >= SEEN_FRACTION
        terms = _weighted_terms(cb, np.asarray(problem.values), cb.problems[pos])
        if terms is not None and len(terms) == len(all_words):
            terms[[i for i, n in enumerate(cb.names) if n == MIRROR_FLAG]] = 0.0
            top = [i for i in np.argsort(-terms)[:MAX_LISTED] if terms[i] > 0]
            differs = tuple(all_words[i] for i in top)
            names = cb.names if len(cb.names) == len(all_words) else problem.names
            for i in top:
                here, unit = quantity(names[i], float(np.asarray(problem.values)[i]))
                there, _ = quantity(names[i], float(cb.problems[pos][i]))
                differences.append(
                    {"feature": all_words[i], "here": here, "there": there, "unit": unit}
                )
        assert cb.ids is not None
        contrast = Contrast(
            label=str(cb.labels[pos]),
            case_id=int(cb.ids[pos]),
            source=cb.sources[pos],
            distance=float(dist),
            would_need=_ranked(o & ~q_seen, distinct, words),
            would_lose=_ranked(q_seen & ~o, distinct, words),
        )
    assert cb.ids is not None
    neighbours = tuple(
        {
            "case_id": int(cb.ids[i]),
            "label": str(cb.labels[i]),
            "distance": float(d),
            "source": cb.sources[i],
        }
        for i, d in zip(retrieval.indices, retrieval.distances, strict=True)
    )
    lines = [
        f"{solution.label} (confidence {solution.confidence:.2f}) from the {len(neighbours)} "
        f"most similar cases ({sum(n['label'] == solution.label for n in neighbours)} of them "
        f"{solution.label}).",
        f"Matched: {_join(matched)}.",
        f"Seen in the similar {solution.label} cases but not in this clip: {_join(not_seen)}.",
        f"In this clip but not in those cases: {_join(only_here)}.",
    ]
    if problem.mirrored:
        lines.insert(
            1,
            "The clip moves its left side more, so it is compared as its mirror image: "
            "read 'left' for 'right' and 'right' for 'left' below.",
        )
    if contrast is not None:
        change = []
        if contrast.would_need:
            change.append(f"show {_join(contrast.would_need)}")
        if contrast.would_lose:
            change.append(f"not show {_join(contrast.would_lose)}")
        what = " and ".join(change) if change else "differ only in degree, not in these features"
        lines.append(
            f"Nearest other activity: {contrast.label} (distance {contrast.distance:.3g}); "
            f"to be that, the clip would {what}."
        )
        if differences:
            said = "; ".join(
                f"{d['feature']}: {_said(d['here'], d['unit'])} here, "
                f"{_said(d['there'], d['unit'])} there"
                for d in differences
            )
            lines.append(f"Weighted, it differs from that case most in: {said}.")
    if weighted_most:
        lines.append(f"Weighted most by this case base: {_join(weighted_most)}.")
    return Explanation(
        label=solution.label,
        confidence=solution.confidence,
        neighbours=neighbours,
        matched=matched,
        not_seen=not_seen,
        only_here=only_here,
        contrast=contrast,
        text="\n".join(lines),
        weighted_most=weighted_most,
        differs_most=differs,
        differences=tuple(differences),
    )
