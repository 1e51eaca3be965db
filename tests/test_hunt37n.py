"""Case-base maintenance after training, data safety (hunt 37n): ``train --replace`` drops
the case base as it was read when the training started, never one another process changed,
replaced or created while it trained."""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from casebase_store import open_store
from cbr.estimator import CaseBaseClassifier
from cbr.training import append
from features.poses import load_pose
from posecbr.cli import main
from tests.once import made_once
from tests.postgres import empty_postgres

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
AGAIN = "nothing was written (run the command again to replace it as it is now)"


def _dump(db: str) -> list[list[tuple[Any, ...]]]:
    """Every row of every posecbr table, in order (SQLite)."""
    con = sqlite3.connect(db)
    try:
        tables = ("case_bases", "cases", "maintenance_log", "case_representations")
        return [list(con.execute(f"SELECT * FROM {t} ORDER BY 1")) for t in tables]
    finally:
        con.close()


def _state(db: str, name: str) -> tuple[str, int, list[int], list[str]]:
    """Case base ``name``: its identity, version, active case ids and their sources."""
    store = open_store(db, readonly=True)
    try:
        info, cases = store.load_case_base(name)
    finally:
        store.close()
    return info.uid, info.version, [int(i) for i in cases.ids], list(cases.sources)


def _meanwhile(monkeypatch: pytest.MonkeyPatch, action: Callable[[], None]) -> None:
    """Run ``action`` (another process's write) once, right after the training's fit: after
    the command read the store, before it stores what it learned."""
    fit = CaseBaseClassifier.fit_described
    calls: list[int] = []

    def fitted(self: CaseBaseClassifier, clips: Any, y: Any) -> CaseBaseClassifier:
        out = fit(self, clips, y)
        if not calls:
            calls.append(1)
            action()
        return out

    monkeypatch.setattr(CaseBaseClassifier, "fit_described", fitted)


def _append_s02(db: str) -> None:
    """Two clips of subject s02 appended to case base ``default`` (as ``train --append``)."""
    clips = [load_pose(DEMO / f) for f in ("m01_s02_e01.npz", "m02_s02_e01.npz")]
    append(db, "default", clips, ["deep_squat", "hurdle_step"])


def _train(db: str, subject: str, *more: str) -> int:
    return main(["train", str(LABELS), "--db", db, "--subjects", subject, *more])


def _refused_replace(db: str, capsys: pytest.CaptureFixture[str], *more: str) -> str:
    """``train --replace`` (subject s03) exits 1 with one line on stderr; returns it."""
    capsys.readouterr()
    assert _train(db, "s03", "--replace", *more) == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err
    return lines[0]


@pytest.fixture
def trained(tmp_path: Path, tmp_path_factory: pytest.TempPathFactory) -> str:
    """A case base of subject s01 trained by the command, made once in the session: each
    test gets its own copy of the file (they change it)."""

    def make(folder: Path) -> Path:
        made = folder / "cb.sqlite"
        assert _train(str(made), "s01") == 0
        assert sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]  # one file to copy
        return made

    db = tmp_path / "cb.sqlite"
    shutil.copyfile(made_once(tmp_path_factory, "hunt37n-s01", make), db)
    return str(db)


def test_replace_keeps_cases_another_process_appended_while_it_trained(
    trained: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: the cases appended while ``train --replace`` fitted (version 1 -> 2) were
    dropped with the case base it replaced, silently; now the replace is refused and they
    stay."""
    uid, version, ids, _ = _state(trained, "default")
    assert version == 1 and len(ids) == 60  # s01: 60 clips
    _meanwhile(monkeypatch, lambda: _append_s02(trained))
    line = _refused_replace(trained, capsys)
    assert line.startswith("posecbr train: error: ")
    assert "cb.sqlite" in line
    assert line.endswith(
        "case base 'default' was changed by another process since it was read (version 1, "
        f"now 2); {AGAIN}"
    )
    uid2, version2, ids2, sources = _state(trained, "default")
    assert (uid2, version2) == (uid, 2)
    assert ids2[:60] == ids and len(ids2) == 62  # the two appended cases are there
    assert [Path(s).name for s in sources[60:]] == ["m01_s02_e01.npz", "m02_s02_e01.npz"]


def test_two_replaces_at_once_one_wins_the_other_is_refused(
    trained: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: both replaced, the second one's case base over the first one's; now the one
    that stores second is refused and the first one's case base (s02) is left exactly."""
    after: list[list[tuple[Any, ...]]] = []

    def other() -> None:
        assert _train(trained, "s02", "--replace") == 0
        after.append(_dump(trained))

    _meanwhile(monkeypatch, other)
    line = _refused_replace(trained, capsys)
    assert line.endswith(f"case base 'default' was replaced by another process since it was "
                         f"read; {AGAIN}")  # fmt: skip
    assert _dump(trained) == after[0]
    sources = _state(trained, "default")[3]
    assert len(sources) == 60 and all("_s02_" in s for s in sources)


def test_replace_of_a_name_absent_at_the_start_keeps_one_created_meanwhile(
    trained: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    after: list[list[tuple[Any, ...]]] = []

    def other() -> None:
        assert _train(trained, "s02", "--name", "other") == 0
        after.append(_dump(trained))

    _meanwhile(monkeypatch, other)
    line = _refused_replace(trained, capsys, "--name", "other")
    assert line.endswith(f"case base 'other' was created by another process since this command "
                         f"started; {AGAIN}")  # fmt: skip
    assert _dump(trained) == after[0]


def test_replace_unchanged_meanwhile_still_replaces(
    trained: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base only read meanwhile (a trim's dry run writes nothing) is replaced, as
    before; so is a name absent before and after."""
    uid = _state(trained, "default")[0]
    _meanwhile(monkeypatch, lambda: None)
    assert _train(trained, "s03", "--replace") == 0
    new_uid, version, ids, sources = _state(trained, "default")
    assert new_uid != uid and version == 1 and len(ids) == 60
    assert all("_s03_" in s for s in sources)
    assert _train(trained, "s03", "--replace", "--name", "fresh") == 0
    assert len(_state(trained, "fresh")[2]) == 60


def test_replace_on_postgresql_keeps_what_was_appended_meanwhile(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    url = empty_postgres()
    assert _train(url, "s01") == 0
    uid, _, ids, _ = _state(url, "default")
    _meanwhile(monkeypatch, lambda: _append_s02(url))
    line = _refused_replace(url, capsys)
    assert line.endswith(
        "case base 'default' was changed by another process since it was read (version 1, "
        f"now 2); {AGAIN}"
    )
    uid2, version2, ids2, _ = _state(url, "default")
    assert (uid2, version2) == (uid, 2) and ids2[:60] == ids and len(ids2) == 62


_PAUSED_IN_MATRICES = """
import sys, time
import cbr.stored as stored
def paused(*a, **kw):
    print("PAUSED", flush=True)
    time.sleep(120)
stored.write_matrices = paused
from posecbr.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _stopped_when_paused(script: str, argv: list[str], sig: signal.Signals) -> tuple[int, str]:
    """``posecbr argv`` run by ``script`` (which prints PAUSED where it holds the command),
    sent ``sig`` there: its exit status and stderr."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "POSECBR_NO_PROGRESS": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-c", script, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    return proc.returncode, err


@pytest.mark.parametrize(
    ("sig", "status", "said"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated (SIGTERM)")],
)
def test_a_trim_interrupted_after_it_committed_says_it_is_stored(
    trained: str, sig: signal.Signals, status: int, said: str
) -> None:
    """Before: Ctrl-C while the committed trim wrote its matrices (a large case base's)
    said "posecbr casebase trim: interrupted" alone, read as a trim not made: run again, it
    trimmed a second time. Now the line says the trim is stored, and how far."""
    argv = ["casebase", "trim", "--db", trained, "--editor", "novelty-benefit", "--keep", "0.5"]
    returncode, err = _stopped_when_paused(_PAUSED_IN_MATRICES, argv, sig)
    assert returncode == status
    # 10 activities of 6 clips each, half of each kept
    assert err.strip() == (
        f"posecbr casebase trim: {said}: the trim was stored before it (60 -> 30 cases: "
        "casebase info shows it); run again, it would trim the case base again"
    )
    store = open_store(trained, readonly=True)
    try:
        assert store.count_cases("default") == 30
        assert [e.action for e in store.maintenance_log("default")].count("trim") == 31
    finally:
        store.close()


_PAUSED_IN_TRAINING_MATRICES = _PAUSED_IN_MATRICES.replace(
    "import cbr.stored as stored", "import cbr.training as stored"
)


@pytest.mark.parametrize(
    ("more", "sig", "said"),
    [
        (
            ["--subjects", "s02", "--labels", "deep_squat", "--append"],
            signal.SIGINT,
            "interrupted: the 6 cases were added to 'default' before it",
        ),
        (
            ["--subjects", "s02", "--name", "other"],
            signal.SIGTERM,
            "terminated (SIGTERM): case base 'other' was stored before it (60 cases)",
        ),
    ],
    ids=["append", "build"],
)
def test_a_train_stopped_after_it_committed_says_what_is_stored(
    trained: str, more: list[str], sig: signal.Signals, said: str
) -> None:
    """Before: "posecbr train: interrupted" alone, after the cases were stored."""
    argv = ["train", str(LABELS), "--db", trained, *more]
    returncode, err = _stopped_when_paused(_PAUSED_IN_TRAINING_MATRICES, argv, sig)
    assert returncode == (130 if sig == signal.SIGINT else 143)
    assert err.strip().splitlines()[-1] == f"posecbr train: {said}"
    name = "other" if "other" in more else "default"
    assert len(_state(trained, name)[2]) == (60 if name == "other" else 66)
