"""What the spec audit (hunt 27a) found: places where the code did not do what SPEC.md says.

- Explanations at the QMP level named no matched and no unmatched features: the lists "shown
  here and in the similar cases", "in the similar cases, not here" and "here, not in the
  similar cases" were read from fluent-state columns only, so a QMP vector (whose columns
  are the ADD's QMPs, detected or not) always gave three empty lists. SPEC: "every
  classification names the matched and unmatched features against the retrieved cases and
  the winning activity, in words" ("knees bending and straightening in rhythm, matched; arms
  raised, not seen").
- A neck -> mid-ear link shorter than the degenerate-link bound (``MIN_LINK_M``, 1 micrometre)
  but not exactly 0 was a head-length: every near distance divided by it read as hundreds of
  thousands of head-lengths, "far from" with confidence 1. SPEC: a degenerate link gives an
  unavailable value, not a silent one; the angles' links already followed that bound.

Each expected value is worked out by hand in the test from SPEC's definitions.
"""

from __future__ import annotations

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.consistency import contradictions
from cbr.explain import Explanation, presence_claims, read
from cbr.problem import FeatureConfig, Problem
from cbr.similarity import Euclidean
from features.fluents import evaluate, state_signals
from features.geometry import MIN_LINK_M
from tests.bodies import standing, to_sequence

# ---- QMP-level explanations name the matched and unmatched QMPs ----------------------------

_QMPS = ("knee_oscillation", "arms_raised", "hip_oscillation", "legs_out_and_in")
_QMP_WORDS = (
    "knees bending and straightening in rhythm",
    "arms raised",
    "hips flexing and extending in rhythm",
    "legs moving outward and in",
)


def _qmp_case_base() -> CaseBase:
    """Six clips' binary QMP vectors: three squats, three jumping jacks."""
    problems = np.array(
        [
            [1.0, 0.0, 1.0, 0.0],  # squat
            [1.0, 0.0, 1.0, 0.0],  # squat
            [1.0, 0.0, 0.0, 0.0],  # squat
            [0.0, 1.0, 0.0, 1.0],  # jumping jack
            [0.0, 1.0, 0.0, 1.0],  # jumping jack
            [0.0, 1.0, 0.0, 0.0],  # jumping jack
        ]
    )
    labels = np.array(["squat"] * 3 + ["jumping jack"] * 3, dtype=object)
    return CaseBase(FeatureConfig(level="qmp"), Euclidean(exact=True), problems, labels, _QMPS,
                    _QMP_WORDS)  # fmt: skip


def test_a_qmp_classification_names_what_it_shares_with_its_similar_cases_and_what_not() -> None:
    """The clip shows knee oscillation and legs moving out and in, not arms raised nor hip
    oscillation; its similar cases are the three squats (positions 0, 1, 2).

    By hand, per QMP, the share of the three squats that show it: knees 3/3, arms 0/3, hips
    2/3, legs 0/3. Shown by most of them (at least half): knees and hips. So:

    - matched (shown here and by most similar cases): knees;
    - not seen (shown by most similar cases, not here): hips, whose difference 0 - 2/3 is
      beyond its spread within one activity, the pooled within-activity standard deviation
      sqrt(((1/3)^2 + (1/3)^2 + (2/3)^2 + 0 + 0 + 0) / (6 - 2)) = sqrt(1/6) = 0.41;
    - only here (shown here, by few similar cases): legs out and in, 1 - 0 = 1 beyond its
      spread (the same sqrt(1/6): jacks 1, 1, 0);
    - arms raised: in no list (neither here nor in the similar cases).

    Before, all three lists were empty: only fluent-state columns were read.
    """
    cb = _qmp_case_base()
    query = Problem(np.array([1.0, 0.0, 0.0, 1.0]), _QMPS, _QMP_WORDS, "qmp")
    matched, not_seen, only_here = presence_claims(read(cb, query), "squat", np.array([0, 1, 2]))
    assert [c.words for c in matched] == ["knees bending and straightening in rhythm"]
    assert [c.words for c in not_seen] == ["hips flexing and extending in rhythm"]
    assert [c.words for c in only_here] == ["legs moving outward and in"]
    assert [c.unit for c in (*matched, *not_seen, *only_here)] == ["detected"] * 3
    # the similar cases' share, as claimed: 3/3, 2/3, 0/3
    assert [c.there for c in (*matched, *not_seen, *only_here)] == [1.0, 2.0 / 3.0, 0.0]

    # and the claims hold against the data (the explanation's own checker)
    claims = (*matched, *not_seen, *only_here)
    exp = Explanation("squat", 1.0, (), (), (), (), None, "", "", claims)
    assert contradictions(exp, cb, query) == []


def test_a_qmp_shown_by_a_minority_of_the_similar_cases_is_not_said_to_be_shared() -> None:
    """One similar case in three shows hip oscillation (share 1/3, less than half): a clip
    that shows it has it "here, not in the similar cases" when the difference 1 - 1/3 = 2/3
    is beyond the spread within one activity (hips: squats 1, 0, 0 and jacks 0, 0, 0, pooled
    sqrt(((2/3)^2 + (1/3)^2 + (1/3)^2) / 4) = sqrt(1/6) = 0.41), never "matched"."""
    cb = _qmp_case_base()
    cb.set_problem(1, np.array([1.0, 0.0, 0.0, 0.0]))
    query = Problem(np.array([1.0, 0.0, 1.0, 0.0]), _QMPS, _QMP_WORDS, "qmp")
    matched, not_seen, only_here = presence_claims(read(cb, query), "squat", np.array([0, 1, 2]))
    assert [c.words for c in matched] == ["knees bending and straightening in rhythm"]
    assert not_seen == []
    assert [c.words for c in only_here] == ["hips flexing and extending in rhythm"]


def test_a_qmp_the_clip_could_not_show_is_in_no_list() -> None:
    """A QMP whose signals the clip lacks (``Problem.unseen``, e.g. no heels on Kinect) is
    neither shared nor missed: hips are shown by 2 of 3 similar cases but unseen here."""
    cb = _qmp_case_base()
    query = Problem(np.array([1.0, 0.0, 0.0, 1.0]), _QMPS, _QMP_WORDS, "qmp",
                    unseen=frozenset({"hip_oscillation"}))  # fmt: skip
    matched, not_seen, only_here = presence_claims(read(cb, query), "squat", np.array([0, 1, 2]))
    assert [c.words for c in matched] == ["knees bending and straightening in rhythm"]
    assert not_seen == []
    assert [c.words for c in only_here] == ["legs moving outward and in"]


# ---- a degenerate head-length gives unavailable near fluents --------------------------------


def _ears_at(link_m: float) -> dict[str, np.ndarray]:
    """The standing body with both ears ``link_m`` above the neck (the shoulders' midpoint,
    (0, 1.50, 0)), 0.08 m to either side: mid-ear -> neck is ``link_m`` long."""
    body = standing()
    body["left_ear"] = np.array([0.08, 1.50 + link_m, 0.0])
    body["right_ear"] = np.array([-0.08, 1.50 + link_m, 0.0])
    return body


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_a_head_length_of_a_degenerate_link_leaves_the_near_fluents_unavailable(
    backend: str,
) -> None:
    """Mid-ear 0.4 micrometres above the neck: the link is degenerate (under MIN_LINK_M = 1e-6
    m), so there is no head-length and every distance in head-lengths, and every near/far
    confidence, is unavailable (NaN). Touching is in metres, not head-lengths: the left index
    finger (0.20, 0.86, 0.02) to the nose (0, 1.63, 0.10) is sqrt(0.04 + 0.5929 + 0.0064) =
    0.80 m, over 0.1 m: not touching (0), still known. Before, the near distances were
    0.80 / 8e-7 = 10^6 head-lengths and "far from" held with confidence 1."""
    assert 4e-7 < MIN_LINK_M
    seq = to_sequence(_ears_at(4e-7), _ears_at(4e-7))
    sig = state_signals(seq, backend)  # type: ignore[arg-type]
    assert np.isnan(sig.head_length_m).all()
    assert np.isnan(sig.column("left_index~nose")).all()
    # the raw distances stay: left index (0.20, 0.86, 0.02) to right index (-0.20, ...): 0.40 m
    assert sig.distances_m[0, 0] == pytest.approx(0.40)
    res = evaluate(seq, backend=backend)  # type: ignore[arg-type]
    assert np.isnan(res.column("near:left_index~nose.near")).all()
    assert np.isnan(res.column("near:left_index~nose.far_from")).all()
    assert res.column("near:left_index~nose.touching")[0] == 0.0
    # a link just over the bound (2 micrometres) is a head-length, 4e-6 m: defined
    ok = state_signals(to_sequence(_ears_at(2e-6)), backend)  # type: ignore[arg-type]
    assert ok.head_length_m[0] == pytest.approx(4e-6)
