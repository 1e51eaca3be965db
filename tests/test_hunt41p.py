"""The 0.1-s block decoders of ``segment`` (:func:`cbr.segmentation.decode`,
:func:`cbr.segmentation.decode_unknown`) take their forward pass a chunk of blocks at a time
(:func:`cbr.segmentation._forward`) and follow the best path back a run at a time: the same
paths, bit for bit, as the textbook recurrence taken block by block (below, in plain Python),
ties included, and paths no other path beats (every path of a short recording tried).
``benchmarks.segment_people`` segments once before it times a recording."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from cbr.segmentation import TIE, decode, decode_unknown, log_votes, switch_penalty


def _viterbi(votes: np.ndarray) -> list[int]:
    """The best path block by block: a change of state costs ``switch_penalty()``; a state
    stays when its total is at least the best's less the penalty, else it comes from the best
    (the first of equal totals); the path ends in the first best state."""
    score, penalty = log_votes(votes).tolist(), switch_penalty()
    k = len(score[0])
    total, back = list(score[0]), [[0] * k]
    for row in score[1:]:
        best = max(range(k), key=lambda s: total[s])
        switch = total[best] - penalty
        back.append([s if total[s] >= switch else best for s in range(k)])
        total = [(t if t >= switch else switch) + x for t, x in zip(total, row, strict=True)]
    return _followed(back, max(range(k), key=lambda s: total[s]))


def _viterbi_unknown(votes: np.ndarray, path: np.ndarray) -> list[bool]:
    """Known (0) / unknown (1) block by block: known to unknown and back cost the penalty, and
    so does staying known across a change of ``path``; a tie within TIE is known."""
    score, penalty = log_votes(votes).tolist(), switch_penalty()
    known, unknown = score[0]
    back = [[0, 0]]
    for t in range(1, len(score)):
        stay = known - penalty if path[t] != path[t - 1] else known
        back.append([0 if stay >= unknown - penalty - TIE else 1,
                     1 if unknown > known - penalty + TIE else 0])  # fmt: skip
        known, unknown = (max(stay, unknown - penalty) + score[t][0],
                          max(unknown, known - penalty) + score[t][1])  # fmt: skip
    return [s == 1 for s in _followed(back, int(unknown > known + TIE))]


def _followed(back: list[list[int]], last: int) -> list[int]:
    path = [last]
    for t in range(len(back) - 1, 0, -1):
        path.append(back[t][path[-1]])
    return path[::-1]


def _votes(rng: np.random.Generator, n: int, k: int, kind: str) -> np.ndarray:
    """Vote shares ``(n, k)`` of one kind: every block its own; quarters (ties, zeros and
    ones); held for runs of blocks, as windows hold them; even, with a block here and there
    that is not."""
    if kind == "each":
        return rng.dirichlet(np.ones(k), size=n)
    if kind == "quarters":
        return rng.integers(0, 5, size=(n, k)) / 4.0
    if kind == "runs":
        rows = rng.dirichlet(np.full(k, 0.3), size=n)
        return np.repeat(rows, rng.integers(1, 40, size=n), axis=0)[:n]
    out = np.full((n, k), 1.0 / k)
    out[rng.random(n) < 0.2] = rng.dirichlet(np.ones(k))
    return out


@pytest.mark.parametrize("kind", ["each", "quarters", "runs", "even"])
def test_decode_is_the_block_by_block_viterbi(kind: str) -> None:
    rng = np.random.default_rng(41)
    for _ in range(150):
        n, k = int(rng.integers(1, 400)), int(rng.integers(1, 9))
        votes = _votes(rng, n, k, kind)
        assert decode(votes).tolist() == _viterbi(votes)


@pytest.mark.parametrize("kind", ["each", "quarters", "runs", "even"])
def test_decode_unknown_is_the_block_by_block_viterbi(kind: str) -> None:
    rng = np.random.default_rng(42)
    for _ in range(150):
        n = int(rng.integers(1, 400))
        share = _votes(rng, n, 2, kind)[:, 1]
        votes = np.stack([1.0 - share, share], axis=1)
        path = np.repeat(rng.integers(0, 3, size=n), rng.integers(1, 30, size=n))[:n]
        assert decode_unknown(votes, path).tolist() == _viterbi_unknown(votes, path)


def test_no_path_beats_the_decoded_one() -> None:
    """Every path of 1-6 blocks over 1-3 states scored as the decoder scores one (the log
    votes of its blocks less the penalty per change): none scores more than the decoded."""
    rng = np.random.default_rng(43)
    penalty = switch_penalty()
    for _ in range(300):
        n, k = int(rng.integers(1, 7)), int(rng.integers(1, 4))
        votes = _votes(rng, n, k, str(rng.choice(["each", "quarters"])))
        score = log_votes(votes)

        def worth(p: tuple[int, ...] | list[int], score: np.ndarray = score) -> float:
            changes = sum(a != b for a, b in itertools.pairwise(p))
            return float(sum(score[t, s] for t, s in enumerate(p))) - penalty * changes

        best = max(worth(p) for p in itertools.product(range(k), repeat=n))
        assert worth(decode(votes).tolist()) == pytest.approx(best, abs=1e-9)


def test_long_runs_decoded_at_their_changes() -> None:
    """200,000 blocks (5.6 hours) of runs of 3,000-7,000 blocks, each voting 0.9 for one of
    three activities and 0.05 for the others, then 10,000 blocks of even votes: a change
    costs 10 ln 2 = 6.93, a block on the wrong side of a change ln 18 = 2.89 more, so the
    path changes exactly where the votes do; the even blocks (every activity alike) stay
    with the last run's activity, which no change need be paid to leave. The chunks run
    long here (thousands of blocks)."""
    assert switch_penalty() == pytest.approx(10 * math.log(2))
    rng = np.random.default_rng(44)
    lengths = rng.integers(3000, 7001, size=60)
    lengths = lengths[np.cumsum(lengths) <= 190_000]
    states = np.r_[0, np.cumsum(rng.integers(1, 3, size=len(lengths) - 1))] % 3
    truth = np.repeat(states, lengths)
    votes = np.full((len(truth), 3), 0.05)
    votes[np.arange(len(truth)), truth] = 0.9
    votes = np.vstack([votes, np.full((200_000 - len(truth), 3), 1.0 / 3)])
    want = np.r_[truth, np.full(200_000 - len(truth), truth[-1])]
    assert np.array_equal(decode(votes), want)
    # known throughout, then unknown over one run: it changes where its share does
    share = np.full(len(votes), 0.1)
    a, b = int(np.cumsum(lengths)[3]), int(np.cumsum(lengths)[4])
    share[a:b] = 0.9
    unknown = decode_unknown(np.stack([1.0 - share, share], axis=1), want)
    assert np.flatnonzero(np.diff(unknown.astype(int))).tolist() == [a - 1, b - 1]


def test_segment_people_segments_once_before_its_clock(monkeypatch: pytest.MonkeyPatch) -> None:
    """``benchmarks.segment_people`` times each recording's segmentation; what a process does
    at its first one (numba's retrieval kernels compiled on a cold cache, SciPy's signal
    module imported) fell in the first recording's time (2.3 s against 0.5 s warm: the
    dataset's times real time a third). A training clip is now segmented and finished by
    every judge before any recording is timed, as the DTW baseline is compiled first."""
    from types import SimpleNamespace

    import benchmarks.segment_people as sp
    import cbr.problem
    import cbr.segmentation

    events: list[object] = []
    clf = SimpleNamespace(feature_config_=SimpleNamespace(level="fluents", side="off"),
                          case_base_=())  # fmt: skip
    seq = SimpleNamespace(duration_s=1.0)
    rec = sp.Recording("r", "p", seq, np.array(["m"]), ("m",), 0.0)
    monkeypatch.setattr(
        sp,
        "joined_training",
        lambda train, read: [("training clip", SimpleNamespace(movement="m"))],
    )
    monkeypatch.setattr(sp, "training_clips", lambda joined, leave_out=None: [])
    monkeypatch.setattr(sp, "fit", lambda clips, mirror, weights: clf)
    monkeypatch.setattr(sp, "judge_named", lambda c, name: name)
    monkeypatch.setattr(sp, "dtw_training", lambda pairs: (np.zeros((1, 2)), np.array(["m"])))
    monkeypatch.setattr(sp, "dtw", lambda X, y, r: {})
    monkeypatch.setattr(sp, "ours", lambda c, r, judges: events.append("timed") or {})
    monkeypatch.setattr(sp, "run_unknown", lambda *a: {})
    monkeypatch.setattr(cbr.problem, "warm", lambda *a, **k: None)
    monkeypatch.setattr(cbr.segmentation, "solve_recording",
                        lambda c, s: events.append(("solved", s)) or "done")  # fmt: skip
    monkeypatch.setattr(cbr.segmentation, "finish",
                        lambda c, done, judge: events.append(("finished", judge)))  # fmt: skip
    sp.run_fold(sp.Fold("ui-prmd-vicon", "f", [], [rec]), sp.Reader())
    judges = list(sp.JUDGES)
    assert events == [("solved", "training clip"), *(("finished", j) for j in judges), "timed"]
