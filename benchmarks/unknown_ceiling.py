"""How well ANY threshold could call left-out movements unknown, on the windows the segmenter
judges: is the gap to issue 14's goal (left-out blocks called unknown >= 80 %, seen blocks
right >= 95 %) the judge's or the features'?

Run: ``python -m benchmarks.unknown_ceiling [--datasets ...] [--left-out N] [--per-person N]
[--cache DIR] [--smooth-jitter] [--feature-weights fisher] [--velocity] [--judge-only]
[--signature-paths angles|positions] [--signature-depth N] [--signature-no-lead-lag]``
(at load 10-16 on 2 cores: HDM05 about 4 minutes, 10 with
``--per-person 3``; UI-PRMD Vicon and Kinect 3-4 minutes per left-out movement, most of it
fitting each case base, and a few minutes of DTW per fold; ``--left-out N`` keeps N of a fold's
movements, evenly spaced in sorted order, and the results name the movements measured;
``--per-person N``: segment_people's, more test recordings per person; ``--cache DIR``
keeps each left-out movement's and each fold's DTW measurements, so an interrupted run
resumes and a run of several datasets reuses single runs'). Writes
``benchmarks/results/unknown_ceiling.json`` (``unknown_ceiling_perN.json`` with
``--per-person N``; ``..._smoothed.json`` with ``--smooth-jitter``: every file's joints
smoothed as their own jitter asks, :func:`features.jitter.smooth_jitter`).
``--feature-weights fisher``: the case bases weight every column by its between- over
within-activity variance on the case base (:func:`cbr.weights.fisher_ratio`; ``train
--feature-weights fisher``), ``..._fisher.json``; ``--velocity``: their problems also hold
the statistics of every column's rate of change (``CaseBaseClassifier(velocity=True)``),
``..._velocity.json``; ``--judge-only``: a quick screen, the default judge, ``margin``,
``nearest`` and the signature scores alone (no scikit-learn peers, DTW or combinations),
``..._judge.json``. Every
run also gives the known windows' seen accuracy: the share whose k-NN vote names their own
movement (with the case base that lacks the left-out one).

The folds, recordings, readers and case bases are :mod:`benchmarks.segment_people`'s (one
recording per held-out person, seed 0): each movement of the test recordings left out of the
case base in turn, every test recording solved with it (:func:`cbr.segmentation.solve_recording`)
and its 2-s windows (not the repetition windows) taken whole within one labelled movement
(windows across a change of movement are left out and counted). A window of a movement the
case base has is *known*, one of the left-out movement *novel*, both measured with the
case base that lacks the left-out movement (the share of known windows kept is what the
threshold costs there, not ``segment_people``'s seen accuracy, which uses the full case
base). Each score below is higher
for "more unknown"; for each: AUROC (known vs novel windows, sklearn's ``roc_auc_score``)
and the ORACLE rate: the share of novel windows above the threshold read from the test
windows themselves, the lowest that keeps >= 95 % of the known windows known
(:func:`oracle_rate`; the best any threshold on that score can do at that budget), and,
where the score has one, the threshold calibrated from the case base alone (held out by
training person: the 95 % quantile of held-out known scores) with what it keeps and calls.

- ``spread-margin``: the default judge (as ``segment`` sees it, :func:`cbr.unknown.for_person`
  per recording): its score over its nearest activity's threshold (1 = its own threshold;
  a window too still for every case, ``cbr.segmentation.too_still``, counts as inf), its
  graded evidence (:func:`cbr.unknown.unknown_evidence`, what ``segment`` averages over
  blocks) and its plain decisions (:meth:`unlike`); also the blocks ``segment`` then calls
  unknown (:func:`cbr.segmentation.finish`), to tie the windows to
  ``benchmarks.segment_people``'s table;
- ``margin`` d1/d2 (calibrated: the ``margin`` judge's pooled threshold) and ``nearest``
  d1, the distance to the nearest case;
- peers from scikit-learn fit on the case base's own window vectors (the measure's
  representation, the mirror flag column dropped, standardised on the cases):
  ``LocalOutlierFactor(novelty=True)``, ``IsolationForest``, ``OneClassSVM(nu=0.05)``, the
  mean distance to the 5 nearest cases, the least Mahalanobis distance to an activity's
  cases (Ledoit-Wolf covariance, per activity);
- ``dtw``: the DTW 1-NN distance (tslearn) from the window's eight limb angles at 30 Hz to
  the baseline's training windows (``benchmarks.segment_people.dtw_training``) of the
  movements in the case base;
- ``sig-nearest``, ``sig-margin``, ``sig-lof``: the same 2-s windows as paths (the eight limb
  angles at 30 Hz, or with ``--signature-paths positions`` the body-frame positions of the
  elbows, wrists, knees and ankles), every channel standardised on the case base's windows,
  from the origin, time added and lead-lagged, as log-signatures (iisignature, depth 2;
  ``--signature-depth``, ``--signature-no-lead-lag``), every term standardised on the case
  base's windows (:class:`SigSpec`, :class:`SigScores`); against the training windows of
  the movements in the case base (cut as the DTW baseline's): the nearest distance, the
  margin d1/d2 (d2 the nearest of another activity) and LocalOutlierFactor; calibrated held
  out by training person (:func:`sig_held`). ``judge+sig-fisher``: the default judge's score
  and ``sig-nearest`` combined as ``tail-fisher`` combines it with d1 (oracle figures only).
  A non-default representation writes ``..._sig-PATHS-dDEPTH[-nolag].json``;
- combinations of the default judge's score and the nearest distance d1, each calibrated on
  the case base's own held-out scan alone (:func:`held_scan`: the training cases held out
  by person as the judges hold them out, :func:`cbr.unknown.held_out_activities`; the
  judge's score and d1 of the held-out known cases, their activity in the case base, and of
  the held-out novel ones, their activity left out; nothing of the test people):
  ``tail-max``, the least of the two upper-tail probabilities among the held-out known
  scores (:func:`tail_p`, a Bonferroni/Sidak union: the more surprising score decides),
  ``tail-fisher``, Fisher's ``-2 sum log p`` of the two, and ``logistic``, a logistic
  regression on the logs of the two fit on held-out known against held-out novel cases;
  each threshold the 95 % quantile of the held-out known cases' own combined scores
  (:func:`combined_scores`; the case bases refit from the fold's descriptions, made once per
  fold, :func:`measure_held`, kept in the cache as ``...-MOVEMENT-held``).

Pooled over a dataset's left-out movements with ONE threshold (as one judge would have);
per movement each with its own. Window level: ``segment`` averages evidence over blocks and
decodes with a cost per change, so its block figures can exceed what a threshold on single
windows gives; the block figures are reported beside.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import pickle  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from functools import cache as cache_once  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks import write_json  # noqa: E402
from benchmarks._common import one_thread_machine, versions  # noqa: E402
from benchmarks.repetitions import HDM05, UIPRMD, Group  # noqa: E402
from benchmarks.segment_people import (  # noqa: E402
    BLOCK_S,
    DATASETS,
    Fold,
    Reader,
    Recording,
    dtw_training,
    fit,
    folds,
    joined_training,
    training_clips,
)

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "unknown_ceiling.json"
KEEP_KNOWN = 0.95
"""The oracle threshold keeps at least this share of known windows known (issue 14's goal)."""
GOAL_UNKNOWN = 0.80
HELD_OUT_SAMPLE = 500
"""Held-out training windows per person scored to calibrate a peer's threshold (a seeded
sample when there are more)."""
DTW_HELD_OUT_SAMPLE = 400
"""Training windows (a seeded sample) whose DTW 1-NN distance to other people's windows sets
the DTW threshold held out by person (each costs a DTW against every training window)."""
CACHE_VERSION = 2
"""2: each window's voted activity kept (the known windows' seen accuracy)."""
JUDGE = "spread-margin"
SCORES = ("spread-margin", "margin", "nearest", "lof", "iforest", "ocsvm", "knn5",
          "mahalanobis", "dtw", "sig-nearest", "sig-margin", "sig-lof", "tail-max",
          "tail-fisher", "logistic", "judge+sig-fisher")  # fmt: skip
"""The scores, the default judge first, the combinations (:data:`COMBINED`) last."""


@dataclass(frozen=True)
class Variant:
    """Options of the case bases measured (``--feature-weights``, ``--velocity``): the
    default is :func:`benchmarks.segment_people.fit`'s, ``posecbr train --split windows``'s."""

    feature_weights: str = "none"
    velocity: bool = False

    def params(self) -> dict[str, Any]:
        """The :class:`cbr.estimator.CaseBaseClassifier` parameters of the variant."""
        out: dict[str, Any] = {"feature_weights": self.feature_weights}
        if self.velocity:
            out["velocity"] = True
        return out

    def suffix(self) -> str:
        """``""`` for the default; else what names its results and cache entries."""
        return ("_fisher" if self.feature_weights == "fisher" else "") + (
            "_velocity" if self.velocity else ""
        )


# ---------------------------------------------------------------- pure scoring helpers


def auroc(known: np.ndarray, novel: np.ndarray) -> float:
    """The area under the ROC curve of telling ``novel`` scores (positives) from ``known``
    ones (higher = more unknown), sklearn's ``roc_auc_score``; NaN without both. Infinite
    scores rank above every finite one."""
    from sklearn.metrics import roc_auc_score

    if not len(known) or not len(novel):
        return float("nan")
    scores = np.r_[np.asarray(known, float), np.asarray(novel, float)]
    finite = scores[np.isfinite(scores)]
    top = (finite.max() if len(finite) else 0.0) + 1.0
    scores = np.where(np.isposinf(scores), top, np.where(np.isneginf(scores), -top, scores))
    truth = np.r_[np.zeros(len(known)), np.ones(len(novel))]
    return float(roc_auc_score(truth, scores))


def oracle_threshold(known: np.ndarray, keep: float = KEEP_KNOWN) -> float:
    """The lowest threshold ``t`` that keeps at least a share ``keep`` of ``known`` scores
    ``(n,)`` (non-empty) known (``score <= t``): the ``ceil(keep * n)``-th smallest."""
    k = np.sort(np.asarray(known, dtype=np.float64))
    return float(k[max(0, int(np.ceil(keep * len(k) - 1e-9)) - 1)])


def called(known: np.ndarray, novel: np.ndarray, threshold: float) -> tuple[float, float]:
    """With a window unknown when its score exceeds ``threshold``: the share of ``known``
    scores kept known and the share of ``novel`` scores called unknown (NaN for none)."""
    k, n = np.asarray(known, float), np.asarray(novel, float)
    kept = float(np.mean(k <= threshold)) if len(k) else float("nan")
    caught = float(np.mean(n > threshold)) if len(n) else float("nan")
    return kept, caught


def oracle_rate(known: np.ndarray, novel: np.ndarray, keep: float = KEEP_KNOWN) -> float:
    """The share of ``novel`` scores above :func:`oracle_threshold` of ``known``: the most
    of them any threshold calls unknown while keeping ``keep`` of the known ones known (ties
    at the threshold stay known). NaN without both."""
    if not len(known) or not len(novel):
        return float("nan")
    return called(known, novel, oracle_threshold(known, keep))[1]


def figures(known: np.ndarray, novel: np.ndarray, calibrated: float | None) -> dict[str, Any]:
    """AUROC, the oracle rate and threshold, and with a ``calibrated`` threshold (from the
    case base alone) the shares it keeps known and calls unknown."""
    out: dict[str, Any] = {
        "known_windows": len(known),
        "novel_windows": len(novel),
        "auroc": auroc(known, novel),
        "oracle_unknown_at_95_known": oracle_rate(known, novel),
    }
    if calibrated is not None and len(known) and len(novel):
        kept, caught = called(known, novel, calibrated)
        out["calibrated"] = {"threshold": calibrated, "known_kept": kept, "novel_unknown": caught}
    return out


# ---------------------------------------------------------------- measuring


def _cached(cache: Path | None, name: str, make: Callable[[], Any]) -> Any:
    """``make()``, kept in ``cache/name.pkl`` when a cache is given."""
    if cache is None:
        return make()
    path = cache / f"{name}.pkl"
    if path.exists():
        with path.open("rb") as f:
            return pickle.load(f)
    value = make()
    cache.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as f:
        pickle.dump(value, f)
    tmp.replace(path)
    return value


def pure_windows(rec: Recording, spans: np.ndarray, fps: float) -> np.ndarray:
    """The movement of each window ``spans`` ``(n, 2)`` (frames [start, stop)) of ``rec``
    whose blocks (by their centres) are all of one movement, None for one across a change."""
    centres = (np.arange(len(rec.blocks)) + 0.5) * BLOCK_S * fps
    out = np.empty(len(spans), dtype=object)
    for i, (a, b) in enumerate(spans.tolist()):
        inside = rec.blocks[(centres >= a) & (centres < b)]
        out[i] = inside[0] if len(inside) and np.all(inside == inside[0]) else None
    return out


def case_vectors(cb: Any) -> tuple[np.ndarray, np.ndarray]:
    """The case base's window vectors as its measure compares them ``(n, D)`` (the mirror
    flag column, when there is one, dropped) and which cases are real (not mirror images)."""
    from cbr.weights import MIRROR_FLAG

    reps = np.asarray(cb.measure.represent(cb.problems), dtype=np.float64)
    real = np.ones(len(cb), dtype=bool)
    if cb.names and cb.names[-1] == MIRROR_FLAG:
        real = np.asarray(cb.problems)[:, -1] == 0
        reps = reps[:, :-1]
    return reps, real


def query_vectors(cb: Any, solved: list[Any]) -> np.ndarray:
    """The solved windows' problems as the case base's measure represents them ``(n, D)``
    (the mirror flag column dropped as :func:`case_vectors` drops it)."""
    from cbr.weights import MIRROR_FLAG

    q = np.stack([cb.measure.represent_query(s.problem.values) for s in solved])
    q = np.asarray(q, dtype=np.float64).reshape(len(solved), -1)
    return q[:, :-1] if cb.names and cb.names[-1] == MIRROR_FLAG else q


class Peers:
    """scikit-learn's open-set detectors fit on window vectors ``X`` ``(n, D)`` of activities
    ``y`` (standardised on ``X``); :meth:`scores` higher = more unknown."""

    NAMES = ("lof", "iforest", "ocsvm", "knn5", "mahalanobis")

    def __init__(self, X: np.ndarray, y: np.ndarray) -> None:
        from sklearn.covariance import LedoitWolf
        from sklearn.ensemble import IsolationForest
        from sklearn.neighbors import LocalOutlierFactor, NearestNeighbors
        from sklearn.preprocessing import StandardScaler
        from sklearn.svm import OneClassSVM

        self.scaler = StandardScaler().fit(X)
        Z = self.scaler.transform(X)
        self.lof = LocalOutlierFactor(n_neighbors=20, novelty=True).fit(Z)
        self.iforest = IsolationForest(random_state=0).fit(Z)
        self.ocsvm = OneClassSVM(nu=0.05, gamma="scale").fit(Z)
        self.knn = NearestNeighbors(n_neighbors=min(5, len(Z))).fit(Z)
        self.gauss = []
        for a in np.unique(y):
            mine = Z[y == a]
            if len(mine) >= 2:
                lw = LedoitWolf().fit(mine)
                self.gauss.append(lw)

    def scores(self, X: np.ndarray) -> dict[str, np.ndarray]:
        Z = self.scaler.transform(X)
        return {
            "lof": -self.lof.score_samples(Z),
            "iforest": -self.iforest.score_samples(Z),
            "ocsvm": -self.ocsvm.score_samples(Z),
            "knn5": self.knn.kneighbors(Z)[0].mean(axis=1),
            "mahalanobis": np.sqrt(np.min([g.mahalanobis(Z) for g in self.gauss], axis=0)),
        }


def peer_thresholds(X: np.ndarray, y: np.ndarray, people: np.ndarray,
                    real: np.ndarray) -> dict[str, float]:  # fmt: skip
    """Each peer's threshold from the case base alone: every training person held out in
    turn, the detectors fit on the others' cases and scored on (a sample of at most
    :data:`HELD_OUT_SAMPLE` of) the held-out person's real cases; the 95 % quantile of all
    those scores (:func:`oracle_threshold` of the held-out known scores)."""
    rng = np.random.default_rng(0)
    held: dict[str, list[np.ndarray]] = {n: [] for n in Peers.NAMES}
    for person in np.unique(people):
        mine = np.flatnonzero((people == person) & real)
        rest = people != person
        if not len(mine) or not rest.any():
            continue
        if len(mine) > HELD_OUT_SAMPLE:
            mine = np.sort(rng.choice(mine, HELD_OUT_SAMPLE, replace=False))
        for name, s in Peers(X[rest], y[rest]).scores(X[mine]).items():
            held[name].append(s)
    return {n: oracle_threshold(np.concatenate(v)) for n, v in held.items() if v}


def distance_thresholds(cb: Any) -> dict[str, float]:
    """The ``nearest`` distance's threshold from the case base alone: the 95 % quantile of
    the nearest-case distance of training cases held out as the margin judges hold them out
    (:func:`cbr.unknown.held_out_activities`, known rows)."""
    from cbr.unknown_held_out import held_out_activities, known_rows

    seen, codes, _, _ = held_out_activities(cb)
    known = seen[known_rows(seen, codes)]
    return {"nearest": oracle_threshold(known.min(axis=1))}


# ---------------------------------------------------------------- path signatures

SIGNATURE_SCORES = ("sig-nearest", "sig-margin", "sig-lof")
"""Novelty scores on the windows' log-signatures (:class:`SigScores`)."""
SIG_FISHER = "judge+sig-fisher"
"""Fisher's ``-2 sum log p`` of the default judge's score and ``sig-nearest``, each p its
upper tail among its own held-out known scores (oracle figures only: the two held-out scans
are of different windows, so no joint held-out distribution sets a threshold)."""
MAX_SIG_TERMS = 6000
"""The most log-signature terms a window may have (memory: a case base's few thousand
windows by this many terms, and their distances)."""
SIG_LIMB_JOINTS = tuple(f"{s}_{j}" for j in ("elbow", "wrist", "knee", "ankle")
                        for s in ("left", "right"))  # fmt: skip
"""The joints whose body-frame positions make the ``positions`` paths (24 channels)."""


@dataclass(frozen=True)
class SigSpec:
    """The window representation of :data:`SIGNATURE_SCORES`: each 2-s window's path
    (``angles``: the DTW baseline's eight limb angles; ``positions``: :data:`SIG_LIMB_JOINTS`
    in the body frame, torso lengths, :func:`features.body.body_positions`) at 30 Hz, every
    channel standardised on the case base's windows, started from the origin (basepoint: the
    signature then sees where the path lies, not only how it moves), time added, lead-lag
    (``lead_lag``), then its log-signature to ``depth``, every term standardised on the case
    base's windows."""

    paths: str = "angles"
    depth: int = 2
    lead_lag: bool = True

    def terms(self) -> int:
        """How many terms each window's log-signature has."""
        import iisignature

        channels = (8 if self.paths == "angles" else 3 * len(SIG_LIMB_JOINTS)) * (
            2 if self.lead_lag else 1
        )
        return int(iisignature.logsiglength(channels + 1, self.depth))

    def suffix(self) -> str:
        """``""`` for the default; else what names its results."""
        if self == SigSpec():
            return ""
        return f"_sig-{self.paths}-d{self.depth}" + ("" if self.lead_lag else "-nolag")


def sig_channels(seq: Any, paths: str) -> np.ndarray:
    """A sequence's path channels at about 30 Hz, gaps interpolated, ``(n, d)``: the eight
    limb angles, or the body-frame positions of :data:`SIG_LIMB_JOINTS`."""
    from benchmarks.segment import DTW_FPS
    from benchmarks.segment_people import _angles
    from cbr.problem import fill_nan_time
    from features.body import body_positions, position_names

    if paths == "angles":
        return _angles(seq)
    if paths != "positions":
        raise ValueError(f"unknown signature paths {paths!r}")
    names = position_names()
    cols = [names.index(f"{j}.{a}") for j in SIG_LIMB_JOINTS for a in ("left", "height", "forward")]
    step = max(1, int(round(seq.fps / DTW_FPS)))
    return np.asarray(fill_nan_time(body_positions(seq)[:, cols], 0.0)[::step])


def sig_fold(
    fold: Fold, joined: list[tuple[Any, Group]], recs: dict[str, Any], paths: str
) -> dict[str, Any]:
    """The fold's windows as paths, once for every left-out movement: the training clips' 2-s
    windows every 0.5 s (as :func:`benchmarks.segment_people.dtw_training` cuts them) with
    their movement and person, and every judged test window (``recs``: each recording's
    window centres in seconds)."""
    from benchmarks.segment import DTW_FPS, DTW_TRAIN_HOP_S, DTW_WINDOW_S
    from benchmarks.segment_people import _windows

    width = int(DTW_WINDOW_S * DTW_FPS)
    Xs, ys, ps = [], [], []
    for seq, g in joined:
        a = sig_channels(seq, paths)
        if len(a) < width:
            continue
        centres_s = np.arange(DTW_WINDOW_S / 2, len(a) / DTW_FPS - DTW_WINDOW_S / 2 + 1e-9,
                              DTW_TRAIN_HOP_S)  # fmt: skip
        Xs.append(_windows(a, centres_s * DTW_FPS))
        ys.append(np.full(len(centres_s), g.movement, dtype=object))
        ps.append(np.full(len(centres_s), g.person, dtype=object))
    test = {
        rec.name: _windows(sig_channels(rec.seq, paths), recs[rec.name]["centres_s"] * DTW_FPS)
        for rec in fold.recordings
    }
    return {"X": np.concatenate(Xs), "y": np.concatenate(ys), "people": np.concatenate(ps),
            "test": test}  # fmt: skip


def log_signatures(windows: np.ndarray, spec: SigSpec) -> np.ndarray:
    """The log-signatures ``(n, k)`` of ``windows`` ``(n, L, d)`` (already standardised)
    started from the origin, time added and (``spec.lead_lag``) lead-lagged, to
    ``spec.depth`` (iisignature)."""
    import iisignature

    from cbr.similarity.signature import augment

    path = augment(windows, time=True, lead_lag_=spec.lead_lag, basepoint=True)
    prepared = iisignature.prepare(path.shape[2], spec.depth)
    return np.asarray(iisignature.logsig(np.ascontiguousarray(path), prepared), dtype=np.float64)


def nearest_and_margin(d: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """From distances ``d`` ``(m, n)`` of m windows to n cases of activities ``y`` ``(n,)``
    (at least two activities): the nearest distance d1 and the margin d1/d2, d2 the nearest
    case of any other activity than the nearest case's (1 when d2 is 0)."""
    per = np.stack([d[:, y == a].min(axis=1) for a in np.unique(y)], axis=1)
    two = np.sort(per, axis=1)[:, :2]
    return two[:, 0], np.where(two[:, 1] > 0, two[:, 0] / np.maximum(two[:, 1], 1e-300), 1.0)


class SigScores:
    """:data:`SIGNATURE_SCORES` against case windows ``X`` ``(n, L, d)`` of activities
    ``y``: the channels standardised on ``X``, each window's :func:`log_signatures`, every
    term standardised on the cases'; :meth:`scores` higher = more unknown."""

    def __init__(self, X: np.ndarray, y: np.ndarray, spec: SigSpec) -> None:
        from sklearn.neighbors import LocalOutlierFactor
        from sklearn.preprocessing import StandardScaler

        self.spec = spec
        flat = X.reshape(-1, X.shape[2])
        self.mean = flat.mean(axis=0)
        self.std = np.where(flat.std(axis=0) > 0, flat.std(axis=0), 1.0)
        sig = log_signatures((X - self.mean) / self.std, spec)
        self.scaler = StandardScaler().fit(sig)
        self.Z = self.scaler.transform(sig)
        self.y = np.asarray(y)
        self.lof = LocalOutlierFactor(n_neighbors=20, novelty=True).fit(self.Z)

    def scores(self, X: np.ndarray) -> dict[str, np.ndarray]:
        from scipy.spatial.distance import cdist

        Z = self.scaler.transform(log_signatures((X - self.mean) / self.std, self.spec))
        d1, margin = nearest_and_margin(cdist(Z, self.Z), self.y)
        return {"sig-nearest": d1, "sig-margin": margin, "sig-lof": -self.lof.score_samples(Z)}


def sig_held(
    X: np.ndarray, y: np.ndarray, people: np.ndarray, spec: SigSpec
) -> dict[str, np.ndarray]:
    """Every :data:`SIGNATURE_SCORES` of the case windows held out by person: each training
    person's windows (a seeded sample of at most :data:`HELD_OUT_SAMPLE`) scored against the
    others' (:class:`SigScores` fit on them alone)."""
    rng = np.random.default_rng(0)
    held: dict[str, list[np.ndarray]] = {n: [] for n in SIGNATURE_SCORES}
    for person in np.unique(people):
        mine = np.flatnonzero(people == person)
        rest = people != person
        if not len(mine) or len(np.unique(y[rest])) < 2:
            continue
        if len(mine) > HELD_OUT_SAMPLE:
            mine = np.sort(rng.choice(mine, HELD_OUT_SAMPLE, replace=False))
        for name, s in SigScores(X[rest], y[rest], spec).scores(X[mine]).items():
            held[name].append(s)
    return {n: np.concatenate(v) for n, v in held.items() if v}


def with_signature(
    left: dict[str, Any],
    sig: dict[str, Any],
    movement: str,
    spec: SigSpec,
    held: dict[str, Any] | None,
) -> dict[str, Any]:
    """``left`` (:func:`measure_left_out`) with each recording's :data:`SIGNATURE_SCORES`
    against the fold's training windows (``sig``, :func:`sig_fold`) of the movements but
    ``movement``, their thresholds held out by person (:func:`sig_held`: the 95 % quantile),
    and with the judge's held-out scan ``held`` (:func:`held_scan`) :data:`SIG_FISHER`."""
    keep = sig["y"] != movement
    X, y, people = sig["X"][keep], sig["y"][keep].astype(str), sig["people"][keep]
    model = SigScores(X, y, spec)
    scan = sig_held(X, y, people, spec)
    for name, s in scan.items():
        left["thresholds"][name] = oracle_threshold(s)
    for name, r in left["recordings"].items():
        scores = model.scores(sig["test"][name])
        r["scores"].update(scores)
        if held is not None:
            tails = {JUDGE: held["known"][JUDGE], "sig-nearest": scan["sig-nearest"]}
            parts = {JUDGE: r["scores"][JUDGE], "sig-nearest": scores["sig-nearest"]}
            r["scores"][SIG_FISHER] = tail_fused(tails, parts, "tail-fisher")
    left["sig_cases"] = int(len(X))
    return left


# ---------------------------------------------------------------- combinations

COMBINED = ("tail-max", "tail-fisher", "logistic")
"""Combinations of the default judge's score and the nearest distance d1 (:data:`PARTS`),
each calibrated on the case base's held-out scan alone (:func:`held_scan`)."""
PARTS = (JUDGE, "nearest")


def tail_p(held: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The upper-tail probability of every score ``x`` ``(m,)`` among the held-out known
    scores ``held`` ``(n,)`` (non-empty): ``(1 + #{held >= x}) / (n + 1)``, the smallest
    ``1 / (n + 1)`` (inf scores above every held one)."""
    h = np.sort(np.asarray(held, dtype=np.float64))
    above = len(h) - np.searchsorted(h, np.asarray(x, dtype=np.float64), side="left")
    return np.asarray((1.0 + above) / (len(h) + 1.0))


def tail_fused(held: dict[str, np.ndarray], scores: dict[str, np.ndarray], how: str) -> np.ndarray:
    """Each part's scores ``scores[name]`` ``(m,)`` as :func:`tail_p` of its held-out known
    scores ``held[name]``, fused: ``tail-max``, ``-log`` of the least (the most surprising
    part decides, a Bonferroni/Sidak union); ``tail-fisher``, Fisher's ``-2 sum log p``.
    Higher = more unknown."""
    logs = np.stack([np.log(tail_p(held[n], scores[n])) for n in held])
    if how == "tail-max":
        return np.asarray(-logs.min(axis=0))
    if how == "tail-fisher":
        return np.asarray(-2.0 * logs.sum(axis=0))
    raise ValueError(f"unknown fusion {how!r}")


def _log_features(held: dict[str, np.ndarray], scores: dict[str, np.ndarray]) -> np.ndarray:
    """``(m, parts)``: the log of each part's scores, clipped into the held-out range widened
    tenfold (an inf score, a window too still for every case, at the top)."""
    cols = []
    for n, h in held.items():
        f = np.asarray(h, dtype=np.float64)
        f = f[np.isfinite(f) & (f > 0)]
        lo, hi = float(f.min()) / 10.0, float(f.max()) * 10.0
        cols.append(np.log(np.clip(np.nan_to_num(scores[n], posinf=hi), lo, hi)))
    return np.stack(cols, axis=1)


def logistic_fused(held_known: dict[str, np.ndarray], held_novel: dict[str, np.ndarray],
                   scores: dict[str, np.ndarray]) -> np.ndarray:  # fmt: skip
    """The log-odds of "novel" of ``scores`` (each part ``(m,)``) by a logistic regression
    (scikit-learn, classes balanced, features :func:`_log_features` standardised) fit on the
    case base's held-out cases: known (their activity in) against novel (their activity left
    out), ``held_known`` / ``held_novel`` each part's scores. Higher = more unknown."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    X = np.r_[_log_features(held_known, held_known), _log_features(held_known, held_novel)]
    y = np.r_[np.zeros(len(next(iter(held_known.values())))),
              np.ones(len(next(iter(held_novel.values()))))]  # fmt: skip
    model = make_pipeline(StandardScaler(), LogisticRegression(class_weight="balanced"))
    model.fit(X, y)
    return np.asarray(model.decision_function(_log_features(held_known, scores)))


def combined_scores(
    held: dict[str, Any], scores: dict[str, np.ndarray]
) -> dict[str, tuple[np.ndarray, float]]:
    """Every combination of :data:`COMBINED` of the windows' ``scores`` (each part's ``(m,)``)
    with its threshold calibrated on the held-out scan ``held`` (:func:`held_scan`:
    ``known`` and ``novel`` each part's scores): the :func:`oracle_threshold` (95 %) of the
    held-out known cases' own combined scores."""
    k, n = held["known"], held["novel"]
    out = {}
    for how in ("tail-max", "tail-fisher"):
        out[how] = (tail_fused(k, scores, how), oracle_threshold(tail_fused(k, k, how)))
    out["logistic"] = (logistic_fused(k, n, scores), oracle_threshold(logistic_fused(k, n, k)))
    return out


def held_scan(cb: Any) -> dict[str, Any]:
    """The case base's held-out scan as the judges read it
    (:func:`cbr.unknown.held_out_activities`): the default judge's score (over its nearest
    activity's threshold, the judge calibrated on that scan as ``segment`` calibrates it) and
    the nearest distance of the held-out known cases (their activity within reach) and novel
    ones (their activity left out; see :func:`cbr.unknown.known_and_novel`)."""
    from cbr.unknown import for_person
    from cbr.unknown_held_out import held_out_activities, known_and_novel
    from cbr.unknown_stored import STORED

    held = held_out_activities(cb)
    judge = STORED[JUDGE].of(cb, held=held)
    seen, codes, basis, groups = held
    out: dict[str, Any] = {"basis": basis}
    for kind, rows in zip(("known", "novel"), known_and_novel(seen, codes), strict=True):
        mine = for_person(judge, rows.min(axis=1))
        score = np.array([mine.ratio(r) / mine.threshold(r) for r in rows])  # type: ignore[attr-defined]
        out[kind] = {JUDGE: score, "nearest": rows.min(axis=1)}
    return out


def dtw_fold(fold: Fold, joined: list[tuple[Any, Group]], recs: dict[str, Any]) -> dict[str, Any]:
    """The DTW distances of a fold, computed once for every left-out movement: from every
    judged test window (``recs``: each recording's window centres in seconds) to every
    training window, and from a sample of training windows to every training window (for
    the threshold held out by person)."""
    from benchmarks.segment import DTW_FPS
    from benchmarks.segment_people import _angles, _windows

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from tslearn.metrics import cdist_dtw

    Xs, ys, ps = [], [], []
    for seq, g in joined:
        try:
            X, y = dtw_training([(seq, g.movement)])
        except ValueError:  # shorter than one window: none
            continue
        Xs.append(X)
        ys.append(y)
        ps.append(np.full(len(y), g.person, dtype=object))
    X, y, people = np.concatenate(Xs), np.concatenate(ys), np.concatenate(ps)
    test = {}
    for rec in fold.recordings:
        centres_s = recs[rec.name]["centres_s"]
        test[rec.name] = cdist_dtw(_windows(_angles(rec.seq), centres_s * DTW_FPS), X)
    rng = np.random.default_rng(0)
    sample = np.sort(rng.choice(len(X), min(len(X), DTW_HELD_OUT_SAMPLE), replace=False))
    return {"y": y, "people": people, "test": test, "sample": sample,
            "train": cdist_dtw(X[sample], X)}  # fmt: skip


def measure_left_out(
    fold: Fold,
    joined: list[tuple[Any, Group]],
    movement: str,
    variant: Variant | None = None,
    judge_only: bool = False,
) -> dict[str, Any]:
    """With ``movement`` left out of the fold's case base (fit with ``variant``'s options):
    for every test recording, its judged windows' spans, movements, voted activities and
    scores, and the blocks ``segment`` calls unknown; the calibrated thresholds
    (``judge_only``: without the scikit-learn peers)."""
    from benchmarks.segment import judge_named
    from cbr.segmentation import finish, solve_recording
    from cbr.unknown import for_person, unknown_evidence

    clf = fit(training_clips(joined, leave_out=movement), **(variant or Variant()).params())
    cb = clf.case_base_
    classes = np.array([str(c) for c in clf.classes_], dtype=object)
    judge = judge_named(clf, JUDGE)
    margin_judge = judge_named(clf, "margin")
    X, real = case_vectors(cb)
    y = np.asarray(cb.labels).astype(str)
    people = np.array([s or "" for s in cb.subjects], dtype=object)
    peers = None if judge_only else Peers(X, y)
    thresholds: dict[str, float] = {JUDGE: 1.0, "margin": float(margin_judge.threshold)}
    thresholds.update(distance_thresholds(cb))
    if not judge_only:
        thresholds.update(peer_thresholds(X, y, people, real))
    recs: dict[str, Any] = {}
    for rec in fold.recordings:
        done = solve_recording(clf, rec.seq, chunk_frames=0)
        counted = [w for w, out in zip(done.windows, done.outliers.tolist(), strict=True)
                   if not out]  # fmt: skip
        mine = for_person(judge, np.array([np.min(w.nearest) for w in counted]))
        windows = [w for w in done.windows if not w.repetition]
        nearest = np.stack([w.nearest for w in windows])
        still = np.array([w.still for w in windows], dtype=bool)
        spans = np.array([(w.start, w.stop) for w in windows], dtype=np.int64)
        score = np.array([mine.ratio(n) / mine.threshold(n) for n in nearest])  # type: ignore[attr-defined]
        two = np.sort(nearest, axis=1)[:, :2]
        scores = {
            JUDGE: np.where(still, np.inf, score),
            "margin": np.where(two[:, 1] > 0, two[:, 0] / np.maximum(two[:, 1], 1e-300), 1.0),
            "nearest": two[:, 0],
        }
        if peers is not None:
            scores.update(peers.scores(query_vectors(cb, [w.solved for w in windows])))
        blocks = np.array(finish(clf, done, judge).blocks[: len(rec.blocks)], dtype=object)
        truth = rec.blocks[: len(blocks)]
        recs[rec.name] = {
            "movements": pure_windows(rec, spans, rec.seq.fps),
            "voted": classes[np.argmax(np.stack([w.vote for w in windows]), axis=1)],
            "centres_s": spans.mean(axis=1) / rec.seq.fps,
            "scores": scores,
            "evidence": np.array(
                [
                    1.0 if s else unknown_evidence(mine, n)
                    for s, n in zip(still, nearest, strict=True)
                ]
            ),  # fmt: skip
            "unlike": np.array([s or mine.unlike(n) for s, n in zip(still, nearest, strict=True)]),
            "blocks_novel": int(np.sum(truth == movement)),
            "blocks_novel_unknown": int(sum(b is None for b in blocks[truth == movement])),
            "blocks_known": int(np.sum(truth != movement)),
            "blocks_known_unknown": int(sum(b is None for b in blocks[truth != movement])),
        }
    return {"cases": len(cb), "thresholds": thresholds, "recordings": recs}


def with_dtw(left: dict[str, Any], dtw: dict[str, Any], movement: str) -> dict[str, Any]:
    """``left`` (:func:`measure_left_out`) with each recording's ``dtw`` score (the nearest
    training window of a movement other than ``movement``) and the DTW threshold held out by
    person."""
    keep = dtw["y"] != movement
    for name, r in left["recordings"].items():
        r["scores"]["dtw"] = dtw["test"][name][:, keep].min(axis=1)
    sample = dtw["sample"]
    rows = [i for i, j in enumerate(sample.tolist()) if keep[j]]
    held = [dtw["train"][i][keep & (dtw["people"] != dtw["people"][sample[i]])].min()
            for i in rows]  # fmt: skip
    left["thresholds"]["dtw"] = oracle_threshold(np.array(held))
    left["dtw_held_out_windows"] = len(rows)
    return left


def with_combined(left: dict[str, Any], held: dict[str, Any]) -> dict[str, Any]:
    """``left`` (:func:`measure_left_out`) with each recording's :data:`COMBINED` scores and
    their thresholds, calibrated on its case base's held-out scan ``held``
    (:func:`held_scan`)."""
    for r in left["recordings"].values():
        for name, (score, t) in combined_scores(held, {p: r["scores"][p] for p in PARTS}).items():
            r["scores"][name] = score
            left["thresholds"][name] = t
    left["held_out_cases"] = {k: len(held[k][JUDGE]) for k in ("known", "novel")}
    return left


def fold_described(
    joined: list[tuple[Any, Group]], variant: Variant | None = None
) -> tuple[list[Any], list[Any]]:
    """The fold's training windows (every movement) and each described as
    :func:`benchmarks.segment_people.fit` describes it with ``variant``'s options (once for
    every case base of the fold: a case base without a movement is fit on the others'
    descriptions)."""
    from cbr.described import describe_clips
    from cbr.estimator import CaseBaseClassifier

    clips = training_clips(joined)
    candidates, mirror, sides = CaseBaseClassifier(
        mirror="auto", **(variant or Variant()).params()
    ).describe_plan()
    return clips, list(describe_clips([c.seq for c in clips], candidates, mirror, sides))


def measure_held(
    described: Callable[[], tuple[list[Any], list[Any]]],
    movement: str,
    variant: Variant | None = None,
) -> dict[str, Any]:
    """:func:`held_scan` of the fold's case base without ``movement`` (``described``: the
    fold's :func:`fold_described`), fit as :func:`benchmarks.segment_people.fit` fits it with
    ``variant``'s options."""
    from cbr.estimator import CaseBaseClassifier

    clips, desc = described()
    keep = [i for i, c in enumerate(clips) if c.label != movement]
    clf = CaseBaseClassifier(mirror="auto", **(variant or Variant()).params()).fit_described(
        [desc[i] for i in keep], [clips[i].label for i in keep]
    )
    return {"cases": len(clf.case_base_), **held_scan(clf.case_base_)}


def scores_in(parts: list[tuple[str, dict[str, Any]]]) -> tuple[str, ...]:
    """The :data:`SCORES` every recording of ``parts`` has (all but a ``--judge-only`` run's
    peers, DTW and combinations)."""
    have = [set(r["scores"]) for _, left in parts for r in left["recordings"].values()]
    return tuple(s for s in SCORES if all(s in h for h in have))


def pool(parts: list[tuple[str, dict[str, Any]]]) -> dict[str, Any]:
    """Known and novel windows' scores, evidence and decisions pooled over ``parts`` (left-out
    movement, :func:`measure_left_out` with DTW), and the blocks."""
    names = scores_in(parts) + ("evidence", "unlike")
    known: dict[str, list[np.ndarray]] = {s: [] for s in names}
    novel: dict[str, list[np.ndarray]] = {s: [] for s in names}
    mixed = 0
    blocks = np.zeros(4, dtype=np.int64)
    right: list[np.ndarray] = []
    for movement, left in parts:
        for r in left["recordings"].values():
            m = r["movements"]
            mixed += int(sum(v is None for v in m))
            is_novel = np.array([v == movement for v in m], dtype=bool)
            is_known = np.array([v is not None and v != movement for v in m], dtype=bool)
            right.append(np.asarray(r["voted"] == m, dtype=bool)[is_known])
            for s in known:
                values = r["scores"][s] if s in r["scores"] else r[s]
                known[s].append(np.asarray(values)[is_known])
                novel[s].append(np.asarray(values)[is_novel])
            blocks += [r["blocks_known"], r["blocks_known_unknown"], r["blocks_novel"],
                       r["blocks_novel_unknown"]]  # fmt: skip
    return {
        "known": {s: np.concatenate(v) for s, v in known.items()},
        "novel": {s: np.concatenate(v) for s, v in novel.items()},
        "mixed_windows": mixed,
        "blocks": blocks,
        "known_voted_right": np.concatenate(right) if right else np.zeros(0, dtype=bool),
    }


def summarise(parts: list[tuple[str, dict[str, Any]]]) -> dict[str, Any]:
    """The figures of every score over ``parts`` (left-out movement, measured), pooled: one
    oracle threshold for all; each part's calibrated threshold applied to its own windows."""
    p = pool(parts)
    k, n = p["known"], p["novel"]
    out: dict[str, Any] = {
        "known_windows": len(k[JUDGE]),
        "novel_windows": len(n[JUDGE]),
        "windows_across_a_change_left_out": p["mixed_windows"],
        # seen accuracy at window level: known windows whose k-NN vote names their movement
        "known_windows_voted_right": float(np.mean(p["known_voted_right"]))
        if len(p["known_voted_right"])
        else float("nan"),
    }
    for s in scores_in(parts):
        out[s] = figures(k[s], n[s], None)
        kept, caught = _calibrated_shares(parts, s)
        if kept is not None:
            out[s]["calibrated"] = {"known_kept": kept, "novel_unknown": caught}
    out[JUDGE]["evidence_auroc"] = auroc(k["evidence"], n["evidence"])
    out[JUDGE]["mean_evidence"] = {"known": float(np.mean(k["evidence"])),
                                   "novel": float(np.mean(n["evidence"]))}  # fmt: skip
    out[JUDGE]["decisions"] = {"known_kept": float(np.mean(~k["unlike"])),
                               "novel_unknown": float(np.mean(n["unlike"]))}  # fmt: skip
    b = p["blocks"]
    out["segment_blocks"] = {
        "known_blocks_not_unknown": 1.0 - float(b[1]) / max(1, int(b[0])),
        "novel_blocks_unknown": float(b[3]) / max(1, int(b[2])),
    }
    return out


def _calibrated_shares(
    parts: list[tuple[str, dict[str, Any]]], score: str
) -> tuple[float | None, float | None]:
    """The shares of known windows kept and novel windows called unknown when each part's
    windows meet that part's threshold for ``score`` calibrated on its case base."""
    kept, caught, nk, nn = 0, 0, 0, 0
    for movement, left in parts:
        t = left["thresholds"].get(score)
        if t is None:
            return None, None
        one = pool([(movement, left)])
        kept += int(np.sum(one["known"][score] <= t))
        caught += int(np.sum(one["novel"][score] > t))
        nk += len(one["known"][score])
        nn += len(one["novel"][score])
    return kept / max(1, nk), caught / max(1, nn)


def spaced(items: list[str], n: int | None) -> list[str]:
    """``n`` of ``items`` evenly spaced (all when ``n`` is None or not fewer)."""
    if n is None or n >= len(items):
        return items
    return [items[int(i)] for i in np.linspace(0, len(items) - 1, n).round().astype(int)]


class SmoothedReader(Reader):
    """:class:`benchmarks.segment_people.Reader` with every repetition file's joints smoothed
    as their own jitter asks (:func:`features.jitter.smooth_jitter`), before joining: training
    and test alike (``--smooth-jitter``)."""

    def __call__(self, group: Group, path: Path) -> Any:
        from features.jitter import smooth_jitter

        if path not in self.cache:
            self.cache[path] = smooth_jitter(super().__call__(group, path))
        return self.cache[path]


def run_dataset(
    dataset: str,
    left_out: int | None,
    cache: Path | None,
    per_person: int = 1,
    seed: int = 0,
    smooth: bool = False,
    variant: Variant | None = None,
    judge_only: bool = False,
    spec: SigSpec | None = None,
) -> list[tuple[str, str, dict[str, Any]]]:
    """``(fold, movement, measured)`` for every fold of ``dataset`` and each movement left out
    (``smooth``: every file read through :class:`SmoothedReader`; ``variant``: the case
    bases' options; ``judge_only``: the default judge, ``margin``, ``nearest`` and the
    signature scores alone, no peers, DTW or combinations; ``spec``: the signature scores'
    window representation)."""
    from features.progress import progress

    variant = variant or Variant()
    spec = spec or SigSpec()
    read = SmoothedReader() if smooth else Reader()
    out = []
    for fold in folds(dataset, per_person, seed, read):
        base = f"v{CACHE_VERSION}-{dataset}-{fold.name.replace(' ', '_')}-seed{seed}"
        tag = base + (f"-per{per_person}" if per_person != 1 else "")
        tag += "-smoothed" if smooth else ""
        dtw_tag = tag  # the DTW distances do not depend on the case base's options
        tag += variant.suffix().replace("_", "-") + ("-judge" if judge_only else "")
        joined = joined_training(fold.train, read)
        movements = spaced(sorted({m for r in fold.recordings for m in r.movements}), left_out)
        measured = {}
        for movement in progress(movements, f"{dataset} {fold.name}: left out", unit="movement"):
            measured[movement] = _cached(
                cache,
                f"{tag}-{movement}",
                partial(measure_left_out, fold, joined, movement, variant, judge_only),
            )
        first = next(iter(measured.values()))["recordings"]
        sig = sig_fold(fold, joined, first, spec.paths)
        if judge_only:
            out += [(fold.name, m, with_signature(v, sig, m, spec, None))
                    for m, v in measured.items()]  # fmt: skip
            continue
        dtw = _cached(cache, f"{dtw_tag}-dtw", partial(dtw_fold, fold, joined, first))
        # the fold's descriptions, made when a held-out scan needs them (once)
        describe_once = cache_once(partial(fold_described, joined, variant))
        # the case bases do not depend on --per-person: one scan for every run
        htag = base + ("-smoothed" if smooth else "") + variant.suffix().replace("_", "-")
        for m, v in measured.items():
            held = _cached(
                cache, f"{htag}-{m}-held", partial(measure_held, describe_once, m, variant)
            )
            if held["cases"] != v["cases"]:
                raise RuntimeError(f"{fold.name} without {m}: {held['cases']} cases, not "
                                   f"{v['cases']} as measured")  # fmt: skip
            v = with_combined(with_dtw(v, dtw, m), held)
            out.append((fold.name, m, with_signature(v, sig, m, spec, held)))
    return out


def dataset_summary(measured: list[tuple[str, str, dict[str, Any]]]) -> dict[str, Any]:
    """Pooled over the dataset's left-out movements (one threshold), and per movement."""
    parts = [(m, v) for _, m, v in measured]
    per: dict[str, Any] = {}
    for movement in sorted({m for m, _ in parts}):
        per[movement] = summarise([p for p in parts if p[0] == movement])
    return {
        "pooled": summarise(parts),
        "per_movement": per,
        "cases": sorted({v["cases"] for _, _, v in measured}),
        "dtw_held_out_windows": sorted(
            {v["dtw_held_out_windows"] for _, _, v in measured if "dtw_held_out_windows" in v}
        ),
    }


def print_table(summary: dict[str, Any]) -> None:
    print("\nLeft-out movements' 2-s windows vs known ones, people not in the case base")
    print(f"  {'dataset, score':42s}{'AUROC':>7s}{'oracle @95%':>13s}"
          f"{'calibrated: kept':>18s}{'unknown':>9s}")  # fmt: skip
    for dataset, s in summary.items():
        p = s["pooled"]
        names = [n for n in SCORES if n in p]
        for name in names:
            if name == COMBINED[0]:
                print(f"  {'':4s}combined, {JUDGE} with nearest, calibrated on the held-out scan")
            if name == SIG_FISHER:
                print(f"  {'':4s}combined, {JUDGE} with sig-nearest (oracle only)")
            o = p[name]
            cal = o.get("calibrated")
            tail = f"{cal['known_kept']:18.1%}{cal['novel_unknown']:9.1%}" if cal else ""
            print(f"  {dataset + ', ' + name:42s}{o['auroc']:7.3f}"
                  f"{o['oracle_unknown_at_95_known']:13.1%}{tail}")  # fmt: skip
        d, e = p[JUDGE]["decisions"], p["segment_blocks"]
        print(
            f"  {dataset + ', ' + JUDGE + ' decisions':42s}{p[JUDGE]['evidence_auroc']:7.3f}"
            f"{'(evidence)':>13s}{d['known_kept']:18.1%}{d['novel_unknown']:9.1%}"
        )
        print(
            f"  {dataset + ', segment blocks':42s}{'':7s}{'':13s}"
            f"{e['known_blocks_not_unknown']:18.1%}{e['novel_blocks_unknown']:9.1%}"
        )
        print(f"  {dataset + ', known windows voted right':42s}{'':7s}{'':13s}"
              f"{p['known_windows_voted_right']:18.1%}")  # fmt: skip
        print(f"  {'':4s}per movement, AUROC " + " / ".join(names))
        for movement, o in s["per_movement"].items():
            print(f"  {'':4s}{movement[:29]:30s}" + " ".join(f"{o[n]['auroc']:.2f}" for n in names))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.unknown_ceiling",
                                     description=__doc__.split("\n\n")[0])  # fmt: skip
    parser.add_argument("--datasets", nargs="+", choices=DATASETS, default=list(DATASETS))
    parser.add_argument("--left-out", type=int, default=None, metavar="N",
                        help="left out in turn: only N of each fold's movements, evenly "
                        "spaced in sorted order (default: every one)")  # fmt: skip
    parser.add_argument(
        "--per-person",
        type=int,
        default=1,
        metavar="N",
        help="test recordings per person (segment_people's; default 1, its table's)",
    )
    parser.add_argument(
        "--cache",
        type=Path,
        default=None,
        metavar="DIR",
        help="keep each fold's measurements here (a rerun resumes)",
    )
    parser.add_argument(
        "--smooth-jitter",
        action="store_true",
        help="smooth every joint as its own measured jitter asks (features.jitter), training "
        "and test alike; writes unknown_ceiling_smoothed.json",
    )
    parser.add_argument(
        "--feature-weights",
        choices=("none", "fisher"),
        default="none",
        help="the case bases' feature weights (default none, as train --split windows); "
        "fisher: each column weighted by its between- over within-activity variance on the "
        "case base; writes unknown_ceiling_fisher.json",
    )
    parser.add_argument(
        "--velocity",
        action="store_true",
        help="the case bases' problems also summarise every column's rate of change "
        "(train --velocity); writes unknown_ceiling_velocity.json",
    )
    parser.add_argument(
        "--judge-only",
        action="store_true",
        help="only the default judge, margin, nearest and the signature scores (no "
        "scikit-learn peers, DTW or combinations: a quick screen); writes ..._judge.json",
    )
    parser.add_argument(
        "--signature-paths",
        choices=("angles", "positions"),
        default="angles",
        help="the signature scores' paths: the eight limb angles (default) or the body-frame "
        "positions of the elbows, wrists, knees and ankles",
    )
    parser.add_argument(
        "--signature-depth",
        type=int,
        choices=(2, 3, 4),
        default=2,
        help="the log-signature's depth (default 2)",
    )
    parser.add_argument(
        "--signature-no-lead-lag",
        action="store_true",
        help="the signature paths without the lead-lag transform (time and basepoint only)",
    )
    args = parser.parse_args(argv)
    if args.left_out is not None and args.left_out < 1:
        parser.error(f"--left-out must be at least 1, got {args.left_out}")
    if args.per_person < 1:
        parser.error(f"--per-person must be at least 1, got {args.per_person}")
    if not UIPRMD.is_dir() or not HDM05.is_dir():
        print(f"no ui-prmd or hdm05 data under {UIPRMD.parents[1]}: nothing to measure")
        return 1
    import numba

    numba.set_num_threads(1)
    load_at_start = [round(x, 2) for x in os.getloadavg()]
    variant = Variant(args.feature_weights, args.velocity)
    spec = SigSpec(args.signature_paths, args.signature_depth, not args.signature_no_lead_lag)
    if spec.terms() > MAX_SIG_TERMS:
        parser.error(
            f"{spec.terms():,} log-signature terms a window with these --signature options; "
            f"at most {MAX_SIG_TERMS:,} (a lower depth or no lead-lag)"
        )
    summary: dict[str, Any] = {}
    for dataset in args.datasets:
        t0 = time.perf_counter()
        measured = run_dataset(
            dataset,
            args.left_out,
            args.cache,
            args.per_person,
            smooth=args.smooth_jitter,
            variant=variant,
            judge_only=args.judge_only,
            spec=spec,
        )
        summary[dataset] = {**dataset_summary(measured), "wall_s": time.perf_counter() - t0,
                            "left_out": sorted({m for _, m, _ in measured})}  # fmt: skip
        print_table({dataset: summary[dataset]})
    print_table(summary)
    result = {
        "benchmark": "unknown_ceiling",
        "command": "python -m benchmarks.unknown_ceiling --datasets "
        + " ".join(args.datasets)
        + (f" --left-out {args.left_out}" if args.left_out else "")
        + (f" --per-person {args.per_person}" if args.per_person != 1 else "")
        + (" --smooth-jitter" if args.smooth_jitter else "")
        + (f" --feature-weights {args.feature_weights}" if args.feature_weights != "none" else "")
        + (" --velocity" if args.velocity else "")
        + (" --judge-only" if args.judge_only else "")
        + (f" --signature-paths {spec.paths}" if spec.paths != "angles" else "")
        + (f" --signature-depth {spec.depth}" if spec.depth != 2 else "")
        + (" --signature-no-lead-lag" if not spec.lead_lag else ""),
        "note": "window level, as cbr.unknown's judges see each window; oracle: the threshold "
        "read from the test windows themselves, the lowest keeping >= 95 % of known windows "
        "known; calibrated: from the case base alone (held out by training person)",
        "machine": one_thread_machine(),
        "load_average_at_start": load_at_start,
        "versions": versions("posecbr", "numpy", "scipy", "scikit-learn", "tslearn", "numba"),
        "summary": summary,
    }
    if args.cache is not None:
        result["cache"] = (
            "measurements read from --cache where a run had made them: wall_s is this run's"
        )
    out = RESULTS
    if args.per_person != 1:
        out = RESULTS.with_name(f"unknown_ceiling_per{args.per_person}.json")
    if args.smooth_jitter:
        out = out.with_name(f"{out.stem}_smoothed.json")
    judge = "_judge" if args.judge_only else ""
    out = out.with_name(f"{out.stem}{variant.suffix()}{judge}{spec.suffix()}.json")
    write_json(result, out)
    print(f"\nwrote {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
