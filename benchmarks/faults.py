"""Fault injection: ``kill -9`` at random moments of ``train``, ``classify --feedback``,
``casebase trim`` and ``convert``; after every kill the store (or the output folder) must be in
a state the command passes through between transactions: before it, after it, or (feedback,
one transaction per clip) after some whole number of clips. Never between.

    python -m benchmarks.faults                  # 50 kills per command
    python -m benchmarks.faults --runs 10 --commands train,trim

A state is compared by its fingerprint: every case base (name, configuration, model), case
(id, label, features, provenance, active) and maintenance-log entry (action, case, reason),
without what differs between two identical runs (identities, timestamps). Each kill also gets
SQLite's ``PRAGMA integrity_check`` after the next writer has rolled the journal back. Half the
kill moments are uniform over the command's uninterrupted run time (measured first), so kills
land in start-up, feature computation and the write alike; the other half are aimed at one of
the writes the uninterrupted run was seen making (a rollback journal, or a hidden file being
built), chosen at random: once that write shows (the n-th time a write begins), uniformly
within as long as it lasted. A command writing in several short transactions (feedback: one a
clip, 5-70 ms each, seconds apart) is hit inside them, not in the gaps between, which aiming at
the span from the first write to the last did. The table says how many kills landed while a
write was under way. After a kill that left hidden temporaries the same command is run again:
the next writer of an output removes those of dead writers (features.fileio).
Results: benchmarks/results/faults.json.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import random
import shutil
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks import json_out, write_json

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "faults.json"


def _demo() -> Path:
    """The bundled UI-PRMD subset (a labels CSV and its pose files)."""
    demo = ROOT / "posecbr" / "demo_data" / "uiprmd"
    if not (demo / "labels.csv").is_file():
        raise SystemExit("the bundled demo data is missing")
    return demo


def store_fingerprint(db: Path) -> str:
    """What a case base file holds, without identities and timestamps (SQLite, read-only)."""
    if not db.exists():
        return "no file"
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if "case_bases" not in tables:
            return "no case base"
        h = hashlib.sha256()
        for row in con.execute(
            "SELECT name, feature_config, feature_names, similarity_config, model, version "
            "FROM case_bases ORDER BY name"
        ):
            h.update(repr(row).encode())
        for row in con.execute(
            "SELECT c.id, b.name, c.label, c.features, c.source, c.frame_start, c.frame_end, "
            "c.subject, c.origin, c.active FROM cases c JOIN case_bases b "
            "ON c.case_base_id = b.id ORDER BY c.id"
        ):
            h.update(repr(row).encode())
        for row in con.execute(
            "SELECT action, case_id, novelty, benefit, reason FROM maintenance_log ORDER BY id"
        ):
            h.update(repr(row).encode())
        return h.hexdigest()
    finally:
        con.close()


def folder_fingerprint(folder: Path) -> dict[str, str]:
    """Every visible file of ``folder`` and its hash (hidden temporary files left by a killed
    writer are counted separately: they never stand in for an output)."""
    if not folder.exists():
        return {}
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.iterdir())
        if p.is_file() and not p.name.startswith(".")
    }


def _posecbr(argv: list[str]) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "posecbr", *argv],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
    )


def _run(argv: list[str]) -> None:
    proc = _posecbr(argv)
    if proc.wait(timeout=600) != 0:
        raise SystemExit(f"posecbr {' '.join(argv)} failed")


def _integrity(db: Path) -> bool:
    """Open as a writer (which rolls a hot journal back), then SQLite's own check."""
    if not db.exists():
        return True
    from casebase_store import StoreError, open_store

    try:
        open_store(db, create=False).close()
    except StoreError:
        pass  # an empty store (a kill before the first commit) has no schema yet
    con = sqlite3.connect(db)
    try:
        return con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    finally:
        con.close()


@dataclass
class Scenario:
    """One command under fire: ``prepare(work)`` makes a fresh working copy in folder
    ``work`` and returns the argv; ``states(work)`` the fingerprint of what is there."""

    name: str
    prepare: Callable[[Path], list[str]]
    state: Callable[[Path], Any]


def _scenarios(template: Path, demo: Path) -> dict[str, Scenario]:
    labels = demo / "labels.csv"
    clips = [str(p) for p in sorted(demo.glob("m01_s03_*.npz"))[:4]]

    def fresh_db(work: Path) -> Path:
        db = work / "cb.sqlite"
        shutil.copyfile(template, db)
        return db

    def train(work: Path) -> list[str]:
        db = fresh_db(work)
        return ["train", str(labels), "--db", str(db), "--subjects", "s03", "--name", "second"]

    def feedback(work: Path) -> list[str]:
        db = fresh_db(work)
        return ["classify", *clips, "--db", str(db), "--feedback", "deep_squat",
                "--novelty", "0", "--benefit", "0"]  # fmt: skip

    def trim(work: Path) -> list[str]:
        db = fresh_db(work)
        return ["casebase", "trim", "--db", str(db), "--keep", "0.5"]

    def convert(work: Path) -> list[str]:
        return ["convert", str(labels), "--out", str(work / "out"), "--subjects", "s01"]

    def db_state(work: Path) -> str:
        return store_fingerprint(work / "cb.sqlite")

    def out_state(work: Path) -> tuple[tuple[str, str], ...]:
        return tuple(sorted(folder_fingerprint(work / "out").items()))

    return {
        "train": Scenario("train", train, db_state),
        "feedback": Scenario("feedback", feedback, db_state),
        "trim": Scenario("trim", trim, db_state),
        "convert": Scenario("convert", convert, out_state),
    }


def _writing(work: Path) -> bool:
    """Whether a write is under way in ``work``: a rollback journal, or a hidden file or
    folder (a store file being built, an output being written, a staging folder)."""
    if (work / "cb.sqlite-journal").exists():
        return True
    return any(p.name.startswith(".") for p in work.rglob("*"))


Windows = list[tuple[float, float]]


def _timed_run(argv: list[str], work: Path) -> tuple[float, Windows]:
    """Run to the end; the run time and every stretch (from, to: seconds from the start) in
    which a write was seen, in order."""
    t0 = time.perf_counter()
    proc = _posecbr(argv)
    windows: Windows = []
    while proc.poll() is None:
        if _writing(work):
            t = time.perf_counter() - t0
            if windows and windows[-1][1] < 0:  # still in the open window
                continue
            windows.append((t, -1.0))
        elif windows and windows[-1][1] < 0:
            windows[-1] = (windows[-1][0], time.perf_counter() - t0)
        time.sleep(0.0005)
    if proc.returncode != 0:
        raise SystemExit(f"posecbr {' '.join(argv)} failed")
    elapsed = time.perf_counter() - t0
    return elapsed, [(a, b if b >= 0 else elapsed) for a, b in windows]


def _strike_in_write(
    proc: subprocess.Popen[bytes], work: Path, nth: int, span: float, rng: random.Random
) -> float:
    """The moment to kill: once the ``nth`` write (counted from 0) shows, within ``span``
    seconds (as long as the uninterrupted run's ``nth`` write lasted)."""  # fmt: skip
    onsets, was = -1, False
    while proc.poll() is None:
        now = _writing(work)
        if now and not was:
            onsets += 1
            if onsets == nth:
                break
        was = now
        time.sleep(0.0002)
    return time.perf_counter() + rng.uniform(0.0, span)


def _allowed(sc: Scenario, base: Path) -> tuple[set[Any], float, Windows]:
    """The states a kill may leave, the uninterrupted run time and when it writes. For
    feedback: the state after each whole number of clips (one transaction each); for convert:
    every subset of the complete outputs (each file is written atomically, labels.csv last)."""
    work = Path(tempfile.mkdtemp(dir=base))
    argv = sc.prepare(work)
    allowed = {sc.state(work)}
    elapsed, writes = _timed_run(argv, work)
    allowed.add(sc.state(work))
    if sc.name == "feedback":
        first = argv.index("--db")
        for k in range(1, first - 1):
            w = Path(tempfile.mkdtemp(dir=base))
            a = sc.prepare(w)
            _run([a[0], *a[1 : 1 + k], *a[first:]])
            allowed.add(sc.state(w))
    return allowed, elapsed, writes


def _acceptable(sc: Scenario, state: Any, allowed: set[Any]) -> bool:
    if sc.name != "convert":
        return state in allowed
    full = dict(max(allowed, key=len))
    files = dict(state)
    whole = all(full.get(name) == digest for name, digest in files.items())
    # the index of the outputs is written last: present only when every output is there
    return whole and ("labels.csv" not in files or files == full)


def _hidden(work: Path) -> int:
    """Hidden files and folders under ``work`` (temporaries and staging folders)."""
    return sum(p.name.startswith(".") for p in work.rglob("*"))


def fire(sc: Scenario, runs: int, base: Path, rng: random.Random) -> dict[str, Any]:
    allowed, elapsed, writes = _allowed(sc, base)
    bad: list[str] = []
    in_write = aimed = aimed_in_write = stray = stray_after = 0
    for run in range(runs):
        work = Path(tempfile.mkdtemp(dir=base))
        argv = sc.prepare(work)
        proc = _posecbr(argv)
        if run % 2 == 0 or not writes:  # anywhere in the run
            deadline = time.perf_counter() + rng.uniform(0.0, elapsed)
        else:  # in one of the writes, chosen at random
            aimed += 1
            nth = rng.randrange(len(writes))
            deadline = _strike_in_write(proc, work, nth, writes[nth][1] - writes[nth][0], rng)
        while time.perf_counter() < deadline and proc.poll() is None:
            time.sleep(0.0002)
        writing = _writing(work)
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
        in_write += writing
        aimed_in_write += writing and run % 2 == 1
        if not _integrity(work / "cb.sqlite"):
            bad.append(f"integrity check failed ({work})")
        state = sc.state(work)
        if not _acceptable(sc, state, allowed):
            bad.append(f"state between transactions after a kill ({work})")
        left = _hidden(work)
        stray += left
        if left:  # the next writer of the same output removes what the killed one left
            _run(argv)
            stray_after += _hidden(work)
        if not bad:
            shutil.rmtree(work, ignore_errors=True)
    return {
        "command": sc.name,
        "runs": runs,
        "uninterrupted_s": elapsed,
        "killed_while_writing": in_write,
        "aimed_at_a_write": aimed,
        "aimed_and_landed_in_a_write": aimed_in_write,
        "write_windows_s": writes,
        "violations": bad,
        "hidden_temporaries_left_by_kills": stray,
        "hidden_temporaries_left_after_the_next_writer": stray_after,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--commands", default="train,feedback,trim,convert")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=json_out, default=RESULTS, help="results JSON")
    args = parser.parse_args(argv)
    demo = _demo()
    rng = random.Random(args.seed)
    rows = []
    with tempfile.TemporaryDirectory(prefix="posecbr-faults-") as tmp:
        base = Path(tmp)
        template = base / "template.sqlite"
        _run(["train", str(demo / "labels.csv"), "--db", str(template), "--subjects", "s01,s02"])
        scenarios = _scenarios(template, demo)
        for name in args.commands.split(","):
            row = fire(scenarios[name.strip()], args.runs, base, rng)
            rows.append({**row, "load": [round(v, 2) for v in os.getloadavg()]})
            _print_row(row)
            _write(rows, args)  # after every command: a long run interrupted keeps its rows
    return 1 if any(r["violations"] for r in rows) else 0


def _print_row(row: dict[str, Any]) -> None:
    print(
        f"{row['command']:<9} {row['runs']:>4} kills  {row['uninterrupted_s']:6.1f} s run  "
        f"{row['killed_while_writing']:>3} while writing ({row['aimed_and_landed_in_a_write']} "
        f"of {row['aimed_at_a_write']} aimed)  {len(row['violations'])} violations  "
        f"hidden temporaries: {row['hidden_temporaries_left_by_kills']} left by kills, "
        f"{row['hidden_temporaries_left_after_the_next_writer']} after the next writer",
        flush=True,
    )
    for v in row["violations"]:
        print(f"    {v}")


def _write(rows: list[dict[str, Any]], args: argparse.Namespace) -> None:
    from benchmarks.__main__ import machine

    doc = {
        "kind": "posecbr-faults",
        "command": f"python -m benchmarks.faults --runs {args.runs} --commands {args.commands}",
        "machine": machine(),
        "load": [round(v, 2) for v in os.getloadavg()],
        "rows": rows,
    }
    write_json(doc, args.out)


if __name__ == "__main__":
    sys.exit(main())
