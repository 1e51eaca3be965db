"""The counterfactual search of vector problems when every feature is changed and the label
still does not win (session 52, task M): no counterfactual, as before the search voted over
every kept set at once; not an error. Its real-data tests are in tests/test_cbr_uiprmd.py."""

from __future__ import annotations

import numpy as np

from cbr.casebase import CaseBase
from cbr.counterfactual import counterfactual
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean


def test_no_counterfactual_when_every_feature_changed_does_not_win() -> None:
    # the guide, the nearest case of "b", has a twin of "a": a problem that takes both its
    # features matches both exactly, and a tie goes to the first class, "a"
    p = np.array([[0.0, 0.0], [0.0, 0.0], [5.0, 5.0], [6.0, 5.0], [5.0, 6.0]])
    labels = np.array(["a", "b", "a", "a", "a"], dtype=object)
    cb = CaseBase(FeatureConfig(), Euclidean(exact=True), p, labels, ("x", "y"), ("x", "y"))
    q = np.array([5.5, 5.5])
    cf = counterfactual(cb, q, "b", lambda v: "a", k=3)
    assert cf.guide is None and cf.features == () and not cf.valid
    assert cf.answer == "a" and np.array_equal(cf.values, q)
