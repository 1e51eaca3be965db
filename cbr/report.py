"""Pictures of a comparison (matplotlib, Agg) and the self-contained HTML report.

Pictures: confusion matrices, accuracy by configuration with Wilson intervals, case-base
feature prevalence per activity in the initial and trimmed case base (the paper's figure 4),
and fluent timelines. The report inlines every picture as a base64 data URI and loads nothing
else, so one file can be mailed or opened offline.
"""

from __future__ import annotations

import base64
import html
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from features.errors import DataError


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig: Any, path: Path) -> Path:
    """Write ``fig`` to ``path`` atomically (temp file in the same folder, then rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    fig.savefig(tmp, bbox_inches="tight")
    _pyplot().close(fig)
    tmp.replace(path)
    return path


def plot_accuracy(results: dict[str, Any], path: str | Path) -> Path:
    """Horizontal bars: accuracy of every method that ran, with its Wilson 95 % interval;
    interpretable methods blue, peers grey, the best interpretable one outlined."""
    plt = _pyplot()
    ok = [m for m in results["methods"] if m["status"] == "ok"]
    if not ok:
        raise DataError("no method produced results", "results")
    names = [m["name"] for m in ok]
    acc = np.array([m["accuracy"] for m in ok]) * 100
    lo = acc - np.array([m["accuracy_ci"][0] for m in ok]) * 100
    hi = np.array([m["accuracy_ci"][1] for m in ok]) * 100 - acc
    colours = ["#3b6fb6" if m["interpretable"] else "#9a9a9a" for m in ok]
    fig, ax = plt.subplots(figsize=(8, 0.42 * len(ok) + 1.3), dpi=110)
    y = np.arange(len(ok))
    bars = ax.barh(y, acc, xerr=np.vstack([lo, hi]), color=colours, capsize=3)
    for bar, m in zip(bars, ok, strict=True):
        if m["name"] == results.get("best_interpretable"):
            bar.set_edgecolor("black")
            bar.set_linewidth(1.6)
    for yi, a in zip(y, acc, strict=True):  # inside the bar's base, clear of the CI whisker
        ax.text(1.5, yi, f"{a:.1f}", va="center", fontsize=8, color="white", weight="bold")
    ax.set_yticks(y)
    ax.set_yticklabels(names, fontsize=9)
    ax.invert_yaxis()
    ax.set_xlim(0, 108)
    ax.set_xlabel("accuracy (%) with 95 % Wilson interval")
    ax.set_title(
        f"accuracy by configuration ({results['cv']['scheme']}, {results['cv']['n_folds']} folds)",
        fontsize=10,
    )
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_confusion(method: dict[str, Any], classes: Sequence[str], path: str | Path) -> Path:
    """Row-normalised confusion matrix of one method (counts in the cells)."""
    plt = _pyplot()
    cm = np.asarray(method["confusion"], dtype=float)
    rows = cm.sum(axis=1, keepdims=True)
    norm = np.divide(cm, rows, out=np.zeros_like(cm), where=rows > 0)
    n = len(classes)
    size = max(4.0, 0.5 * n + 2.5)
    fig, ax = plt.subplots(figsize=(size + 1.0, size), dpi=110)
    im = ax.imshow(norm, cmap="Blues", vmin=0, vmax=1)
    for i in range(n):
        for j in range(n):
            if cm[i, j]:
                ax.text(
                    j,
                    i,
                    f"{int(cm[i, j])}",
                    ha="center",
                    va="center",
                    fontsize=7,
                    color="white" if norm[i, j] > 0.5 else "black",
                )
    short = [_short(c, 26) for c in classes]
    ax.set_xticks(range(n))
    ax.set_xticklabels(short, rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(n))
    ax.set_yticklabels(short, fontsize=7)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(f"{method['name']}: accuracy {100 * method['accuracy']:.1f} %", fontsize=10)
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="share of the true class")
    fig.tight_layout()
    return _save(fig, Path(path))


def plot_prevalence(prev: dict[str, Any], path: str | Path) -> Path:
    """Feature prevalence per activity, initial and trimmed case base side by side (heatmaps
    ``(features, activities)``, shared colour scale)."""
    plt = _pyplot()
    acts = prev["activities"]
    feats = prev["features"]
    init = np.asarray(prev["initial"], dtype=float).T
    trim = np.asarray(prev["trimmed"], dtype=float).T
    height = max(3.5, 0.2 * len(feats) + 2.2)
    width = max(9.0, 0.9 * len(acts) + 6.0)
    fig, axes = plt.subplots(1, 2, figsize=(width, height), dpi=110, sharey=True)
    short = [_short(a, 24) for a in acts]
    im = None
    for ax, mat, title, counts in (
        (axes[0], init, "initial case base", prev["cases_initial"]),
        (axes[1], trim, f"trimmed (keep {100 * prev['trim']:.0f} %)", prev["cases_trimmed"]),
    ):
        im = ax.imshow(np.nan_to_num(mat), aspect="auto", cmap="viridis", vmin=0, vmax=1)
        ax.set_xticks(range(len(acts)))
        ax.set_xticklabels(
            [f"{s} ({c})" for s, c in zip(short, counts, strict=True)],
            rotation=60,
            ha="right",
            fontsize=7,
        )
        ax.set_title(title, fontsize=10)
    axes[0].set_yticks(range(len(feats)))
    axes[0].set_yticklabels(feats, fontsize=7)
    fig.suptitle(
        f"feature prevalence per activity ({prev['method']}; cases in brackets)", fontsize=10
    )
    fig.colorbar(im, ax=axes, fraction=0.025, pad=0.02, label="prevalence")
    return _save(fig, Path(path))


def _short(name: str, n: int) -> str:
    """``name`` cut to ``n`` characters keeping both ends (class names often differ at the end:
    "standing_shoulder_abduction" vs "standing_shoulder_extension")."""
    if len(name) <= n:
        return name
    head = (n - 1) // 3
    return name[:head] + "…" + name[-(n - 1 - head) :]


def _safe_name(s: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in s)[:60]


def make_pictures(results: dict[str, Any], out_dir: str | Path) -> dict[str, Any]:
    """The pictures that need only the results (accuracy, confusion matrices), written to
    ``out_dir``; returns their file names relative to it."""
    out = Path(out_dir)
    pics: dict[str, Any] = {}
    if not any(m["status"] == "ok" for m in results["methods"]):
        return pics
    pics["accuracy"] = plot_accuracy(results, out / "accuracy.png").name
    chosen: list[str] = []
    cbr = [m for m in results["methods"] if m["status"] == "ok" and m["kind"] == "cbr"]
    if cbr:  # the best case-base configuration, whatever beats it
        chosen.append(max(cbr, key=lambda m: (m["accuracy"], m["macro_f1"]))["name"])
    for key in ("best_interpretable", "best"):
        if results.get(key) and results[key] not in chosen:
            chosen.append(results[key])
    for m in results["methods"]:  # and DAD and the best peer, for the contrast
        if m["status"] == "ok" and m["kind"] == "dad" and m["name"] not in chosen:
            chosen.append(m["name"])
    peers = [m for m in results["methods"] if m["status"] == "ok" and m["kind"] == "peer"]
    if peers:
        bp = max(peers, key=lambda m: m["accuracy"])["name"]
        if bp not in chosen:
            chosen.append(bp)
    pics["confusion"] = []
    for name in chosen:
        m = next(x for x in results["methods"] if x["name"] == name)
        dest = out / f"confusion_{_safe_name(name)}.png"
        p = plot_confusion(m, results["dataset"]["classes"], dest)
        pics["confusion"].append({"method": name, "file": p.name})
    return pics


# ---------------------------------------------------------------------------- HTML

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


def _img(path: Path, alt: str) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'


def _pct(x: float) -> str:
    return "" if x is None or not np.isfinite(x) else f"{100 * x:.1f}"


def _p_value(p: float) -> str:
    # Exact binomial tails underflow to 0 for large samples: say how small, not "0".
    return "< 1e-300" if p < 1e-300 else f"{p:.3g}"


def _table(results: dict[str, Any]) -> str:
    e = html.escape
    rows = [
        "<table id='results'><thead><tr><th class='l'>method</th><th>accuracy %</th>"
        "<th>95 % CI</th><th>macro-F1 %</th><th>95 % CI</th><th>fit s</th>"
        "<th>ms / clip</th><th>case base</th><th>McNemar p vs best</th></tr></thead><tbody>"
    ]
    for m in results["methods"]:
        if m["status"] != "ok":
            rows.append(
                f"<tr><td class='l'>{e(m['name'])}</td><td class='l' colspan='8'>"
                f"{e(m['status'])}: {e(m['message'])}</td></tr>"
            )
            continue
        cls = " class='best'" if m["name"] == results.get("best_interpretable") else ""
        cb = "" if m.get("case_base_size") is None else f"{m['case_base_size']:.0f}"
        p = "best" if m["name"] == results.get("best") else _p_value(m["mcnemar_p"])
        tag = "" if m["interpretable"] else " <span class='small'>(peer)</span>"
        rows.append(
            f"<tr{cls}><td class='l'>{e(m['name'])}{tag}</td><td>{_pct(m['accuracy'])}</td>"
            f"<td>{_pct(m['accuracy_ci'][0])}–{_pct(m['accuracy_ci'][1])}</td>"
            f"<td>{_pct(m['macro_f1'])}</td>"
            f"<td>{_pct(m['macro_f1_ci'][0])}–{_pct(m['macro_f1_ci'][1])}</td>"
            f"<td>{m['fit_s']:.2f}</td><td>{m['predict_ms_per_clip']:.2f}</td><td>{cb}</td>"
            f"<td>{p}</td></tr>"
        )
    rows.append("</tbody></table>")
    return "<div class='wide'>" + "\n".join(rows) + "</div>"


def _rate_table(
    ok: list[dict[str, Any]], field: str, value: str, keys: list[str], table_id: str, what: str
) -> str:
    """Methods as columns, ``keys`` as rows: ``m[field][key][value]`` in %, its 95 % interval
    as the cell's tooltip."""
    e = html.escape
    head = "".join(f"<th>{e(m['name'])}</th>" for m in ok)
    rows = [
        f"<table id='{table_id}'><thead><tr><th class='l'>{e(what)} (n)</th>{head}</tr></thead>"
        "<tbody>"
    ]
    for key in keys:
        cells = "".join(
            f"<td title='95 % CI {_pct(m[field][key]['ci'][0])}–"
            f"{_pct(m[field][key]['ci'][1])}'>{_pct(m[field][key][value])}</td>"
            for m in ok
        )
        rows.append(f"<tr><td class='l'>{e(key)} ({ok[0][field][key]['n']})</td>{cells}</tr>")
    rows.append("</tbody></table>")
    return "<div class='wide'>" + "\n".join(rows) + "</div>"


def _recall_table(results: dict[str, Any]) -> str:
    ok = [m for m in results["methods"] if m["status"] == "ok"]
    if not ok:
        return ""
    return _rate_table(ok, "per_class", "recall", results["dataset"]["classes"], "recall", "class")


def _group_table(results: dict[str, Any]) -> str:
    """Accuracy per model group (one model per movement, say), when there are groups."""
    ok = [m for m in results["methods"] if m["status"] == "ok" and m.get("per_group")]
    if not ok:
        return ""
    within = str(results["settings"].get("within") or "group")
    table = _rate_table(ok, "per_group", "accuracy", list(ok[0]["per_group"]), "groups", within)
    return f"<h2>Accuracy per {html.escape(within)} (%)</h2>{table}"


def _explanations(results: dict[str, Any]) -> str:
    e = html.escape
    items = results.get("explanations") or []
    if not items:
        return "<p>No misclassified clip to explain (or no case-base configuration ran).</p>"
    out = []
    for x in items:
        text = e(x["text"]).replace("\n", "<br>")
        out.append(
            f"<div class='expl'><b>{e(x['clip'])}</b> (subject {e(str(x['subject']))}): "
            f"true <b>{e(x['true'])}</b>, predicted <b>{e(x['predicted'])}</b> by "
            f"{e(x['method'])}<br>{text}</div>"
        )
    return "\n".join(out)


def render_html(results: dict[str, Any], base_dir: str | Path) -> str:
    """The report page for ``results`` (a compare results dict); pictures named in
    ``results["pictures"]`` are read from ``base_dir`` and inlined."""
    e = html.escape
    base = Path(base_dir)
    ds = results["dataset"]
    st = results["settings"]
    pics = results.get("pictures") or {}
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        # A data: favicon stops the browser from requesting /favicon.ico (a console error).
        "<link rel='icon' href='data:,'>",
        f"<title>posecbr compare: {e(Path(str(ds['source'])).name)}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Activity recognition comparison: {e(Path(str(ds['source'])).name)}</h1>",
        f"<p>{ds['n_clips']} clips, {len(ds['classes'])} classes of <b>{e(st['target'])}</b>"
        + (f" (one model per {e(st['within'])})" if st.get("within") else "")
        + f", {len(ds['subjects'])} subjects; cross-validation <b>{e(results['cv']['scheme'])}"
        f"</b> with {results['cv']['n_folds']} folds. Best: <b>{e(str(results['best']))}</b>; "
        f"best interpretable: <b>{e(str(results['best_interpretable']))}</b> (bold row).</p>",
        f"<p class='small'>Made {e(results['created_utc'])} on "
        f"{e(results['machine']['platform'])}, {results['machine']['cpu_count']} CPUs, Python "
        f"{e(results['machine']['python'])}. Source: {e(str(ds['source']))}.</p>",
    ]
    if results.get("notes"):
        parts.append("<h2>Notes</h2><ul>")
        parts += [f"<li class='note'>{e(n)}</li>" for n in results["notes"]]
        parts.append("</ul>")
    parts += [
        "<h2>Results</h2>",
        "<p class='small'>Accuracy with Wilson 95 % interval; macro-F1 with bootstrap 95 % "
        "interval over clips; fit and predict times summed over folds; case base = cases kept "
        "after trimming (mean over folds); McNemar exact test against the best method on the "
        "same clips.</p>",
        _table(results),
    ]
    if "accuracy" in pics:
        parts.append(
            f"<figure>{_img(base / pics['accuracy'], 'accuracy by configuration')}"
            "<figcaption>Accuracy by configuration (blue: interpretable, grey: peers)."
            "</figcaption></figure>"
        )
    parts += ["<h2>Recall per class (%)</h2>", _recall_table(results)]
    parts.append(_group_table(results))
    if pics.get("confusion"):
        parts.append("<h2>Confusion matrices</h2>")
        for c in pics["confusion"]:
            parts.append(
                f"<figure>{_img(base / c['file'], 'confusion ' + c['method'])}"
                f"<figcaption>{e(c['method'])}</figcaption></figure>"
            )
    if pics.get("prevalence"):
        parts.append("<h2>Case-base feature prevalence per activity</h2>")
        parts.append(
            f"<figure>{_img(base / pics['prevalence'], 'feature prevalence')}"
            "<figcaption>Share of each feature per activity in the initial and the "
            "trimmed case base (paper fig. 4).</figcaption></figure>"
        )
    parts += ["<h2>Explanations of misclassified clips</h2>", _explanations(results)]
    if pics.get("timelines"):
        parts.append("<h2>Fluent timeline of an example clip per activity</h2>")
        for t in pics["timelines"]:
            parts.append(
                f"<figure>{_img(base / t['file'], 'timeline ' + t['activity'])}"
                f"<figcaption>{e(t['activity'])}: {e(t['clip'])}</figcaption>"
                "</figure>"
            )
    parts.append("</body></html>")
    return "\n".join(parts)


def load_results(path: str | Path) -> tuple[dict[str, Any], Path]:
    """A compare results JSON (or a folder holding ``results.json``) and its folder."""
    p = Path(path)
    if p.is_dir():
        p = p / "results.json"
    if not p.exists():
        raise DataError("no such results file (run `posecbr compare DATA --out DIR` first)", p)
    try:
        results = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"not a JSON results file ({exc})", p) from None
    if not isinstance(results, dict) or results.get("kind") != "posecbr-compare":
        raise DataError("not a `posecbr compare` results file", p)
    return results, p.parent


def write_report(results_path: str | Path, out: str | Path) -> Path:
    """Render the report for a results file to ``out`` (atomically). Pictures missing from
    the results (a run without ``--out``) are drawn from the results into a temporary folder."""
    results, base = load_results(results_path)
    pics = dict(results.get("pictures") or {})
    with tempfile.TemporaryDirectory() as tmp:
        missing = "accuracy" not in pics or not (base / pics["accuracy"]).exists()
        if missing:
            drawn = make_pictures(results, tmp)
            # Pictures drawn now live in tmp; the data-dependent ones stay where they were.
            for key in list(pics):
                if key not in drawn and not _all_exist(base, pics[key]):
                    del pics[key]
            results = {**results, "pictures": {**pics, **drawn}}
            page = render_html(_rebase(results, base, Path(tmp), set(drawn)), Path(tmp))
        else:
            page = render_html({**results, "pictures": pics}, base)
    dest = Path(out)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp_path = dest.with_name(f".{dest.name}.{os.getpid()}.tmp")
    tmp_path.write_text(page, encoding="utf-8")
    os.replace(tmp_path, dest)
    return dest


def _all_exist(base: Path, entry: Any) -> bool:
    if isinstance(entry, str):
        return (base / entry).exists()
    if isinstance(entry, list):
        return all((base / x["file"]).exists() for x in entry)
    return False


def _rebase(results: dict[str, Any], base: Path, tmp: Path, drawn: set[str]) -> dict[str, Any]:
    """Pictures not drawn into ``tmp`` referenced by absolute path (so one base works)."""
    pics = dict(results["pictures"])
    for key, entry in pics.items():
        if key in drawn:
            continue
        if isinstance(entry, str):
            pics[key] = str((base / entry).resolve())
        else:
            pics[key] = [{**x, "file": str((base / x["file"]).resolve())} for x in entry]
    return {**results, "pictures": pics}


__all__ = [
    "load_results",
    "make_pictures",
    "plot_accuracy",
    "plot_confusion",
    "plot_prevalence",
    "render_html",
    "write_report",
]
