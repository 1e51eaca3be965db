"""Feature prevalence per activity in the initial and the trimmed case base (the paper's
figure 4), for the best case-base configuration of a comparison."""

from __future__ import annotations

from typing import Any

import numpy as np

from .compare import CompareRun
from .results import Prevalence


def _table(cb: Any, activities: list[str]) -> tuple[np.ndarray, list[int]]:
    """Mean presence of every feature per activity ``(activities, features)`` over a case
    base's cases, and its case count per activity."""
    from ..explain import presence

    v = np.asarray(cb.problems)
    pres = presence(v if v.ndim == 3 else v[:, None, :])  # (cases, features)
    lab = cb.labels.astype(str)
    rows = [
        pres[lab == a].mean(axis=0) if (lab == a).any() else np.full(pres.shape[1], np.nan)
        for a in activities
    ]
    return np.stack(rows), [int((lab == a).sum()) for a in activities]


def _columns(cb: Any, initial: np.ndarray, max_features: int) -> np.ndarray:
    """The ``max_features`` fluent-state columns that differ most between activities, in
    order: a joint angle or position above 0.5 is no feature being present."""
    from ..explain import state_columns

    spread = np.nanmax(initial, axis=0) - np.nanmin(initial, axis=0)
    picked = state_columns(tuple(cb.names))
    if picked is not None:
        keep = np.zeros(len(spread), dtype=bool)
        keep[picked[0]] = True
        spread = np.where(keep, spread, -np.inf)
        max_features = min(max_features, int(keep.sum()))
    return np.sort(np.argsort(-spread, kind="stable")[:max_features])


def _words(cb: Any, n_columns: int) -> list[str]:
    """A word for every column (extra columns such as a mirror-image flag have none)."""
    words = list(cb.words)
    return [words[i] if i < len(words) else f"feature {i}" for i in range(n_columns)]


def prevalence(run: CompareRun, trim: float = 0.5, max_features: int = 40) -> Prevalence | None:
    """Feature prevalence per activity in the initial and the trimmed case base.

    Uses the best case-base configuration's parameters, built on every clip with the activity
    label as solution. Prevalence of a feature in an activity = mean over its cases of the
    share of (resampled) frames where the feature holds (confidence >= 0.5); for QMP vectors,
    the share of cases that show the QMP. None without a case-base configuration or with one
    activity.
    """
    from ..estimator import CaseBaseClassifier

    best = run.results.best_cbr()
    labels = run.data.labels
    if best is None or len(set(labels)) < 2:
        return None
    params = {**best[0].params, "trim": None}
    full = CaseBaseClassifier(**params).fit(run.data.seqs, labels).case_base_
    trimmed = CaseBaseClassifier(**{**params, "trim": float(trim)}).fit(run.data.seqs, labels)
    activities = sorted(set(labels))
    init, n_init = _table(full, activities)
    trim_t, n_trim = _table(trimmed.case_base_, activities)
    cols = _columns(full, init, max_features)
    words = _words(full, init.shape[1])
    return Prevalence(
        method=best[0].name,
        trim=float(trim),
        activities=activities,
        features=[words[c] for c in cols],
        initial=init[:, cols].tolist(),
        trimmed=trim_t[:, cols].tolist(),
        cases_initial=n_init,
        cases_trimmed=n_trim,
    )
