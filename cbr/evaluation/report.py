"""The self-contained HTML report of a comparison: the results file read and checked, every
value escaped, pictures inlined only from inside the results folder.

The page inlines every picture as a base64 data URI and loads nothing else, so one file can be
mailed or opened offline. Nothing in the results file is trusted: it is read by
:meth:`CompareResults.from_dict` (one line naming the file and the key for a missing key or a
wrong type), every inserted value goes through ``html.escape``, and a picture must be a PNG
file inside the results folder.
"""

from __future__ import annotations

import base64
import html
import json
import sys
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError
from features.fileio import binary_kind, check_output, file_head, path_exists, write_text_atomic
from features.poses import check_not_poses
from features.targets import truth_value
from features.text import size_words

from ..explain import class_noun
from .pictures import Drawing, result_pictures
from .results import CompareResults, MethodResult, Rate, Scores, spread
from .tables import p_value

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:2em auto;max-width:1200px;
color:#222;line-height:1.4;padding:0 1em}
h1{font-size:1.6em}h2{font-size:1.25em;margin-top:1.8em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;font-size:.9em;margin:.5em 0}
th,td{border:1px solid #ccc;padding:.25em .55em;text-align:right}
th{background:#f2f2f2}td.l,th.l{text-align:left}
tr.best td{font-weight:bold;background:#eef5ff}
figure{margin:1em 0}img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{font-size:.85em;color:#555}.note{color:#7a4b00}.small{font-size:.85em;color:#555}
.wide{overflow-x:auto}
.expl{border-left:3px solid #3b6fb6;padding:.3em .8em;margin:.8em 0;background:#fafcff}
"""


def e(value: Any) -> str:
    """Any value as HTML text (quotes escaped too: safe inside attributes)."""
    return html.escape(str(value), quote=True)


def _pct(x: float | None) -> str:
    return "" if x is None or not np.isfinite(x) else e(f"{100 * x:.1f}")


# ---------------------------------------------------------------------------- reading

# A compare's results file holds a few hundred bytes per clip and method: a gigabyte is
# hundreds of thousands of clips. Anything larger is the wrong file, and reading it whole
# would exhaust the memory before json could say so.
MAX_RESULTS_BYTES = 1024**3


def _not_text(path: Path, exc: UnicodeDecodeError) -> str:
    """Why a results file that is no UTF-8 text is refused: what it is when it is one of the
    files a user has beside it (a case base, a pose file, a picture), else where it stops
    being text; never the codec's own words."""
    kind = binary_kind(file_head(path))
    if kind is not None:
        return (
            f"is {kind}, not a results file (report takes a compare --out folder or its"
            " results JSON file)"
        )
    return f"not a JSON results file (not UTF-8 text: {exc.reason} at byte {exc.start})"


def load_results(path: str | Path) -> tuple[CompareResults, Path]:
    """A compare results file (or a folder holding ``results.json``), checked, and its path."""
    p = Path(path)
    if p.is_dir():
        p = p / "results.json"
    if p.is_dir():  # a folder named results.json in the folder given
        raise DataError("is a folder, not a results file", p)
    if path_exists(p) and not p.is_file():  # reading a pipe waits for a writer that may not come
        raise DataError("is a pipe, socket or device, not a results file", p)
    if not p.is_file():
        raise DataError("no such results file (run `posecbr compare DATA --out DIR` first)", p)
    size = p.stat().st_size
    if size > MAX_RESULTS_BYTES:
        raise DataError(
            f"is {size_words(size)}: larger than any compare results file (the limit is"
            f" {size_words(MAX_RESULTS_BYTES)}; the wrong file?)",
            p,
        )
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise DataError(_not_text(p, exc), p) from None
    except json.JSONDecodeError as exc:
        raise DataError(f"not a JSON results file ({exc})", p) from None
    except ValueError:  # a whole number of more digits than Python reads
        raise DataError(
            f"not a results file: it holds a number of more than {sys.get_int_max_str_digits()}"
            " digits",
            p,
        ) from None
    except RecursionError:  # json's decoder recurses once per level of nesting
        raise DataError("not a JSON results file (nested too deeply)", p) from None
    return CompareResults.from_dict(doc, str(p)), p


def picture_files(results: CompareResults, results_file: Path) -> dict[str, Path]:
    """The pictures named in ``results`` that exist, by name; each must resolve (links
    followed) to a PNG file inside the results folder, or it is an error naming it."""
    base = results_file.parent.resolve()
    found: dict[str, Path] = {}
    for name in results.pictures.files():
        path = (base / name).resolve()
        if not path.is_relative_to(base):
            raise DataError(f"picture {name!r} lies outside the results folder", results_file)
        if not path.is_file():
            continue  # drawn again from the results, or left out
        with open(path, "rb") as fh:
            if fh.read(len(PNG_MAGIC)) != PNG_MAGIC:
                raise DataError(f"picture {name!r} is not a PNG image", results_file)
        found[name] = path
    return found


# ---------------------------------------------------------------------------- HTML parts


def _img(images: Mapping[str, Path], name: str | None, alt: str) -> str:
    path = images.get(name or "")
    if path is None:
        return ""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{e(alt)}">'


def _figure(images: Mapping[str, Path], name: str | None, alt: str, caption: str) -> str:
    img = _img(images, name, alt)
    return f"<figure>{img}<figcaption>{e(caption)}</figcaption></figure>" if img else ""


def _person_cell(s: Scores) -> str:
    """The accuracy over the subjects held out: ``mean ± sd`` (min) in %, its max in the
    tooltip."""
    spread = s.subject_spread()
    if spread is None:
        return "<td></td>"
    mean, sd, low, high = spread
    sd_text = _pct(sd) or "n/a"
    return (
        f"<td title='{e(len(s.per_subject))} subjects; max {_pct(high)}'>"
        f"{_pct(mean)} ± {sd_text} ({_pct(low)})</td>"
    )


def _people_cells(results: CompareResults, m: MethodResult, s: Scores) -> str:
    """The accuracy's bootstrap interval over the subjects held out and their clips, and
    Wilcoxon's p-value over them against the best (the subjects whose accuracies differ in
    the tooltip)."""
    ci = s.accuracy_ci_people
    cell = "" if ci is None else f"{_pct(ci[0])}–{_pct(ci[1])}"
    w = s.wilcoxon
    if m.name == results.best:
        test = "<td>best</td>"
    elif w is None:
        test = "<td></td>"
    else:
        test = f"<td title='{e(w.n)} subjects differ; W = {e(f'{w.w:g}')}'>{e(p_value(w.p))}</td>"
    return f"<td>{cell}</td>{test}"


def _method_row(results: CompareResults, m: MethodResult, s: Scores, person: bool) -> str:
    cls = " class='best'" if m.name == results.best_interpretable else ""
    cb = "" if s.case_base_size is None else e(f"{s.case_base_size:.0f}")
    p = "best" if m.name == results.best else p_value(s.mcnemar.p if s.mcnemar else float("nan"))
    tag = "" if m.interpretable else " <span class='small'>(peer)</span>"
    return (
        f"<tr{cls}><td class='l'>{e(m.name)}{tag}</td><td>{_pct(s.accuracy)}</td>"
        f"<td>{_pct(s.accuracy_ci[0])}–{_pct(s.accuracy_ci[1])}</td>"
        f"<td>{_pct(s.macro_f1)}</td>"
        f"<td>{_pct(s.macro_f1_ci[0])}–{_pct(s.macro_f1_ci[1])}</td>"
        f"{_person_cell(s) + _people_cells(results, m, s) if person else ''}"
        f"<td>{e(f'{s.fit_s:.2f}')}</td><td>{e(f'{s.predict_ms_per_clip:.2f}')}</td>"
        f"<td>{cb}</td><td>{e(p)}</td></tr>"
    )


def _has_person(results: CompareResults) -> bool:
    """Whether the results give the accuracy per subject held out."""
    return any(s.per_subject for _, s in results.scored())


def _table(results: CompareResults) -> str:
    person = _has_person(results)
    rows = [
        "<table id='results'><thead><tr><th class='l'>method</th><th>accuracy %</th>"
        "<th>95 % CI</th><th>macro-F1 %</th><th>95 % CI</th>"
        + (
            "<th>per person % ± sd (min)</th><th>95 % CI over people</th>"
            "<th>Wilcoxon p vs best (people)</th>"
            if person
            else ""
        )
        + "<th>fit s</th><th>ms / clip</th><th>case base</th><th>McNemar p vs best</th>"
        "</tr></thead><tbody>"
    ]
    for m in results.methods:
        if m.scores is None:
            rows.append(
                f"<tr><td class='l'>{e(m.name)}</td><td class='l' colspan='{11 if person else 8}'>"
                f"{e(m.status)}: {e(m.message)}</td></tr>"
            )
        else:
            rows.append(_method_row(results, m, m.scores, person))
    rows.append("</tbody></table>")
    return "<div class='wide'>" + "\n".join(rows) + "</div>"


def _rate_table(
    ok: list[tuple[str, dict[str, Rate]]],
    keys: list[str],
    table_id: str,
    what: str,
    extra: str = "",
) -> str:
    """Methods as columns, ``keys`` as rows: each method's rate per key in %, its 95 %
    interval as the cell's tooltip; ``extra``: rows (HTML) after them."""
    head = "".join(f"<th>{e(name)}</th>" for name, _ in ok)
    rows = [
        f"<table id='{e(table_id)}'><thead><tr><th class='l'>{e(what)} (n)</th>{head}</tr>"
        "</thead><tbody>"
    ]
    for key in keys:
        cells = "".join(
            f"<td title='95 % CI {_pct(rates[key].ci[0])}–{_pct(rates[key].ci[1])}'>"
            f"{_pct(rates[key].value)}</td>"
            if key in rates
            else "<td></td>"
            for _, rates in ok
        )
        n = next((rates[key].n for _, rates in ok if key in rates), 0)
        rows.append(f"<tr><td class='l'>{e(key)} ({e(n)})</td>{cells}</tr>")
    rows.append(extra + "</tbody></table>")
    return "<div class='wide'>" + "\n".join(rows) + "</div>"


def _recall_table(results: CompareResults) -> str:
    ok = [(m.name, s.per_class) for m, s in results.scored()]
    if not ok:
        return ""
    return _rate_table(ok, results.dataset.classes, "recall", "class")


def _group_table(results: CompareResults) -> str:
    """Accuracy per model group (one model per movement, say), when there are groups."""
    ok = [(m.name, s.per_group) for m, s in results.scored() if s.per_group]
    if not ok:
        return ""
    within = str(results.settings.get("within") or "group")
    table = _rate_table(ok, list(ok[0][1]), "groups", within)
    return f"<h2>Accuracy per {e(within)} (%)</h2>{table}"


def _subject_table(results: CompareResults) -> str:
    """Accuracy per subject held out (leave-one-subject-out), then its mean ± sd and min
    over them; under k-fold, or for a file written before, why there is none."""
    ok = [(m.name, s.per_subject) for m, s in results.scored() if s.per_subject]
    if not ok:
        why = (
            "this results file was written before it was given"
            if results.cv.scheme == "loso"
            else f"{results.cv.scheme} folds are not people held out one by one"
        )
        return f"<p class='small' id='no-person'>No accuracy per person: {e(why)}.</p>"
    keys = sorted({p for _, rates in ok for p in rates})
    spreads = [x for _, rates in ok if (x := spread(rates)) is not None]
    mean_sd = "".join(f"<td>{_pct(x[0])} ± {_pct(x[1]) or 'n/a'}</td>" for x in spreads)
    low_high = "".join(f"<td>{_pct(x[2])}–{_pct(x[3])}</td>" for x in spreads)
    summary = (
        f"<tr class='spread'><td class='l'>mean ± sd</td>{mean_sd}</tr>"
        f"<tr class='spread'><td class='l'>min–max</td>{low_high}</tr>"
    )
    table = _rate_table(ok, keys, "subjects", "subject held out", summary)
    return (
        "<h2>Accuracy per person held out (%)</h2><p class='small'>Each subject's clips"
        " predicted by the models trained without them (its 95 % Wilson interval as the"
        " cell's tooltip); the mean weighs every subject the same, the sd is the sample"
        " standard deviation over the subjects.</p>" + table
    )


def _explanations(results: CompareResults) -> str:
    if not results.explanations:
        return "<p>No misclassified clip to explain (or no case-base configuration ran).</p>"
    return "\n".join(
        f"<div class='expl'><b>{e(x.name)}</b> (subject {e(x.subject)}): "
        f"true <b>{e(x.true)}</b>, predicted <b>{e(x.predicted)}</b> by "
        f"{e(x.method)}<br>{e(x.text).replace(chr(10), '<br>')}</div>"
        for x in results.explanations
    )


def _classes_words(classes: list[str], target: str | None) -> str:
    """What the clips were told apart by, as the report's first line says it (HTML): "3
    activities"; for a two-valued column its values, "correct and incorrect repetitions" or
    "<b>sensor</b>: kinect or vicon" (it said "2 classes of correct"); else "4 classes of
    <b>grade</b>"."""
    k = len(classes)
    if target in (None, "label"):
        return e(f"{k} {class_noun(target, k)}")
    if k == 2:
        truths = {truth_value(c) for c in classes}
        repetitions = target == "correct" or set(classes) == {"correct", "incorrect"}
        if repetitions and truths == {True, False}:  # as label_words says each
            return "correct and incorrect repetitions"
        return f"<b>{e(target)}</b>: {e(classes[0])} or {e(classes[1])}"
    return f"{e(k)} classes of <b>{e(target)}</b>"


def _bootstrap_over(results: CompareResults) -> str:
    """What macro-F1's bootstrap resampled, in words for the table's caption."""
    if results.cv.bootstrap_over == "subjects":
        return "subjects and their clips (subjects drawn, then clips within each)"
    return "clips"


def _head(results: CompareResults) -> list[str]:
    ds, st, cv, machine = results.dataset, results.settings, results.cv, results.machine
    name = e(Path(ds.source).name)
    within = f" (one model per {e(st['within'])})" if st.get("within") else ""
    return [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        # A data: favicon stops the browser from requesting /favicon.ico (a console error).
        "<link rel='icon' href='data:,'>",
        f"<title>posecbr compare: {name}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Activity recognition comparison: {name}</h1>",
        f"<p>{e(ds.n_clips)} clips, {_classes_words(ds.classes, st.get('target'))}"
        f"{within}, {e(len(ds.subjects))} subjects; cross-validation <b>{e(cv.scheme)}</b> with "
        f"{e(cv.n_folds)} folds. Best: <b>{e(results.best)}</b>; best interpretable: "
        f"<b>{e(results.best_interpretable)}</b> (bold row).</p>",
        f"<p class='small'>Made {e(results.created_utc)} on {e(machine['platform'])}, "
        f"{e(machine.get('cpu_count'))} CPUs, Python {e(machine['python'])}. "
        f"Source: {e(ds.source)}.</p>",
    ]


def _notes(results: CompareResults) -> list[str]:
    if not results.notes:
        return []
    return [
        "<h2>Notes</h2><ul>",
        *(f"<li class='note'>{e(n)}</li>" for n in results.notes),
        "</ul>",
    ]


def _figures(results: CompareResults, images: Mapping[str, Path]) -> dict[str, str]:
    """The HTML of every picture group (empty where there is no picture)."""
    pics = results.pictures
    confusion = "".join(
        _figure(images, c.file, f"confusion {c.method}", c.method) for c in pics.confusion
    )
    timelines = "".join(
        _figure(images, t.file, f"timeline {t.activity}", f"{t.activity}: {t.clip}")
        for t in pics.timelines
    )
    prevalence = _figure(
        images,
        pics.prevalence,
        "feature prevalence",
        "Share of each feature per activity in the initial and the trimmed case base "
        "(paper fig. 4).",
    )
    return {
        "accuracy": _figure(
            images,
            pics.accuracy,
            "accuracy by configuration",
            "Accuracy by configuration (blue: interpretable, grey: peers).",
        ),
        "confusion": "<h2>Confusion matrices</h2>" + confusion if confusion else "",
        "prevalence": "<h2>Case-base feature prevalence per activity</h2>" + prevalence
        if prevalence
        else "",
        "timelines": "<h2>Fluent timeline of an example clip per activity</h2>" + timelines
        if timelines
        else "",
    }


def render_html(results: CompareResults, images: Mapping[str, Path]) -> str:
    """The report page for ``results``; ``images`` maps a picture's name in
    ``results.pictures`` to the PNG file to inline (a picture without one is left out)."""
    fig = _figures(results, images)
    parts = _head(results) + _notes(results)
    parts += [
        "<h2>Results</h2>",
        "<p class='small'>Accuracy with Wilson 95 % interval; macro-F1 with bootstrap 95 % "
        f"interval over {_bootstrap_over(results)}; fit and predict times summed over folds; "
        "case base = cases kept after trimming (mean over folds); McNemar exact test against "
        "the best method on the same clips"
        + (
            "; per person = the accuracy on each subject held out: mean ± sample sd (lowest);"
            " with the person as the unit, the accuracy's 95 % interval from a bootstrap over"
            " the subjects and their clips, and Wilcoxon's signed-rank test of their"
            " accuracies against the best (n subjects cannot give p below 2/2^n)"
            if _has_person(results)
            else ""
        )
        + ".</p>",
        _table(results),
        fig["accuracy"],
        "<h2>Recall per class (%)</h2>",
        _recall_table(results),
        _group_table(results),
        _subject_table(results),
        fig["confusion"],
        fig["prevalence"],
        "<h2>Explanations of misclassified clips</h2>",
        _explanations(results),
        fig["timelines"],
        "</body></html>",
    ]
    return "\n".join(p for p in parts if p)


# ---------------------------------------------------------------------------- writing


#: the suffixes of a file an HTML page is written to
PAGE_SUFFIXES = (".html", ".htm")


def check_page_name(out: Path) -> None:
    """Refuse a report named as another kind of file (``--out data/labels.csv``): the page
    replaced the CSV, HTML under a name that says otherwise."""
    if out.suffix.lower() not in PAGE_SUFFIXES:
        raise DataError(
            "the report is an HTML page: name it .html or .htm"
            f" (got {out.suffix or 'no suffix'!r})",
            out,
        )


def write_report(results_path: str | Path, out: str | Path) -> tuple[Path, list[str]]:
    """Render the report for a results file to ``out`` (atomically); returns it and the
    pictures that could not be drawn. The results-only pictures (accuracy, confusion
    matrices) missing from the folder (a ``--json``-only run) are drawn into a temporary
    folder. ``out`` must end in .html or .htm (:func:`check_page_name`)."""
    results, source = load_results(results_path)
    images = picture_files(results, source)
    # The compare run's own files are kept as they are: the results, their pictures and the
    # table compare writes beside them (named as a folder or as its results.json). Any other
    # file there, an earlier report the first, is no input and may be replaced.
    table = source.with_name("results.csv")
    kept = [table] if table.is_file() else []
    dest = check_output(out, inputs=[source, *images.values(), *kept], what="report")
    check_not_poses(dest, "report")
    check_page_name(dest)
    drawing = Drawing()
    named = results.pictures.files()
    with tempfile.TemporaryDirectory() as tmp:
        if results.pictures.accuracy not in images:
            redrawn = {results.pictures.accuracy, *(c.file for c in results.pictures.confusion)}
            named = [name for name in named if name not in redrawn]
            drawn = result_pictures(results, tmp, drawing)
            results.pictures.accuracy = drawn.accuracy
            results.pictures.confusion = drawn.confusion
            images.update({name: Path(tmp) / name for name in drawn.files()})
        # a picture the results name that is not there (moved, deleted): said on the page
        # and by the command, not left out unseen
        lost = _lost_line([name for name in named if name not in images], source)
        results.notes = [*results.notes, *lost]  # this page's, not written back
        page = render_html(results, images)
    write_text_atomic(dest, page)
    return dest, drawing.failures + [f"note: {line}" for line in lost]


def _lost_line(lost: list[str], source: Path) -> list[str]:
    """The line naming the pictures ``source`` names that its folder lacks (none: no line)."""
    if not lost:
        return []
    these = "it" if len(lost) == 1 else "them"
    return [
        f"{', '.join(lost)}: named in {source} but not in its folder (moved or deleted?): the"
        f" report is without {these}"
    ]
