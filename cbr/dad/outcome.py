"""What DAD answers for one clip: every ADD activity's score and, QMP by QMP, what was and was
not executed as expected."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from features.text import percent

NOT_ENOUGH_DATA = "not enough data"


@dataclass(frozen=True)
class QMPOutcome:
    """One step of an activity: met in order, seen but out of order, not met, or not
    observable. ``window_s``: [start, end] seconds of the window that satisfied it (met)."""

    qmp: str
    words: str
    weight: int
    status: str  # "met" | "out of order" | "not met" | "not observable"
    window_s: tuple[float, float] | None = None
    reasons: tuple[str, ...] = ()

    @property
    def met(self) -> bool:
        return self.status == "met"


@dataclass(frozen=True)
class ActivityScore:
    """An activity's score: the weighted ratio of its QMPs met in order among those observable,
    NaN when less than the configured share of its weight (``DADConfig.min_observable_share``,
    half) is observable: two QMPs of a kick seen out of seventeen are no kick, whatever they
    show. ``total_weight``: all its QMPs' weight (0: not given)."""

    activity: str
    words: str
    labels: tuple[str, ...]
    score: float
    met_weight: int
    observable_weight: int
    qmps: tuple[QMPOutcome, ...]
    total_weight: int = 0

    @property
    def met(self) -> tuple[QMPOutcome, ...]:
        return tuple(q for q in self.qmps if q.met)

    @property
    def not_met(self) -> tuple[QMPOutcome, ...]:
        return tuple(q for q in self.qmps if q.status in ("not met", "out of order"))

    def in_words(self) -> str:
        """Score, QMPs met and not met (with the first reason) in one line."""
        score = (
            f"{percent(self.score, 0)} of its QMPs in order"
            if np.isfinite(self.score)
            else "no observable QMP"
            if self.observable_weight == 0
            else f"too little observable: weight {self.observable_weight} of {self.total_weight}"
        )
        met = ", ".join(q.words for q in self.met) or "none"
        missed = "; ".join(
            q.words + (f" ({q.status}: {q.reasons[0]})" if q.reasons else f" ({q.status})")
            for q in self.not_met
        )
        return f"{self.words} ({score}); met: {met}" + (f"; not met: {missed}" if missed else "")


@dataclass(frozen=True)
class DADResult:
    """DAD's answer for one clip.

    status: "ok" or "not enough data" (then ``activities`` is empty and ``message`` says why);
    windows_s ``(W, 2)`` seconds; detected: per window, the QMP names that held; activities:
    ranked best first.
    """

    source: str
    status: str
    message: str
    fps: float
    duration_s: float
    windows_s: tuple[tuple[float, float], ...]
    detected: tuple[tuple[str, ...], ...]
    activities: tuple[ActivityScore, ...]
    add_source: str = ""
    qmp_words: dict[str, str] = field(default_factory=dict)

    @property
    def best(self) -> ActivityScore | None:
        """The top-ranked activity, when some of its QMPs were met in order (None when no
        activity's were: a 0% or unobservable activity is no match)."""
        top = self.activities[0] if self.activities else None
        if top is None or not np.isfinite(top.score) or top.met_weight == 0:
            return None
        return top

    @property
    def tied(self) -> tuple[ActivityScore, ...]:
        """The activities scored as high as :attr:`best` (none when there is no best match):
        the clip matches them as well."""
        best = self.best
        if best is None:
            return ()
        return tuple(a for a in self.activities if a is not best and a.score == best.score)

    def activity_for(self, label: str) -> ActivityScore | None:
        """The best-ranked activity that stands for ``label`` (None if the ADD has none),
        names matched ignoring case, spaces, underscores and hyphens ("Squat": "squat")."""
        from .names import stands_for

        return next((a for a in self.activities if stands_for(a.labels, label)), None)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (NaN scores become None); the clip is ``clip``, as in ``classify`` and
        ``reps``, and ``source``, the name it had first; ``frames`` its frame count after
        ``fps``, as ``describe``, ``reps`` and ``segment`` give it (``duration_s`` is that count
        over ``fps``). ``best``: the :attr:`best` match's ``activity`` (None: no match), and
        ``tied_with`` those scored as high (:attr:`tied`), as the text says them."""
        fields = asdict(self)
        out: dict[str, Any] = {"clip": self.source}
        for key, value in fields.items():
            out[key] = value
            if key == "fps":
                out["frames"] = int(round(self.duration_s * self.fps))
            if key == "detected":
                out["best"] = None if self.best is None else self.best.activity
                out["tied_with"] = [a.activity for a in self.tied]
        for act in out["activities"]:
            if not np.isfinite(act["score"]):
                act["score"] = None
        return out
