"""A comparison as tables for people (plain text) and for spreadsheets (CSV rows)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from features.fileio import write_text_atomic
from features.text import shown

from .results import CompareResults, MethodResult, Scores


def p_value(p: float) -> str:
    """A p-value as people read it; exact binomial tails underflow to 0 for large samples, so
    say how small rather than "0"."""
    return "<1e-300" if p < 1e-300 else f"{p:.3g}"


#: the per-person column's heading: the accuracy on the subjects held out one by one
PERSON = "person % ± sd (min)"


def _person(s: Scores) -> str:
    """The accuracy over the subjects held out, ``mean ± sd (min)`` in %; empty without."""
    spread = s.subject_spread()
    if spread is None:
        return ""
    mean, sd, low, _ = (100 * x for x in spread)
    return f"{mean:.1f} ± {'n/a' if math.isnan(sd) else f'{sd:.1f}'} ({low:.1f})"


def _row(results: CompareResults, m: MethodResult, s: Scores, width: int, person: bool) -> str:
    acc = f"{100 * s.accuracy:5.1f} [{100 * s.accuracy_ci[0]:4.1f}, {100 * s.accuracy_ci[1]:5.1f}]"
    f1 = f"{100 * s.macro_f1:5.1f} [{100 * s.macro_f1_ci[0]:4.1f}, {100 * s.macro_f1_ci[1]:5.1f}]"
    p = s.mcnemar.p if s.mcnemar is not None else float("nan")
    pv = "best" if m.name == results.best else p_value(p)
    mark = " *" if m.name == results.best_interpretable else ""
    spread = f" {_person(s):>{len(PERSON)}}" if person else ""
    return f"{m.name + mark:<{width}} {acc:<22} {f1:<22}{spread} {pv:>9}"


def _legend(results: CompareResults, person: bool) -> list[str]:
    """What the per-person column holds (or why there is none), and what macro-F1's interval
    resampled (``cv.bootstrap_over``)."""
    if person:
        n = len(results.dataset.subjects)
        what = f"person: the accuracy on each of the {n} subjects held out: mean ± sample sd (min)"
    elif results.cv.scheme == "loso":
        what = "no accuracy per person: this results file was written before it was given"
    else:  # k-fold, or folds given: a fold holds any person's clips
        what = f"no accuracy per person: {results.cv.scheme} folds are not people held out"
    drawn = (
        "subjects, then each one's clips" if results.cv.bootstrap_over == "subjects" else "clips"
    )
    return [what, f"macro-F1's 95 % interval: bootstrap over {drawn}"]


def _people(results: CompareResults, width: int) -> list[str]:
    """Under leave-one-subject-out, the figures whose unit is the person: the accuracy's
    bootstrap interval over the subjects and their clips and Wilcoxon's test of their
    accuracies against the best (n: the subjects whose accuracies differ); none without."""
    ok = [(m, s) for m, s in results.scored() if s.accuracy_ci_people is not None]
    if not ok:
        return []
    head = f"{'method':<{width}} {'accuracy % [95 % CI over people]':<33} {'Wilcoxon p (n)':>14}"
    lines = ["", head, "-" * len(head)]
    for m, s in ok:
        lo, hi = s.accuracy_ci_people or (math.nan, math.nan)
        acc = f"{100 * s.accuracy:5.1f} [{100 * lo:4.1f}, {100 * hi:5.1f}]"
        w = s.wilcoxon
        pv = "best" if m.name == results.best else "" if w is None else f"{p_value(w.p)} ({w.n})"
        lines.append(f"{m.name:<{width}} {acc:<33} {pv:>14}".rstrip())
    n = len(ok[0][1].per_subject)
    return lines + [
        f"people as the unit: the accuracy's 95 % bootstrap over the {n} subjects held out and"
        " their clips;",
        "Wilcoxon's signed-rank test of their accuracies against the best (n: the subjects",
        "whose accuracies differ; n subjects cannot give p below 2/2^n, 0.25 for 3, 0.0625 for 5)",
    ]


def _costs(results: CompareResults, width: int) -> list[str]:
    """Training and prediction time and case-base size of every method that ran."""
    head = f"{'method':<{width}} {'fit s':>9} {'ms/clip':>9} {'cases':>7}"
    lines = ["", head, "-" * len(head)]
    for m, s in results.scored():
        cases = "" if s.case_base_size is None else f"{s.case_base_size:.0f}"
        lines.append(
            f"{m.name:<{width}} {s.fit_s:9.2f} {s.predict_ms_per_clip:9.2f} {cases:>7}".rstrip()
        )
    return lines


def format_table(results: CompareResults) -> str:
    """The comparison as a plain-text table in method order (``*``: best interpretable; the
    accuracy per person under leave-one-subject-out), what it holds, the figures whose unit
    is the person (leave-one-subject-out), the costs (time, case base) of each method, then
    the accuracy per model group when there are groups."""
    # the method column holds the longest name with its " *" ("cbr fluents/euclidean *": 23)
    width = max([22, *(len(m.name) + 2 for m in results.methods)])
    person = any(s.per_subject for _, s in results.scored())
    spread = f" {PERSON}" if person else ""
    head = (
        f"{'method':<{width}} {'accuracy % [95 % CI]':<22} {'macro-F1 % [95 % CI]':<22}"
        f"{spread} {'McNemar p':>9}"
    )
    lines = [head, "-" * len(head)]
    for m in results.methods:
        if m.scores is None:
            lines.append(f"{m.name:<{width}} {m.status}: {m.message}")
        else:
            lines.append(_row(results, m, m.scores, width, person))
    lines += _legend(results, person) + _people(results, width)
    if results.scored():
        lines += _costs(results, width)
    return "\n".join(lines + group_table(results))


def group_table(results: CompareResults) -> list[str]:
    """Accuracy (%) of every method per model group (e.g. per movement), when there are
    groups: which activities the target is hard to tell in."""
    ok = [(m, s) for m, s in results.scored() if s.per_group]
    if not ok:
        return []
    groups = list(ok[0][1].per_group)
    within = shown(results.settings.get("within") or "group")
    # the groups are the data's values (labels): escaped, they cannot drive the terminal
    names = {g: shown(g) for g in groups}
    width = max(len(within), *(len(n) for n in names.values())) + 2
    cols = [max(len(m.name), len("100.0")) + 2 for m, _ in ok]
    head = "".join(f"{m.name:>{w}}" for (m, _), w in zip(ok, cols, strict=True))
    lines = ["", f"accuracy % per {within} (one model each):", f"{within:<{width}}{head}"]
    for g in groups:
        row = "".join(
            f"{100 * s.per_group[g].value:>{w}.1f}" for (_, s), w in zip(ok, cols, strict=True)
        )
        lines.append(f"{names[g]:<{width}}{row}")
    return lines


def _figures(s: Scores, classes: list[str]) -> dict[str, Any]:
    row: dict[str, Any] = {
        "accuracy": round(s.accuracy, 6),
        "accuracy_lo": round(s.accuracy_ci[0], 6),
        "accuracy_hi": round(s.accuracy_ci[1], 6),
        "macro_f1": round(s.macro_f1, 6),
        "macro_f1_lo": round(s.macro_f1_ci[0], 6),
        "macro_f1_hi": round(s.macro_f1_ci[1], 6),
        "fit_s": round(s.fit_s, 4),
        "predict_s": round(s.predict_s, 4),
        "case_base_size": s.case_base_size,
        "mcnemar_p": None if s.mcnemar is None else s.mcnemar.p,
        "mcnemar_vs": None if s.mcnemar is None else s.mcnemar.versus,
    }
    people = s.accuracy_ci_people
    row["accuracy_people_lo"] = None if people is None else round(people[0], 6)
    row["accuracy_people_hi"] = None if people is None else round(people[1], 6)
    row["wilcoxon_p"] = None if s.wilcoxon is None else s.wilcoxon.p
    row["wilcoxon_n"] = None if s.wilcoxon is None else s.wilcoxon.n
    spread = s.subject_spread()
    for key, v in zip(("mean", "sd", "min", "max"), spread or (None,) * 4, strict=True):
        # NaN (one subject's sd) as an empty cell, as a figure of a row that did not run
        row[f"person_{key}"] = None if v is None or math.isnan(v) else round(v, 6)
    row.update({f"recall:{c}": round(s.per_class[c].value, 6) for c in classes})
    # the accuracy per model group the table prints under it (per movement with --target)
    row.update({f"accuracy:{g}": round(r.value, 6) for g, r in s.per_group.items()})
    # and per subject held out (leave-one-subject-out only)
    row.update({f"subject:{p}": round(r.value, 6) for p, r in s.per_subject.items()})
    return row


def csv_rows(results: CompareResults) -> list[dict[str, Any]]:
    """One row per method: the table's figures (``mcnemar_vs``: the best method, tested
    against; ``accuracy_people_lo``, ``accuracy_people_hi``: the accuracy's bootstrap
    interval over the subjects held out and their clips, ``wilcoxon_p``, ``wilcoxon_n``:
    Wilcoxon's test over them against the best; ``person_mean``, ``person_sd``, ``person_min``,
    ``person_max``: the accuracy over the subjects held out; all empty under k-fold),
    per-class recall (``recall:CLASS``), with model groups the accuracy per group printed
    under the table (``accuracy:GROUP``), the accuracy per subject held out
    (``subject:SUBJECT``); ``message`` for one that did not run."""
    rows = []
    for m in results.methods:
        row: dict[str, Any] = {
            "method": m.name,
            "kind": m.kind,
            "interpretable": m.interpretable,
            "status": m.status,
        }
        if m.scores is not None:
            row.update(_figures(m.scores, results.dataset.classes))
        else:
            row["message"] = m.message
        rows.append(row)
    return rows


def write_csv(rows: list[dict[str, Any]], path: str | Path) -> Path:
    """CSV rows to ``path`` atomically (columns: union of the rows' keys, first seen first)."""
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=cols)
    writer.writeheader()
    writer.writerows(rows)
    return write_text_atomic(path, buf.getvalue())
