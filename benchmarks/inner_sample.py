"""Does capping the inner selection change what is learned? UI-PRMD, 1,600 Kinect clips.

Fitting chooses the side handling, the weighting and the phase means by inner
leave-one-subject-out accuracy, whose all-pairs distances cost the square of the clips; it
scores them on a stratified sample of at most ``cbr.fitting.INNER_SAMPLE`` (2,000) clips. With
1,600 clips the cap does not bite, so this benchmark lowers it to 800 (half the clips) and
compares, on the real data: the choice made on all 1,600 clips, and the leave-one-subject-out
accuracy of the default classifier (fluent summaries, euclidean) through ``posecbr compare``'s
harness.

Run: ``python -m benchmarks.inner_sample`` (about 10 min). Writes
``benchmarks/results/inner_sample.json``.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any

from benchmarks import no_options, write_json

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))
RESULTS = ROOT / "benchmarks" / "results" / "inner_sample.json"
CAPS = (2000, 800)


def _with_cap(cap: int, clips: list[Any]) -> dict[str, Any]:
    import cbr.estimator as est
    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.settings import CompareSettings

    real = est.inner_sample

    def capped(labels: Any, subjects: Any, cap_: int = cap, seed: int = 0) -> Any:
        return real(labels, subjects, cap=cap_, seed=seed)

    est.inner_sample = capped  # type: ignore[assignment]
    try:
        t0 = time.perf_counter()
        seqs = [c.seq for c in clips]
        clf = est.CaseBaseClassifier().fit(seqs, [c.label for c in clips])
        fit_s = time.perf_counter() - t0
        settings = CompareSettings(similarities=("euclidean",), features=("fluents",), dad=False,
                                   peers=(), explain=0)  # fmt: skip
        run = run_compare(clips, settings, source=str(DATA / "ui-prmd"))
    finally:
        est.inner_sample = real
    scores = run.results.methods[0].scores
    assert scores is not None
    return {
        "cap": cap,
        "clips": len(clips),
        "chosen": {"side": clf.side_, "weighting": clf.weighting_, "phases": clf.phases_},
        "inner_scores": clf.selection_,
        "fit_s": round(fit_s, 1),
        "loso_accuracy": scores.accuracy,
        "loso_predictions": list(scores.predictions),
        "load": [round(v, 2) for v in os.getloadavg()],
    }


def main(argv: list[str] | None = None) -> int:
    no_options("inner_sample", __doc__, argv)
    from features.datasets import load_dataset

    os.environ["POSECBR_NO_PROGRESS"] = "1"
    clips = load_dataset(DATA / "ui-prmd")
    runs = [_with_cap(cap, clips) for cap in CAPS]
    full, sampled = runs
    same = sum(a == b for a, b in zip(full["loso_predictions"], sampled["loso_predictions"],
                                      strict=True))  # fmt: skip
    from cbr.evaluation.machine import machine_info

    doc = {
        "benchmark": "inner_sample",
        "machine": machine_info(),
        "runs": [{k: v for k, v in r.items() if k != "loso_predictions"} for r in runs],
        "same_choice": full["chosen"] == sampled["chosen"],
        "same_predictions": same,
        "of": len(full["loso_predictions"]),
    }
    for r in runs:
        print(f"cap {r['cap']:5d}: chosen {r['chosen']}, LOSO accuracy {r['loso_accuracy']:.4f}, "
              f"fit {r['fit_s']} s, load {r['load'][0]}")  # fmt: skip
    print(f"same choice: {doc['same_choice']}; same LOSO prediction for {same} of {doc['of']}")
    write_json(doc, RESULTS)
    return 0


if __name__ == "__main__":
    sys.exit(main())
