"""How often `compare`'s bootstrap intervals over people hold the population's figure.

Run: ``python -m benchmarks.bootstrap_coverage [--reps 400] [--seed 53]`` (3 to 7
minutes on one of two shared cores). Writes ``benchmarks/results/bootstrap_coverage.json``.

Simulated leave-one-subject-out outcomes with a known spread between people: 3 balanced
classes; person i gets a clip of class k right with chance ``expit(logit(mu_k) + sigma *
z_i)``, ``z_i ~ N(0, 1)``, ``mu = (0.95, 0.8, 0.6)``; a wrong answer of class 1 or 2 is class
0, of class 0 class 1 (so macro-F1 is not the accuracy). The population's accuracy and
macro-F1 are those of the expected counts over infinitely many people (Gauss-Hermite over
``z``). For 3, 5 and 8 people of 12, 51 and 198 clips and ``sigma`` 0, 0.5 and 1, ``--reps``
data sets are drawn and each scheme's 95 % percentile interval (1,000 resamples) is checked
for holding the population's figure:

- ``people``: the people drawn with replacement, each with all their clips (hunt 53i's
  accuracy interval);
- ``two``: the people, then each drawn person's clips drawn again (``compare``'s, for the
  accuracy and macro-F1 alike since hunt 53w);
- ``clips``: the clips alone, as if independent (``compare``'s under k-fold).

A person's clips drawn again with replacement are a multinomial draw over their confusion
cells, the same distribution as drawing them one by one, as
:func:`cbr.evaluation.stats.bootstrap_accuracy` does.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import expit, logit

from benchmarks import write_json
from benchmarks._common import versions

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "bootstrap_coverage.json"
MU = np.array([0.95, 0.8, 0.6])
K = len(MU)
DEST = np.zeros((K, K))
"""``DEST[k, j] = 1``: class k's wrong answers are class j."""
DEST[0, 1] = 1
DEST[1:, 0] = 1
SCHEMES = ("people", "two", "clips")
N_BOOT = 1000


def population(sigma: float) -> tuple[float, float]:
    """The accuracy and macro-F1 of the expected counts over the population of people."""
    z, w = np.polynomial.hermite_e.hermegauss(80)
    w = w / w.sum()
    right = (w[:, None] * expit(logit(MU)[None, :] + sigma * z[:, None])).sum(axis=0)
    fp = (1 - right) @ DEST
    f1 = 2 * right / (2 * right + fp + (1 - right))
    return float(right.mean()), float(f1.mean())


def figures(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Accuracy and macro-F1 of counts ``(..., K, 2)``: per true class, right and wrong."""
    right, wrong = cells[..., 0], cells[..., 1]
    acc = right.sum(-1) / (right + wrong).sum(-1)
    den = 2 * right + wrong @ DEST + wrong
    with np.errstate(invalid="ignore", divide="ignore"):
        f1 = np.where(den > 0, 2 * right / np.where(den > 0, den, 1), np.nan)
    return acc, np.nanmean(f1, axis=-1)


def one_data_set(
    rng: np.random.Generator, people: int, clips: int, sigma: float
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """One simulated data set's resampled accuracy and macro-F1 ``(N_BOOT,)`` per scheme."""
    p = expit(logit(MU)[None, :] + sigma * rng.standard_normal(people)[:, None])
    per = clips // K
    right = rng.binomial(per, p)
    cells = np.stack([right, per - right], axis=-1)  # (people, K, 2)
    picked = cells[rng.integers(0, people, size=(N_BOOT, people))]
    again = rng.multinomial(per * K, picked.reshape(N_BOOT, people, 2 * K) / (per * K))
    pooled = cells.sum(0).reshape(2 * K)
    iid = rng.multinomial(pooled.sum(), pooled / pooled.sum(), size=N_BOOT)
    return {
        "people": figures(picked.sum(1)),
        "two": figures(again.reshape(N_BOOT, people, K, 2).sum(1)),
        "clips": figures(iid.reshape(N_BOOT, K, 2)),
    }


def run(reps: int, seed: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    rows = []
    for sigma in (0.0, 0.5, 1.0):
        acc, f1 = population(sigma)
        for people in (3, 5, 8):
            for clips in (12, 51, 198):
                held = {s: np.zeros(2) for s in SCHEMES}
                width = {s: 0.0 for s in SCHEMES}
                for _ in range(reps):
                    for s, (a, f) in one_data_set(rng, people, clips, sigma).items():
                        lo_a, hi_a = np.quantile(a, [0.025, 0.975])
                        lo_f, hi_f = np.nanquantile(f, [0.025, 0.975])
                        held[s] += [lo_a <= acc <= hi_a, lo_f <= f1 <= hi_f]
                        width[s] += (hi_a - lo_a) / reps
                rows.append(
                    {
                        "people": people,
                        "clips_each": clips,
                        "sigma": sigma,
                        "accuracy": acc,
                        "macro_f1": f1,
                        **{f"accuracy_held_{s}": held[s][0] / reps for s in SCHEMES},
                        **{f"macro_f1_held_{s}": held[s][1] / reps for s in SCHEMES},
                        **{f"accuracy_width_{s}": width[s] for s in SCHEMES},
                    }
                )
                r = rows[-1]
                print(
                    f"{people:>6} {clips:>5} {sigma:>5.1f} {acc:>6.3f} {f1:>6.3f}  "
                    + " ".join(f"{100 * r[f'accuracy_held_{s}']:>6.1f}" for s in SCHEMES)
                    + "  "
                    + " ".join(f"{100 * r[f'macro_f1_held_{s}']:>6.1f}" for s in SCHEMES)
                    + "  "
                    + " ".join(f"{100 * r[f'accuracy_width_{s}']:>5.1f}" for s in SCHEMES[:2]),
                    flush=True,
                )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bootstrap_coverage")
    parser.add_argument("--reps", type=int, default=400, help="data sets per setting")
    parser.add_argument("--seed", type=int, default=53)
    args = parser.parse_args(argv)
    print(
        "people clips sigma    acc     f1  % held: accuracy people/two/clips"
        "  macro-F1 people/two/clips  width % people/two"
    )
    started = time.perf_counter()
    rows = run(args.reps, args.seed)
    write_json(
        {
            "benchmark": "bootstrap_coverage",
            "command": f"python -m benchmarks.bootstrap_coverage --reps {args.reps}"
            f" --seed {args.seed}",
            "n_boot": N_BOOT,
            "mu": MU.tolist(),
            "seconds": time.perf_counter() - started,
            "versions": versions("numpy", "scipy"),
            "rows": rows,
        },
        RESULTS,
    )
    print(f"\nwrote {RESULTS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
