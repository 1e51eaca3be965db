"""Hunt 53v: a review of hunts 53a, 53c, 53f and 53k. Since hunt 53k, ``watch --split
repetitions`` explains each repetition on a thread of its own while the frame loop explains
the segments that finish, both with one case base: what an explanation reads once and keeps
on the case base (:func:`cbr.explain.read`) was put there a piece at a time, so the other
thread could find a piece and not the rest."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import cbr.explain as explain_module
from cbr.estimator import CaseBaseClassifier
from features.poses import PoseSequence


def test_an_explanation_read_while_another_fills_the_case_bases_cache_finds_it_whole(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The other thread's read, run where a thread switch can put it: while the first read
    fills the cache (at its first reading of a column's unit). It raised KeyError
    ('angles': the importance was there, the rest not yet); now it reads the columns as a
    read alone does."""
    clf, rec, _ = arm_k3
    cb = clf.case_base_
    problem = clf.problems([PoseSequence(rec.positions[:60], rec.joint_names, rec.fps)])[0]
    cb.cache.clear()
    alone = explain_module.read(cb, problem)  # a read with nothing else going on
    cb.cache.clear()
    quantity, meanwhile = explain_module.quantity, []

    def switched(*args: Any, **kwargs: Any) -> Any:
        if not meanwhile:
            meanwhile.append(None)
            meanwhile.append(explain_module.read(cb, problem))  # the other thread's read
        return quantity(*args, **kwargs)

    monkeypatch.setattr(explain_module, "quantity", switched)
    first = explain_module.read(cb, problem)
    other = meanwhile[1]
    for reading in (first, other):
        for part in ("importance", "readable", "angles", "states", "state_means", "qmps", "seen"):
            np.testing.assert_array_equal(getattr(reading, part), getattr(alone, part))
