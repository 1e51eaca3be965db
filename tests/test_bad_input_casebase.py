"""Bad case base files and bad options of train, classify and casebase: one line naming the file
or option, exit 1, and every file involved unchanged (issue 15)."""

from __future__ import annotations

import hashlib
import json
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from casebase_store import encode_array, open_store
from posecbr.cli import main

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
CLIP = DEMO / "m01_s03_e01.npz"
V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _one_line_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 1, (argv, out, err)
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    command = " ".join(argv[:2]) if argv[0] == "casebase" else argv[0]  # with its action
    assert err.startswith(f"posecbr {command}: error: "), err
    return err


# on one xdist worker: the module's trained made once, not once per worker
pytestmark = pytest.mark.xdist_group("bad_input_casebase")


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    db = tmp_path_factory.mktemp("cb") / "cb.sqlite"
    argv = ["train", str(LABELS), "--db", str(db), "--subjects", "s01",
            "--labels", "deep_squat,standing_shoulder_abduction"]  # fmt: skip
    assert main(argv) == 0
    return db


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


def _tamper(db: Path, sql: str, *params: object) -> None:
    con = sqlite3.connect(db)
    con.execute(sql, params)
    con.commit()
    con.close()


@pytest.mark.parametrize(
    ("sql", "params", "message"),
    [
        (
            "UPDATE cases SET features = ? WHERE id = 3",
            (b"not an array",),
            "features of case 3 is damaged",
        ),  # fmt: skip
        (
            "UPDATE cases SET features = ? WHERE id = 3",
            (encode_array(np.zeros(7)),),
            "features of different shapes",
        ),  # fmt: skip
        (
            "UPDATE cases SET features = ? WHERE id = 3",
            (encode_array(np.array(["a", "b"])),),
            "features of different shapes",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET feature_config = '{level: fluents'",
            (),
            "feature configuration of case base 'default' is not valid JSON",
        ),  # fmt: skip
        ("UPDATE case_bases SET feature_config = '[1, 2]'", (), "is not an object"),
        (
            'UPDATE case_bases SET feature_config = \'{"level": "video"}\'',
            (),
            "unreadable feature configuration",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET feature_config = '{}'",
            (),
            "case base 'default' has a damaged feature configuration (no list of states)",
        ),  # fmt: skip
        (
            'UPDATE case_bases SET similarity_config = \'{"name": "cosine"}\'',
            (),
            "unknown similarity 'cosine'",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET model = 'null'",
            (),
            "model of case base 'default' is not an object",
        ),  # fmt: skip
        ('UPDATE case_bases SET model = \'{"params": {"k": -3}}\'', (), "bad model"),
        (
            'UPDATE case_bases SET feature_names = \'["a", "b"]\'',
            (),
            "feature columns but the case base names 2",
        ),  # fmt: skip
        ("DELETE FROM cases", (), "has no cases"),
        (
            "UPDATE case_bases SET model = json_set(model, '$.confidence.temperature', -1.0)",
            (),
            "damaged confidence calibration (the soft vote needs a positive temperature",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET model = json_set(model, '$.confidence', 'x')",
            (),
            "damaged confidence calibration (TypeError",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET model = json_remove(model, '$.novelty.scale')",
            (),
            "damaged novelty calibration (KeyError: 'scale')",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET model = json_set(model, '$.judges', json(?))",
            (
                json.dumps(
                    {
                        "case_base_version": 1,
                        "calibrated": {
                            "margin": {
                                "threshold": 0.9,
                                "basis": "subject",
                                "known": -5,
                                "novel": 3,
                            }
                        },
                    }
                ),
            ),
            "damaged unknown judge calibration (margin: field 'known' must be a whole number >= 0,"
            " got -5)",
        ),  # fmt: skip
        (
            "UPDATE case_bases SET model = json_set(model, '$.judges', json(?))",
            (json.dumps({"calibrated": {}}),),
            "damaged unknown judge calibration (KeyError: 'case_base_version')",
        ),  # fmt: skip
    ],
)
def test_a_damaged_case_base_is_one_line_and_stays_as_it_is(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    sql: str,
    params: tuple[object, ...],
    message: str,
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    _tamper(db, sql, *params)
    before = _sha(db)
    err = _one_line_error(capsys, ["classify", str(CLIP), "--db", str(db)])
    assert str(db) in err and message in err
    assert _sha(db) == before


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["classify", str(CLIP), "--novelty", "nan", "--feedback", "deep_squat"],
            "--novelty: must be a number >= 0, got nan",
        ),  # fmt: skip
        (
            ["classify", str(CLIP), "--benefit", "-1", "--feedback", "deep_squat"],
            "--benefit: must be in [0, 1], got -1.0",
        ),  # fmt: skip
        (["classify", str(CLIP), "--top", "-1"], "--top: must be >= 1, got -1"),
        (["classify", str(CLIP), "-k", "0"], "-k: must be >= 1, got 0"),
        (["classify", str(CLIP), "--new-label"], "--new-label: goes with --feedback LABEL"),
        # accepted and ignored before
        (["classify", str(CLIP), "--novelty", "0.1"], "--novelty: goes with --feedback LABEL"),
        (["classify", str(CLIP), "--benefit", "0.1"], "--benefit: goes with --feedback LABEL"),
        (["classify", str(CLIP), "--top", "2"], "--top: goes with --verbose"),
        (
            ["casebase", "trim", "--editor", "icf", "--keep", "0.5"],
            "--keep: goes with --editor novelty-benefit",
        ),
        (["casebase", "trim", "-k", "0"], "-k: must be >= 1, got 0"),
        (["casebase", "trim", "--keep", "0"], "--keep: must be in (0, 1]"),
        (["train", str(LABELS), "--name", ""], "the case base name is empty"),
        (
            ["train", str(LABELS), "--name", "x", "--length", "100000000"],
            "--length: must be a whole number of frames from 2 to 4096",
        ),  # fmt: skip
        (
            ["train", str(LABELS), "--append", "--similarity", "dtw"],
            "--append adds cases to the stored model as it is; it does not take --similarity",
        ),  # fmt: skip
        (["train", str(LABELS), "--name", "x", "-k", "0"], "-k: must be a positive integer"),
        (["train", str(LABELS), "--name", "x", "--trim", "1.5"], "--trim: must be in (0, 1]"),
    ],
)
def test_bad_options_are_refused_before_anything_is_written(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    message: str,
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    before = _sha(db)
    err = _one_line_error(capsys, [*argv, "--db", str(db)])
    assert message in err
    assert _sha(db) == before and sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite"]


@pytest.mark.parametrize(
    "argv",
    [["train", str(LABELS)], ["classify", str(CLIP)], ["segment", str(CLIP)],
     ["casebase", "info"]],
)  # fmt: skip
def test_an_empty_db_is_named_as_such(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], monkeypatch: Any
) -> None:
    """``--db ''`` (an unset variable in a script): "--db: is empty", where train said ".: is a
    folder, not a case base file" and the others looked for a file named ''. Nothing made."""
    monkeypatch.chdir(tmp_path)
    err = _one_line_error(capsys, [*argv, "--db", ""])
    assert err.endswith(
        "error: --db: is empty: name a case base file (SQLite) or a SQLAlchemy URL\n"
    ), err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["classify", "train"])
def test_an_unknown_sensor_is_refused_by_the_parser(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    """``--sensor foo`` was taken (and ignored) when the data were not a UI-PRMD folder: the
    parser refuses it as it refuses any unknown choice (exit 2, one line)."""
    db = tmp_path / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    before = _sha(db)
    with pytest.raises(SystemExit) as stop:
        main([command, str(LABELS if command == "train" else CLIP), "--db", str(db), "--sensor",
              "foo"])  # fmt: skip
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"posecbr {command}: error: argument --sensor: invalid choice: 'foo' (choose from "
        f"'kinect', 'vicon'); see posecbr {command} --help"
    ]
    assert _sha(db) == before and sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite"]


@pytest.mark.parametrize(
    ("version", "read", "upgrade"),
    [
        # told to upgrade, which then said it cannot
        (0, "schema version 0, this posecbr", "cannot upgrade a store of schema version 0: "
         "posecbr upgrades versions 1"),
        # "cannot upgrade" where a newer posecbr wrote it
        (3, "(written by a newer posecbr: read it with that one)",
         "the store has schema version 3, newer than this posecbr"),
    ],
)  # fmt: skip
def test_a_store_of_a_schema_it_cannot_read_or_upgrade_says_which(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    version: int,
    read: str,
    upgrade: str,
) -> None:
    db = tmp_path / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    con = sqlite3.connect(db)
    con.execute("UPDATE posecbr_schema_version SET version = ?", (version,))
    con.commit()
    con.close()
    before = _sha(db)
    err = _one_line_error(capsys, ["classify", str(CLIP), "--db", str(db)])
    assert read in err and "casebase upgrade" not in err
    assert upgrade in _one_line_error(capsys, ["casebase", "upgrade", "--db", str(db)])
    assert _sha(db) == before


def assert_upgraded_store_v1(db: str, capsys: pytest.CaptureFixture[str]) -> None:
    """The case base of tests/fixtures/store_v1.sql in ``db`` (a file or a URL) after
    ``casebase upgrade``: every case and log entry keeps its id, the case base has a uid and
    version 1, and ``classify`` reads it (the demo squat: deep_squat)."""
    store = open_store(db, readonly=True)
    assert store.load_cases("squats ✓").ids.tolist() == list(range(1, 9))
    log = store.maintenance_log("squats ✓")
    assert [(e.action, e.case_id) for e in log] == [("build", None), ("retain", None),
                                                    ("revise", 6)]  # fmt: skip
    info = store.get_case_base("squats ✓")
    assert len(info.uid) == 32 and info.version == 1
    store.close()
    assert main(["classify", str(CLIP), "--db", db, "--json"]) == 0
    assert '"label": "deep_squat"' in capsys.readouterr().out


def test_a_store_of_schema_1_is_refused_then_upgraded_in_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A real case base written by posecbr 0.1 (tests/fixtures/store_v1.sql: `posecbr train` on
    eight demo clips and one `classify --feedback`, dumped by sqlite3)."""
    db = tmp_path / "old.sqlite"
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    con.close()
    before = _sha(db)
    err = _one_line_error(capsys, ["classify", str(CLIP), "--db", str(db)])
    assert "schema version 1" in err and "posecbr casebase upgrade --db FILE" in err
    assert _sha(db) == before
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "converted from schema version 1 to 2" in capsys.readouterr().out
    assert_upgraded_store_v1(str(db), capsys)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "already schema version 2" in capsys.readouterr().out
    # new cases never take an old id
    assert main(["classify", str(CLIP), "--db", str(db), "--feedback", "deep_squat",
                 "--novelty", "0", "--benefit", "0"]) == 0  # fmt: skip
    store = open_store(db, readonly=True)
    assert max(store.load_cases("squats ✓").ids) == 9
    store.close()


def test_train_and_casebase_print_hostile_labels_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    hostile = "squat\x1b]0;pwned\x07\u202e"
    data = tmp_path / "data"
    for label, pattern in ((hostile, "m01_s01_*.npz"), ("abduction", "m07_s01_*.npz")):
        (data / label).mkdir(parents=True)
        for f in sorted(DEMO.glob(pattern)):
            (data / label / f.name).write_bytes(f.read_bytes())
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db)]) == 0
    for argv in (["casebase", "info", "--db", str(db)], ["casebase", "list", "--db", str(db)]):
        assert main(argv) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\u202e" not in out
    assert "squat\\x1b]0;pwned\\x07\\u202e" in out
