"""``evaluate_criteria`` works on every test of the ADD at once; here each criterion is worked
out one test at a time from the ADD's own definitions (module docstring of
``features.qmp.add``: a condition is ``min <= quantity <= max``; a relation asks both
amplitudes at least ``min_amplitude``, the longer period at most ``max_period_ratio`` times the
shorter and the phase gap (from anti-phase for ``anti_phase``) at most ``max_phase_diff_rad``;
a variant holds when all its tests do; "both" sides: every variant, "either": one), on real
clips' fits over sliding windows (windows where some signal has too little data included)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from features.datasets import load_dataset
from features.fluents import state_signals
from features.qmp.add import Condition, evaluate_criteria, load_add, phase_gap
from features.qmp.fit import NOT_ENOUGH_DATA, QMPFits, fit_signals

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"


def _one_test(test: object, fits: QMPFits) -> tuple[np.ndarray, np.ndarray]:
    """(passed, observable) ``(W,)`` of one test, by its definition."""
    idx = [fits.index(s) for s in test.signals]  # type: ignore[attr-defined]
    observable = np.ones(len(fits.windows), dtype=bool)
    for i in idx:
        observable &= fits.status[:, i] != NOT_ENOUGH_DATA
    if isinstance(test, Condition):
        v = fits.quantity(test.quantity)[:, idx[0]]
        ok = np.isfinite(v)
        with np.errstate(invalid="ignore"):
            if test.min is not None:
                ok &= v >= test.min
            if test.max is not None:
                ok &= v <= test.max
        return ok, observable
    amp = fits.quantity("amplitude")
    per = fits.quantity("period_s")
    a, b = idx
    gap = phase_gap(fits, a, b)
    if test.relation == "anti_phase":  # type: ignore[attr-defined]
        gap = np.pi - gap
    passed = np.zeros(len(fits.windows), dtype=bool)
    for w in range(len(fits.windows)):
        longer, shorter = max(per[w, a], per[w, b]), min(per[w, a], per[w, b])
        passed[w] = bool(
            np.isfinite(gap[w])
            and amp[w, a] >= test.min_amplitude  # type: ignore[attr-defined]
            and amp[w, b] >= test.min_amplitude  # type: ignore[attr-defined]
            and longer / shorter <= test.max_period_ratio  # type: ignore[attr-defined]
            and gap[w] <= test.max_phase_diff_rad  # type: ignore[attr-defined]
        )
    return passed, observable


@pytest.fixture(scope="module")
def windowed_fits() -> list[QMPFits]:
    add = load_add()
    clips = load_dataset(DEMO)[::6]
    out = []
    for c in clips:
        sig = state_signals(c.seq.to_canonical())
        values = sig.values[:, [sig.names.index(s) for s in add.signals]]
        out.append(fit_signals(values, c.seq.fps, add.signals, window_s=1.0, step_s=0.5))
    return out


def test_every_criterion_in_every_window_as_its_tests_define_it(
    windowed_fits: list[QMPFits],
) -> None:
    add = load_add()
    n_checked = n_met = n_unobservable = 0
    for fits in windowed_fits:
        res = evaluate_criteria(add, fits)
        assert res.names == tuple(add.criteria)
        for q, crit in enumerate(add.criteria.values()):
            for w in range(len(fits.windows)):
                met, seen, share = [], [], []
                for variant in crit.variants:
                    tested = [_one_test(t, fits) for t in variant]
                    ok = [bool(p[w]) for p, _ in tested]
                    obs = all(bool(o[w]) for _, o in tested)
                    met.append(all(ok) and obs)
                    seen.append(obs)
                    share.append(sum(ok) / len(ok) if obs else 0.0)
                both = crit.sides == "both"
                assert res.met[w, q] == (all(met) if both else any(met)), (crit.name, w)
                assert res.observable[w, q] == (all(seen) if both else any(seen)), (crit.name, w)
                expected = sum(share) / len(share) if both else max(share)
                assert res.fraction[w, q] == pytest.approx(expected, abs=1e-12), (crit.name, w)
                n_checked += 1
                n_met += bool(res.met[w, q])
                n_unobservable += not res.observable[w, q]
            # a miss is explained in the observable window where the criterion came closest
            missed = ~res.met[:, q] & res.observable[:, q]
            if missed.any():
                best = res.fraction[missed, q].max()
                assert res.observable[res.closest[q], q] and not res.met[res.closest[q], q]
                assert res.fraction[res.closest[q], q] == best
                assert res.failed[q]
            else:
                assert res.closest[q] == -1 and res.failed[q] == ()
    # the clips exercise every outcome: criteria met, missed, and unobservable
    assert n_met > 0 and n_unobservable > 0 and n_met < n_checked
