"""The CBR cycle against SPEC.md and the peer libraries (hunt 28b).

- The similarity plug-ins against their peers in the same test: DTW against tslearn's ``dtw``
  (with the Sakoe-Chiba band the plug-in exposes), signatures against iisignature's ``sig`` on
  the augmented path built here by hand, Euclidean by hand; the vote against scikit-learn's
  ``KNeighborsClassifier``.
- Found and fixed: a DTW query holding NaN had no neighbour (every cost NaN) and ``nearest``
  answered the case position ``n``, one past the last case, at distance inf; a case holding
  NaN was silently never a neighbour (Euclidean refused both already).
- Found and fixed: novelty/benefit trimming ranked equal values by their position in the case
  base (the later case ranked higher), so of cases of equal benefit (a count) the earlier
  one went, even when it was the most novel of its activity.
- Found and fixed: feedback could relabel a case trimmed meanwhile by another process
  (a move was refused; a relabel was written to the inactive case and the feedback lost).
- Found and fixed: ``Euclidean(exact=True)`` given a NaN query answered no neighbour at all
  (every distance NaN), without a word; the float32 path refused it already.
- Found and fixed: the Euclidean measure given a query of another number of values than the
  cases' read a shorter query past its end and left a longer one's last values out.
- Found and fixed: after fit, ``set_params(k=0)`` (or ``k=-1``, ``k=2.5``, ``weights="x"``)
  classified without complaint: k=0 gave every clip the first class at share 0.5.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import iisignature
import numpy as np
import pytest
from sklearn.base import clone
from sklearn.neighbors import KNeighborsClassifier
from tslearn.metrics import dtw as tslearn_dtw

from casebase_store import StaleCaseError, open_store
from cbr.casebase import CaseBase
from cbr.estimator import CaseBaseClassifier
from cbr.evaluation.peers import cache_tslearn_kernels
from cbr.maintenance import novelty_benefit, trim_novelty_benefit
from cbr.problem import FeatureConfig
from cbr.retrieve import retrieve
from cbr.reuse import reuse
from cbr.revise import Revision, record_revision
from cbr.similarity import get_measure
from cbr.stored import case_records
from features.errors import ConfigError, InputError
from tests.moves import clip

# tslearn's DTW compiled once per machine, not once per process (numba's disk cache)
cache_tslearn_kernels()
# ---- similarity measures against their peers ----------------------------------------------


@pytest.mark.parametrize(
    ("params", "radius"),
    [({}, 2), ({"band": 1.0}, 20), ({"band": 0.25, "prune": False}, 5)],
)  # fmt: skip
def test_dtw_equals_tslearn_within_the_same_sakoe_chiba_band(
    params: dict[str, object], radius: int
) -> None:
    """Distances and the 3 nearest equal tslearn's dtw with ``sakoe_chiba_radius`` = the
    plug-in's radius (band 0.1 x 20 frames = 2; band 1.0 = unconstrained)."""
    rng = np.random.default_rng(0)
    cases, q = rng.normal(size=(6, 20, 3)), rng.normal(size=(20, 3))
    m = get_measure("dtw", **params)
    assert m.radius_for(20) == radius  # type: ignore[attr-defined]
    index = m.build_index(m.represent(cases))
    peer = np.array(
        [tslearn_dtw(q, c, global_constraint="sakoe_chiba", sakoe_chiba_radius=radius)
         for c in cases]
    )  # fmt: skip
    np.testing.assert_allclose(m.distances(m.represent_query(q), index), peer, rtol=1e-9)
    idx, dist = m.nearest(m.represent_query(q), index, 3)
    assert idx.tolist() == np.argsort(peer, kind="stable")[:3].tolist()
    np.testing.assert_allclose(dist, np.sort(peer)[:3], rtol=1e-9)


@pytest.mark.parametrize("length", [1, 2])
def test_dtw_of_one_and_two_frames_and_of_integers_equals_tslearn(length: int) -> None:
    rng = np.random.default_rng(length)
    cases, q = rng.integers(0, 5, size=(4, length, 2)), rng.integers(0, 5, size=(length, 2))
    m = get_measure("dtw")
    d = m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
    peer = [tslearn_dtw(q, c, global_constraint="sakoe_chiba", sakoe_chiba_radius=1)
            for c in cases]  # fmt: skip
    np.testing.assert_allclose(d, peer, rtol=1e-12)


@pytest.mark.parametrize("where", ["query", "case"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_dtw_refuses_nan_or_inf_instead_of_answering_no_case_or_skipping_one(
    where: str, bad: float
) -> None:
    """Before: a NaN query gave every distance NaN and nearest answered case 4 of a 4-case
    base (one past the last) at distance inf; a NaN case was never a neighbour, silently.
    Euclidean refuses both; DTW now does too, naming the query or the case."""
    rng = np.random.default_rng(5)
    cases, q = rng.normal(size=(4, 10, 2)), rng.normal(size=(10, 2))
    if where == "query":
        q[3, 1] = bad
    else:
        cases[1, 4, 0] = bad
    for params in ({}, {"prune": False}):
        m = get_measure("dtw", **params)
        with pytest.raises(InputError, match="query holds NaN" if where == "query" else "rows 1 "):
            m.nearest(m.represent_query(q), m.build_index(m.represent(cases)), 2)
        if where == "query":
            with pytest.raises(InputError, match="NaN or inf"):
                m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
        else:
            with pytest.raises(InputError, match="NaN or inf"):
                m.index_for(cases)  # type: ignore[attr-defined]


def _path(x: np.ndarray, *, time: bool, lead_lag: bool, basepoint: bool) -> np.ndarray:
    """The augmented path, built point by point (Chevyrev & Kormilitzin's lead-lag: lead
    steps first, then the lag catches up)."""
    p = np.asarray(x, dtype=np.float64)
    if basepoint:
        p = np.vstack([np.zeros((1, p.shape[1])), p])
    if lead_lag:
        pts = []
        for i in range(len(p)):
            pts.append(np.concatenate([p[i], p[i]]))
            if i + 1 < len(p):
                pts.append(np.concatenate([p[i + 1], p[i]]))
        p = np.array(pts)
    if time:
        p = np.hstack([np.linspace(0.0, 1.0, len(p))[:, None], p])
    return p


@pytest.mark.parametrize(
    "params",
    [{}, {"depth": 3}, {"time": False}, {"lead_lag": True}, {"basepoint": False},
     {"depth": 1, "time": False, "basepoint": False}],
)  # fmt: skip
def test_signature_distance_equals_iisignature_on_the_augmented_path(
    params: dict[str, object],
) -> None:
    rng = np.random.default_rng(1)
    cases, q = rng.normal(size=(5, 12, 3)), rng.normal(size=(12, 3))
    m = get_measure("signature", **params)
    kw = {"time": m.time, "lead_lag": m.lead_lag, "basepoint": m.basepoint}  # type: ignore[attr-defined]
    depth = int(m.depth)  # type: ignore[attr-defined]

    def sig(x: np.ndarray) -> np.ndarray:
        return np.asarray(iisignature.sig(_path(x, **kw), depth))

    peer = [np.linalg.norm(sig(q) - sig(c)) for c in cases]
    d = m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
    np.testing.assert_allclose(d, peer, rtol=1e-6)  # float32 rows (the documented kernel)


def test_signature_of_one_frame_sees_its_level_only_with_the_basepoint() -> None:
    """One frame is a constant path: its signature is all zeros, so without the basepoint
    every one-frame clip is at distance 0 from every other; with it, the path 0 -> x."""
    cases, q = np.array([[[1.0, 2.0]], [[3.0, -1.0]]]), np.array([[1.0, 2.0]])
    plain = get_measure("signature", basepoint=False)
    np.testing.assert_array_equal(
        plain.distances(plain.represent_query(q), plain.build_index(plain.represent(cases))), 0.0
    )
    m = get_measure("signature", depth=2, time=False)

    # the straight path 0 -> x: signature (x, x (x) x / 2)
    def sig(x: np.ndarray) -> np.ndarray:
        return np.concatenate([x, np.outer(x, x).ravel() / 2])

    peer = [np.linalg.norm(sig(q[0]) - sig(c[0])) for c in cases]
    d = m.distances(m.represent_query(q), m.build_index(m.represent(cases)))
    np.testing.assert_allclose(d, peer, rtol=1e-6, atol=1e-6)


def test_euclidean_by_hand_on_integers_and_float32_and_nan_refused() -> None:
    cases = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 1], [0, 1, 0]])
    q = np.array([1, 1, 0])
    m = get_measure("euclidean")
    for c in (cases, cases.astype(np.float32)):
        idx, d = m.nearest(m.represent_query(q), m.build_index(m.represent(c)), 10)
        # mismatches: 2, 1, 1, 1 -> three at distance 1 (lower index first), then sqrt 2
        assert idx.tolist() == [1, 2, 3, 0]
        np.testing.assert_allclose(d, [1, 1, 1, np.sqrt(2)], rtol=1e-6)
    with pytest.raises(InputError, match="NaN"):
        m.nearest(m.represent_query(np.array([1.0, np.nan, 0.0])), m.build_index(cases), 1)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_exact_euclidean_refuses_a_nan_or_inf_query_as_the_float32_path_does(bad: float) -> None:
    """Before: with ``exact=True`` a NaN query had every distance NaN and no neighbour at all
    (the vote then gave equal shares: the first class), an inf query every case at inf."""
    m = get_measure("euclidean", exact=True)
    index = m.build_index(m.represent(np.arange(12.0).reshape(4, 3)))
    q = np.array([1.0, bad, 2.0])
    with pytest.raises(InputError, match="query holds NaN or inf"):
        m.nearest(m.represent_query(q), index, 2)
    with pytest.raises(InputError, match="query holds NaN or inf"):
        m.distances(m.represent_query(q), index)


@pytest.mark.parametrize("exact", [False, True])
@pytest.mark.parametrize("width", [2, 4])
def test_euclidean_refuses_a_query_of_another_width_than_the_cases(exact: bool, width: int) -> None:
    """Before: the float32 row kernel read a 2-value query past its end (whatever lay in
    memory as its third value) and left a 4-value query's last value out, answering either
    as a distance; the exact path raised numpy's broadcasting error."""
    m = get_measure("euclidean", exact=exact)
    index = m.build_index(m.represent(np.arange(12.0).reshape(4, 3)))
    q = np.arange(float(width))
    for call in (
        lambda: m.distances(m.represent_query(q), index),
        lambda: m.nearest(m.represent_query(q), index, 2),
        lambda: m.nearest_many(np.stack([q, q]), index, 2),
    ):
        with pytest.raises(ConfigError, match=f"the query has {width} values but the cases have 3"):
            call()


# ---- reuse: the vote -----------------------------------------------------------------------


def _line(xs: list[float], labels: list[str]) -> CaseBase:
    """Cases on a line: problem (x,), every distance |x_i - x_j|."""
    p = np.asarray(xs, dtype=np.float64)[:, None]
    return CaseBase(FeatureConfig(), get_measure("euclidean", exact=True), p,
                    np.array(labels, dtype=object), ("x",), ("x",))  # fmt: skip


@pytest.mark.parametrize("weights", ["distance", "uniform"])
def test_the_vote_equals_scikit_learns_k_neighbours(weights: str) -> None:
    rng = np.random.default_rng(7)
    xs = rng.uniform(0, 10, 15)
    labels = list(rng.choice(["a", "b", "c"], 15))
    cb = _line(list(xs), labels)
    peer = KNeighborsClassifier(n_neighbors=4, weights=weights).fit(xs[:, None], labels)
    queries = rng.uniform(0, 10, 20)
    classes = np.array(["a", "b", "c"], dtype=object)
    ours = [reuse(retrieve(cb, np.array([x]), 4), classes, weights) for x in queries]  # type: ignore[arg-type]
    np.testing.assert_allclose([s.proba for s in ours], peer.predict_proba(queries[:, None]))
    assert [s.label for s in ours] == peer.predict(queries[:, None]).tolist()


def test_a_tie_between_classes_goes_to_the_first_class_and_duplicates_decide_alone() -> None:
    cb = _line([1.0, 3.0, 2.0, 2.0], ["b", "a", "a", "b"])
    classes = np.array(["a", "b"], dtype=object)
    # x=2: two exact matches (a, b) decide alone, one vote each: the tie goes to "a"
    s = reuse(retrieve(cb, np.array([2.0]), 4), classes)
    assert (s.label, s.proba.tolist()) == ("a", [0.5, 0.5])
    # k larger than the case base: every case votes; k < 1 refused
    assert len(retrieve(cb, np.array([0.0]), 99).indices) == 4
    for k in (0, -1):
        with pytest.raises(ConfigError, match="k: must be"):
            retrieve(cb, np.array([0.0]), k)


# ---- maintenance: novelty and benefit ------------------------------------------------------


def test_novelty_and_benefit_of_a_five_case_base_by_hand() -> None:
    """x = 0, 1, 3 (a), 4, 10 (b), k = 2.

    novelty: nearest case of the same activity over the activity's median of those:
    a: 1, 1, 2 (median 1) -> 1, 1, 2; b: 6, 6 (median 6) -> 1, 1.
    2-NN of each case: 0 -> 1, 3 (a, a); 1 -> 0, 3 (a, a); 3 -> 4 (b), 1 (a);
    4 -> 3 (a), 1 (a); 10 -> 4 (b), 3 (a).
    coverage (among the 2-NN of a case of its label): 1, 2, 2, 1, 0
    liability (among the 2-NN of a case of another label): 0, 1, 2, 1, 0
    benefit = coverage - liability: 1, 1, 0, 0, 0."""
    cb = _line([0.0, 1.0, 3.0, 4.0, 10.0], list("aaabb"))
    nov, ben = novelty_benefit(cb, 2)
    np.testing.assert_allclose(nov, [1, 1, 2, 1, 1])
    np.testing.assert_allclose(ben, [1, 1, 0, 0, 0])


def test_trim_ranks_equal_benefits_alike_and_keeps_the_most_novel() -> None:
    """Two far clusters of four, cases at x = 7, 0, 3, 1 (a) and 107, 100, 103, 101 (b), k = 3:
    every case's 3 nearest are its own activity's three others, so every benefit is 3 (a tie).
    Nearest same-activity distances, in case order: 4, 1, 2, 1 (median 1.5). Keeping half,
    the two most novel of each activity stay: x = 7 and 3. Before, equal benefits got ranks
    0, 1, 2, 3 by position, and the most novel case (x = 7, the first) went."""
    xs = [7.0, 0.0, 3.0, 1.0]
    cb = _line(xs + [x + 100.0 for x in xs], list("aaaabbbb"))
    nov, ben = novelty_benefit(cb, 3)
    np.testing.assert_allclose(ben, 3.0)
    np.testing.assert_allclose(nov, np.array([4, 1, 2, 1] * 2) / 1.5)
    rep = trim_novelty_benefit(cb, keep=0.5, k=3)
    assert np.flatnonzero(rep.kept).tolist() == [0, 2, 4, 6]


def test_trim_never_drops_an_activity_and_leaves_a_one_case_base_alone() -> None:
    cb = _line([0.0, 0.1, 0.2, 5.0], list("aaab"))
    rep = trim_novelty_benefit(cb, keep=0.01, k=2)
    assert rep.kept[3] and rep.kept[:3].sum() == 1  # one case of each activity stays
    one = trim_novelty_benefit(_line([1.0], ["a"]), keep=0.5, k=2)
    assert one.kept.tolist() == [True]


# ---- revise / retain -----------------------------------------------------------------------


def test_relabelling_a_case_trimmed_meanwhile_is_refused_as_stale(tmp_path: Path) -> None:
    """Before: moving a trimmed case was refused (StaleCaseError: the caller reads again),
    but relabelling one was written to the inactive case, and the feedback was lost."""
    store = open_store(tmp_path / "cb.sqlite", create=True)
    cb = _line([0.0, 4.0, 10.0], ["a", "a", "b"])
    with store.transaction() as tx:
        info = tx.create_case_base("x", {"level": "fluents"}, ["x"], ["x"], {"name": "euclidean"})
        ids = tx.add_cases(info, case_records(cb))
    with store.transaction() as tx:  # another process trims case 2
        tx.deactivate_cases(tx.case_base("x"), [ids[2]])
    rev = Revision("relabelled", 2, ids[2], "b", "a", 1.0, "by hand")
    for action in ("relabelled", "moved"):
        with pytest.raises(StaleCaseError, match="trimmed"), store.transaction() as tx:
            record_revision(tx, tx.case_base("x"), replace(rev, action=action), np.array([9.0]))
    cases = store.load_cases("x", include_inactive=True)
    assert cases.labels[2] == "b" and cases.features[2].tolist() == [10.0]
    assert all(e.action != "revise" for e in store.maintenance_log("x"))


# ---- the Python API ------------------------------------------------------------------------


# on one xdist worker: the module's fitted made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt28b")


@pytest.fixture(scope="module")
def fitted() -> tuple[CaseBaseClassifier, list[object]]:
    X = [clip("squat", seconds=s) for s in (3, 4)] + [clip("jumping_jack", seconds=s)
                                                      for s in (3, 4)]  # fmt: skip
    clf = CaseBaseClassifier(similarity="dtw", k=3).fit(X, ["squat"] * 2 + ["jj"] * 2)
    return clf, [clip("squat", seconds=2.5), clip("jumping_jack", seconds=6)]


def test_clips_of_mixed_lengths_are_classified_and_a_clone_is_unfitted(
    fitted: tuple[CaseBaseClassifier, list[object]],
) -> None:
    clf, Q = fitted
    assert clf.predict(Q).tolist() == ["squat", "jj"]
    twin = clone(clf)
    assert twin.get_params() == clf.get_params() and not hasattr(twin, "case_base_")


@pytest.mark.parametrize(("param", "value"), [("k", 0), ("k", -1), ("k", 2.5), ("k", True),
                                              ("weights", "nearest")])  # fmt: skip
def test_a_bad_k_or_weighting_set_after_fit_is_refused_when_classifying(
    fitted: tuple[CaseBaseClassifier, list[object]], param: str, value: object
) -> None:
    """Before: k=0 gave every clip the first class at share 0.5; k=-1 voted with the wide
    neighbourhood but its last case; 2.5 voted with 2; an unknown weighting voted 1/d."""
    clf, Q = fitted
    good = clf.get_params()[param]
    clf.set_params(**{param: value})
    try:
        with pytest.raises(ConfigError, match=param):
            clf.predict(Q)
        with pytest.raises(ConfigError, match=param):
            clf.answer(clf.case_base_.problems[0])
    finally:
        clf.set_params(**{param: good})
    assert clf.predict(Q).tolist() == ["squat", "jj"]
