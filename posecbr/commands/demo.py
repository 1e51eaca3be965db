"""``posecbr demo``: the main job on the bundled UI-PRMD subset, end to end, as a user runs it.

describe one clip -> train a case base on two subjects (the configuration the README
recommends: ``posecbr train``'s defaults) -> classify the third subject's clips with
explanations -> compare similarity measures, feature levels and DAD by leave-one-subject-out
cross-validation -> one report. Each step prints the command it runs, so a user can repeat it,
and its output; ``report.html`` holds them all: the commands, what they printed, the fluent
timeline and the comparison.

The data ships inside the package (``posecbr/demo_data/uiprmd``, found with
:mod:`importlib.resources`), so the demo runs wherever posecbr is installed.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import html
import io
import shlex
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TextIO

from features.errors import DataError, PosecbrError
from posecbr.arguments import path_arg

# --quick: one configuration, no DAD or peers, one explanation and no pictures that need the
# clips again (the report draws the accuracy and confusion pictures from the results).
QUICK_COMPARE = ("--similarities", "euclidean", "--features", "fluents", "--no-dad",
                 "--peers", "none", "--explain", "1")  # fmt: skip


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "demo",
        epilog="example: posecbr demo --quick",
        help="describe, train, classify, compare and report on the bundled UI-PRMD subset",
        description="Runs describe -> train -> classify -> compare on the bundled UI-PRMD "
        "subset (3 subjects x 10 movements x 6 repetitions), printing each command so you can "
        "repeat it, and writes one report with all of them.",
    )
    p.add_argument(
        "--data",
        type=path_arg,
        default=None,
        help="folder with the demo's labels.csv (default: the subset bundled with posecbr)",
    )
    p.add_argument(
        "--out",
        type=path_arg,
        default=Path("demo-output"),
        metavar="DIR",
        help="output folder (default demo-output)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="compare one configuration (fluents/euclidean) without DAD, peers or the "
        "per-activity pictures: seconds instead of about a minute",
    )
    p.set_defaults(func=run)


@dataclass
class Step:
    """One step of the demo: its title, the command (argv after ``posecbr``), what it
    printed and how long it took."""

    title: str
    argv: list[str]
    output: str = ""
    seconds: float = 0.0

    @property
    def command(self) -> str:
        return "posecbr " + " ".join(shlex.quote(a) for a in self.argv)


class _Tee(io.TextIOBase):
    """Writes to the terminal and keeps a copy (a step's output for the report)."""

    def __init__(self, out: TextIO) -> None:
        self.out, self.kept = out, io.StringIO()

    def write(self, text: str) -> int:
        self.out.write(text)
        self.kept.write(text)
        return len(text)

    def flush(self) -> None:
        self.out.flush()


def _run_step(step: Step) -> int:
    from posecbr.cli import main

    print(f"\n== {step.title} ==\n$ {step.command}", flush=True)
    tee = _Tee(sys.stdout)
    t = time.perf_counter()
    with contextlib.redirect_stdout(tee):
        code = main(step.argv)
    step.seconds = time.perf_counter() - t
    step.output = tee.kept.getvalue()
    print(f"({step.seconds:.1f} s)", flush=True)
    return code


DEMO_SUBJECTS = ("s01", "s02", "s03")
DEMO_CLIP = "m01_s01_e01.npz"
# What the demo writes in --out (a rerun replaces them), and the file that marks the folder
# as the demo's: only there are they the demo's own to replace.
DEMO_OUTPUTS = ("casebase.sqlite", "casebase.sqlite-wal", "casebase.sqlite-shm", "compare",
                "timeline_deep_squat.png", "report.html")  # fmt: skip
DEMO_MARK = ".posecbr-demo"


def _check_out(out: Path, data: Path) -> None:
    """The output folder: created if needed, never a file, never the demo data, never a
    folder holding a file the demo writes that an earlier demo did not (the demo clears its
    own earlier outputs there); marked as the demo's."""
    if out.exists() and not out.is_dir():
        raise DataError("exists and is not a folder", out)
    if out.resolve() == data.resolve() or data.resolve() in out.resolve().parents:
        raise DataError("is the demo data folder or inside it: choose another --out", out)
    replaced = out / "compare"  # removed with all it holds before the steps run
    if replaced.resolve() == data.resolve() or replaced.resolve() in data.resolve().parents:
        raise DataError(
            f"the demo data is in {replaced}, which the demo replaces with its comparison: "
            "choose another --out",
            data,
        )
    if out.is_dir() and not (out / DEMO_MARK).is_file():
        theirs = [name for name in DEMO_OUTPUTS if (out / name).exists()]
        if theirs:
            raise DataError(
                f"holds {theirs[0]}, not written by the demo, which would replace it: choose"
                " another --out",
                out,
            )
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / DEMO_MARK).touch()
    except OSError as exc:
        raise DataError(f"cannot create: {exc.strerror or exc}", out) from None


def run(args: argparse.Namespace) -> int:
    if args.data is not None:
        return _run(args, args.data)
    with resources.as_file(resources.files("posecbr") / "demo_data" / "uiprmd") as bundled:
        return _run(args, bundled)


def _steps(data: Path, out: Path, quick: bool) -> list[Step]:
    labels = data / "labels.csv"
    db = out / "casebase.sqlite"
    compare = ["compare", str(labels)]
    if quick:
        compare += [*QUICK_COMPARE, "--json", str(out / "compare" / "results.json")]
    else:
        compare += ["--out", str(out / "compare")]
    return [
        Step("1. describe: a deep squat in words",
             ["describe", str(data / DEMO_CLIP), "--plot",
              str(out / "timeline_deep_squat.png")]),
        # the configuration the README recommends is train's default: fluent clip summaries
        # under weighted euclidean, side handling and weights chosen inside the training clips
        Step("2. train: a case base from subjects s01 and s02 (the recommended configuration: "
             "train's defaults)",
             ["train", str(labels), "--db", str(db), "--subjects", "s01,s02"]),
        Step("3. classify: subject s03, unseen in training",
             ["classify", str(labels), "--db", str(db), "--subjects", "s03"]),
        Step("4. compare: leave-one-subject-out cross-validation of the configurations",
             compare),
    ]  # fmt: skip


def _check_data(data: Path) -> None:
    """Refuse, before anything is written, a ``--data`` folder the steps cannot run on: the
    demo describes ``m01_s01_e01.npz``, trains on subjects s01 and s02 and classifies s03."""
    from features.labels_csv import read_labels_csv

    if data.is_file():  # the labels CSV itself, say: "expected labels.csv" puzzled
        folder = f": give its folder, {data.parent}" if data.name == "labels.csv" else ""
        raise PosecbrError(
            f"is a file: --data takes the folder holding the demo's labels.csv{folder}", data
        )
    if not (data / "labels.csv").is_file():
        raise PosecbrError("demo data not found (expected labels.csv)", data)
    rows = read_labels_csv(data / "labels.csv")
    # a row without a subject (no column, an empty cell) names none: not the subject "None"
    subjects = {str(r["subject"]) for r in rows if r.get("subject") not in (None, "")}
    missing = [s for s in DEMO_SUBJECTS if s not in subjects]
    if missing or not (data / DEMO_CLIP).is_file():
        have = f"subjects {', '.join(sorted(subjects)[:6])}" if subjects else "no subjects"
        raise PosecbrError(
            f"the demo trains on subjects s01 and s02, classifies s03 and describes {DEMO_CLIP}"
            f"; this folder's labels.csv has {have}"
            + ("" if (data / DEMO_CLIP).is_file() else f" and no {DEMO_CLIP}"),
            data,
        )


#: what an earlier demo left that a rerun builds anew (a case base is trained only into a new
#: file; a comparison's folder would keep the earlier run's pictures)
REBUILT = ("casebase.sqlite", "casebase.sqlite-wal", "casebase.sqlite-shm", "compare")


def _set_aside(out: Path) -> Path:
    """The earlier demo's case base and comparison moved into a hidden folder in ``out``
    (renamed, not copied), to be put back if this run fails and removed once it succeeds."""
    from features.fileio import staging_folder

    try:
        aside = staging_folder(out, "posecbr-demo-earlier")
        for name in REBUILT:
            if (out / name).exists() or (out / name).is_symlink():
                (out / name).rename(aside / name)
    except OSError as exc:
        raise DataError(f"cannot set the earlier demo's outputs aside: {exc}", out) from None
    return aside


def _put_back(out: Path, aside: Path) -> None:
    """The earlier demo's outputs in place again, over what the failed run made of them."""
    for kept in aside.iterdir():
        made = out / kept.name
        if made.is_dir() and not made.is_symlink():
            shutil.rmtree(made)
        else:
            made.unlink(missing_ok=True)
        kept.rename(made)
    aside.rmdir()


def _run(args: argparse.Namespace, data: Path) -> int:
    _check_data(data)
    out: Path = args.out
    _check_out(out, data)
    db = out / "casebase.sqlite"
    # the earlier outputs stay until this run has made its own (a failed or interrupted run
    # removed them and made none)
    aside = _set_aside(out)
    done = False
    try:
        if args.quick:
            (out / "compare").mkdir()  # compare --json writes into an existing folder only
        steps = _steps(data, out, args.quick)
        for step in steps:
            code = _run_step(step)
            if code:
                return code
        report = out / "report.html"
        results = steps[-1].argv[steps[-1].argv.index("--json" if args.quick else "--out") + 1]
        print("\n== 5. report: every step on one page ==", flush=True)
        _write_report(steps, Path(results), out / "timeline_deep_squat.png", report)
        done = True
    finally:
        if done:
            shutil.rmtree(aside, ignore_errors=True)
        else:
            _put_back(out, aside)
    total = sum(s.seconds for s in steps)
    print(f"\nDone in {total:.0f} s. Case base: {db}\nReport: {report.resolve()}")
    return 0


def _write_report(steps: list[Step], results: Path, timeline: Path, report: Path) -> None:
    """One page: the comparison's report (``posecbr report``) with the steps before it, each
    with its command and output, and the fluent timeline inlined."""
    from features.fileio import check_output, write_text_atomic
    from posecbr.cli import main

    dest = check_output(report, inputs=[results, timeline], what="report")
    with tempfile.TemporaryDirectory() as tmp:
        page_path = Path(tmp) / "compare.html"
        said = io.StringIO()  # its "report written to" names the temporary page: not said
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(said):
            code = main(["report", str(results), "--out", str(page_path)])
        for line in said.getvalue().splitlines():  # its notes (a glyph the font lacks), said
            if not line.startswith("report written to "):
                print(line, file=sys.stderr)
        if code:
            raise PosecbrError("the comparison's report could not be written", results)
        page = page_path.read_text(encoding="utf-8")
    sections = ["<h2>The demo, step by step</h2>",
                "<p>Each command below is what the demo ran; run it yourself to repeat the "
                "step.</p>"]  # fmt: skip
    for step in steps:
        sections += [
            f"<h3>{html.escape(step.title)} ({step.seconds:.1f} s)</h3>",
            f"<pre><code>$ {html.escape(step.command)}</code></pre>",
            f"<pre>{html.escape(step.output.strip())}</pre>",
        ]
        if step.argv[0] == "describe" and timeline.is_file():
            data = base64.b64encode(timeline.read_bytes()).decode("ascii")
            sections.append(
                f"<figure><img src='data:image/png;base64,{data}' alt='fluent timeline'>"
                "<figcaption>The deep squat's fluents over time (describe --plot)"
                "</figcaption></figure>"
            )
    sections.append("<h2>5. The comparison (posecbr compare, posecbr report)</h2>")
    at = page.find("<h2>")
    page = page[:at] + "\n".join(sections) + "\n" + page[at:] if at >= 0 else page
    write_text_atomic(dest, page)
