"""What commands promise about damaged stores, unjudgeable clips, option combinations and
override files: one clear line and a non-zero exit where they cannot do what was asked, words
that are true where they can."""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_cbr_cli import _write_classes

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small real case base (SQLite) trained from synthetic arm movements."""
    base = tmp_path_factory.mktemp("cb")
    data = _write_classes(base / "train", 3, 5)
    db = base / "cb.sqlite"
    code = main(["train", str(data), "--db", str(db), "--mirror", "off",
                 "--feature-weights", "none", "--phases", "0"])  # fmt: skip
    assert code == 0
    return db


def _damaged(case_base: Path, folder: Path, *sql: str) -> Path:
    """A copy of ``case_base`` in ``folder`` with ``sql`` run on it."""
    db = folder / "damaged.sqlite"
    shutil.copy(case_base, db)
    with sqlite3.connect(db) as conn:
        for statement in sql:
            conn.execute(statement)
    conn.close()
    return db


# ----------------------------------------------------------------- dates that are not dates


@pytest.mark.parametrize(
    "action", [["info"], ["list"], ["export", "--out", "x.npz"], ["trim", "--dry-run"]]
)
def test_a_creation_date_that_is_not_one_is_named_damage(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], action: list[str]
) -> None:
    """``created_at = 'garbage'``: a 35-line traceback (ValueError: Invalid isoformat
    string) from every command that reads the case base; now one line naming it."""
    db = _damaged(case_base, tmp_path, "UPDATE case_bases SET created_at = 'garbage'")
    argv = ["casebase", action[0], "--db", str(db), *action[1:]]
    if action[0] == "export":
        argv[-1] = str(tmp_path / "x.npz")
    capsys.readouterr()
    refused(argv, tmp_path, capsys,
            f"{db}: case base 'default' is damaged: its created_at is not a date",
            "'garbage'")  # fmt: skip


def test_a_maintenance_date_that_is_not_one_is_named_damage(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = _damaged(
        case_base,
        tmp_path,
        "INSERT INTO maintenance_log(case_base_id, case_id, action, reason, at) "
        "VALUES (1, NULL, 'zzz', 'x', 'bad-date')",
    )
    capsys.readouterr()
    refused(["casebase", "info", "--db", str(db)], tmp_path, capsys,
            "case base 'default' is damaged: a date in its maintenance log is not a date",
            "'bad-date'")  # fmt: skip


# ----------------------------------------------------------------- export of a damaged base


def test_export_refuses_feature_names_that_do_not_match_the_cases(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One feature name for cases of many columns: export wrote it as it was (exit 0), an
    export whose names do not describe its problems; now refused as trim refuses it."""
    with sqlite3.connect(case_base) as conn:
        (names,) = conn.execute("SELECT feature_names FROM case_bases").fetchone()
    conn.close()
    width = len(json.loads(names))
    assert width > 1
    db = _damaged(case_base, tmp_path, """UPDATE case_bases SET feature_names = '["a"]'""")
    out = tmp_path / "fn.npz"
    capsys.readouterr()
    refused(["casebase", "export", "--db", str(db), "--out", str(out)], tmp_path, capsys,
            f"case base 'default' is damaged: its cases have {width} feature columns but the "
            "case base names 1")  # fmt: skip


def test_export_of_a_sound_case_base_names_every_column(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "ok.npz"
    assert main(["casebase", "export", "--db", str(case_base), "--out", str(out)]) == 0
    capsys.readouterr()
    with np.load(out) as z:
        assert z["problems"].shape[-1] == len(z["feature_names"]) > 1


# ----------------------------------------------------------------- casebase info of QMPs


def test_info_of_a_qmp_case_base_says_its_qmp_columns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """It said "features: qmp, angles states, length 32": "angles" is the group of state
    signals, not a count of states, and QMP features have no length."""
    data = _write_classes(tmp_path / "train", 3, 5)
    db = tmp_path / "qmp.sqlite"
    assert main(["train", str(data), "--db", str(db), "--features", "qmp", "--mirror", "off",
                 "--feature-weights", "none"]) == 0  # fmt: skip
    out = tmp_path / "qmp.npz"
    assert main(["casebase", "export", "--db", str(db), "--out", str(out)]) == 0
    with np.load(out) as z:
        columns = z["problems"].shape[-1]
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    line = capsys.readouterr().out.splitlines()[1]
    assert line.startswith(f"  features: qmp (binary), {columns} QMP columns; hash "), line
    assert "states" not in line and "length" not in line
