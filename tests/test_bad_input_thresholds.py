"""Fluent thresholds and the ADD: the printed table reads back, and every malformed or
out-of-range file is one clear line, exit 1, nothing changed (issue 15)."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.fluents import DEFAULT_TABLE, FluentTable
from features.qmp.add import default_add_path
from posecbr.cli import main
from tests.badinput import good_pose_file, refused, snapshot
from tests.bodies import standing, to_sequence


def _printed_table(capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["thresholds"]) == 0
    return capsys.readouterr().out


def test_documented_round_trip_reads_back_the_same_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``posecbr thresholds > t.json; posecbr thresholds --from t.json`` prints the same."""
    printed = _printed_table(capsys)
    path = tmp_path / "t.json"
    path.write_text(printed)
    assert main(["thresholds", "--from", str(path)]) == 0
    assert capsys.readouterr().out == printed
    assert FluentTable.from_file(path) == DEFAULT_TABLE


def test_one_value_edited_in_the_printed_table_takes_effect(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The user edits one number in the full printed table (not a table of their own): a
    knee at 150 degrees reads straight by default (tau = 19pi/24 = 142.5 deg) and bent once
    left_leg_bent's tau is 7pi/8 (157.5 deg), with delta pi/48 (3.75 deg)."""
    table = json.loads(_printed_table(capsys))
    table["fluents"]["left_leg_bent"]["lower"] = {"tau": 7 * math.pi / 8, "delta": math.pi / 48}
    path = tmp_path / "t.json"
    path.write_text(json.dumps(table, indent=1))
    body = standing()
    shank = [0.0, -math.cos(math.radians(30)), -math.sin(math.radians(30))]
    body["left_ankle"] = body["left_knee"] + 0.45 * np.array(shank)
    clip = tmp_path / "knee150.npz"
    from features.poses import save_pose

    save_pose(to_sequence(body), clip)

    def states(*extra: str) -> set[str]:
        assert main(["describe", str(clip), "--json", *extra]) == 0
        runs = json.loads(capsys.readouterr().out)["runs"]
        return {s["name"] for s in runs[0]["states"]}

    assert "left_leg_bent.straight" in states()
    edited = states("--thresholds", str(path))
    assert "left_leg_bent.bent" in edited
    assert "right_leg_bent.straight" in edited  # only the left side was edited


def _thresholds(tmp_path: Path, text: str, suffix: str = ".toml") -> Path:
    path = tmp_path / f"t{suffix}"
    path.write_text(text)
    return path


def _printed_with(change: Callable[[dict], None]) -> str:
    table = DEFAULT_TABLE.to_dict()
    change(table)
    return json.dumps(table)


def _set(path: str, value: object) -> Callable[[dict], None]:
    def change(table: dict) -> None:
        keys = path.split("/")
        node = table
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value

    return change


# (case, file name, its text or bytes, words the line must hold)
CASES: list[tuple[str, str, str | bytes, str]] = [
    # the kinds named in issue 15
    ("a binary thresholds file", "t.json", bytes(range(256)) * 4,
     "the thresholds file is not UTF-8 text"),
    ("tau 3pi/0", "t.toml", '[fluents.leg_bent.lower]\ntau = "3pi/0"\n',
     "fluents.leg_bent.lower.tau: division by zero in '3pi/0'"),
    ("tau -1", "t.toml", "[fluents.leg_bent.lower]\ntau = -1\n",
     "lower tau must be radians in [0, pi], got -1"),
    ("touching_m -5", "t.toml", "touching_m = -5\n",
     "touching_m must be a distance in metres in (0, 10], got -5"),
    # more kinds
    ("tau above pi", "t.toml", "[fluents.arm_bent.lower]\ntau = 4.0\n",
     "lower tau must be radians in [0, pi], got 4"),
    ("a negative near distance", "t.toml", "[fluents.near.lower]\ntau = -0.5\n",
     "lower tau must be head-lengths >= 0, got -0.5"),
    ("a motion threshold above pi", "t.toml", '[fluents.leg_bent.motion]\ntau = "4pi"\n',
     "motion tau must be radians in [0, pi]"),
    ("tau a lone dot", "t.toml", '[fluents.leg_bent.lower]\ntau = "."\n',
     "cannot read '.' as a number or a multiple of pi"),
    ("tau an over-long string", "t.toml", f'[fluents.leg_bent.lower]\ntau = "{"1" * 5000}"\n',
     "as a number or a multiple of pi"),
    ("tau an integer of 400 digits", "t.json",
     '{"fluents": {"leg_bent": {"lower": {"tau": 1' + "0" * 400 + "}}}}",
     "value is too large"),
    ("delta zero", "t.toml", "[fluents.leg_bent.lower]\ndelta = 0\n",
     "delta must be positive"),
    # found by hunt 32h: accepted, then an infinite slope and a RuntimeWarning in describe
    ("delta subnormal", "t.json", '{"fluents": {"leg_bent": {"lower": {"delta": 1e-320}}}}',
     "delta must be at least 1e-300 (the confidence's slope would be infinite), got 1e-320"),
    ("upper tau below lower tau", "t.toml", "[fluents.arm_raised.upper]\ntau = 0.5\n",
     "upper tau is below lower tau"),
    ("an upper boundary on a two-state fluent", "t.toml", "[fluents.leg_bent.upper]\ntau = 3\n",
     "this fluent has no such boundary"),
    ("window zero", "t.toml", "window = 0\n", "window must be a whole number from 1 to 100"),
    ("window a million", "t.toml", "window = 1000000\n",
     "window must be a whole number from 1 to 100, got 1000000"),
    ("window a fraction", "t.json", '{"window": 5.5}', "window must be a whole number"),
    ("epsilon 0.7", "t.toml", "epsilon = 0.7\n", "epsilon must be in (0, 0.5)"),
    ("reference_fps zero", "t.toml", "reference_fps = 0\n",
     "reference_fps must be between 0.01 and 10000"),
    ("an unknown setting", "t.toml", "windw = 5\n", "unknown setting 'windw'"),
    ("an unknown fluent", "t.toml", "[fluents.tail_wagging.lower]\ntau = 1\n",
     "unknown fluent 'tail_wagging'"),
    ("a changed signal", "t.json",
     _printed_with(_set("fluents/left_leg_bent/signal", "right_knee")),
     "signal is fixed by the fluent (\"left_knee\") and cannot be changed"),
    ("renamed states", "t.json",
     _printed_with(_set("fluents/left_leg_bent/states", ["flexed", "extended"])),
     "states is fixed by the fluent"),
    ("a value as a list", "t.json", _printed_with(_set("fluents/left_leg_bent/lower/tau", [1])),
     "expected a number, got [1]"),
    ("a value true", "t.json", _printed_with(_set("epsilon", True)), "expected a number, got True"),
    ("fluents as a list", "t.json", '{"fluents": [1, 2]}',
     "'fluents' must be a table of fluent names"),
    ("a fluent as a number", "t.json", '{"fluents": {"leg_bent": 3}}',
     "fluent 'leg_bent': expected a table"),
    # it said "expected a table with keys tau and/or delta", leaving 'tao' to be found (46c)
    ("a boundary with an unknown key", "t.toml", "[fluents.leg_bent.lower]\ntao = 1\n",
     "fluents.leg_bent.lower: unknown key 'tao' (known: tau, delta)"),
    ("malformed TOML", "t.toml", "[fluents.leg_bent\n", "not valid TOML"),
    ("malformed JSON", "t.json", '{"window": 5,,}', "not valid JSON"),
    ("a JSON list at the top", "t.json", "[1, 2, 3]",
     "the thresholds file must hold a table/object at the top level"),
    ("JSON nested a hundred thousand deep", "t.json", "[" * 100_000 + "]" * 100_000,
     "the thresholds file is nested too deeply"),
    ("an empty file", "t.json", "", "not valid JSON"),
    ("UTF-16 text", "t.json", '{"window": 5}'.encode("utf-16"),
     "the thresholds file is not UTF-8 text"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "name", "content", "needle"), CASES, ids=[c[0] for c in CASES])
def test_bad_thresholds_are_one_clear_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    case: str,
    name: str,
    content: str | bytes,
    needle: str,
) -> None:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    line = refused(["thresholds", "--from", str(path)], tmp_path, capsys, needle)
    assert str(path) in line
    # the same file given to describe is refused the same way, before the clip is read
    clip = good_pose_file(tmp_path / "clip.npz")
    line = refused(["describe", str(clip), "--thresholds", str(path)], tmp_path, capsys, needle)


def test_a_thresholds_file_that_is_a_folder_missing_or_huge(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "dir.json").mkdir()
    refused(["thresholds", "--from", str(tmp_path / "dir.json")], tmp_path, capsys,
            "the thresholds file is a folder, not a file")  # fmt: skip
    refused(["thresholds", "--from", str(tmp_path / "none.json")], tmp_path, capsys,
            "thresholds file not found")  # fmt: skip
    huge = tmp_path / "huge.json"
    huge.write_bytes(b" " * (11 * 1024**2))
    refused(["thresholds", "--from", str(huge)], tmp_path, capsys,
            "the thresholds file is 12 MB: too large for a configuration file")  # fmt: skip


# ---- the ADD (posecbr dad --add) -----------------------------------------------------


def _add_text() -> str:
    return default_add_path().read_text(encoding="utf-8")


ADD_CASES: list[tuple[str, str | bytes, str]] = [
    ("a binary ADD", bytes(range(256)) * 4, "the ADD file is not UTF-8 text"),
    ("not TOML", "[qmp.x\nwords = 1", "not valid TOML"),
    ("nested too deeply", "a = " + "[" * 100_000 + "]" * 100_000,
     "nested too deeply"),
    ("an unknown signal", _add_text().replace('"{side}_knee"', '"{side}_tail"', 1),
     "unknown signal"),
    ("a weight of 11", _add_text().replace("weight = 10", "weight = 11", 1),
     "field 'weight' must be an integer from 1 to 10"),
    ("min above max", "schema = 1\n[qmp.a]\nwords = 'a'\nconditions = "
     "[{signal = 'left_knee', quantity = 'amplitude', min = 2, max = 1}]\n"
     "[activity.b]\nwords = 'b'\nlabels = ['b']\nsequence = [{qmp = 'a', weight = 1},"
     " {qmp = 'a', weight = 1}]\n", "'min' (2.0) is above 'max' (1.0)"),
    ("an unknown schema", "schema = 2\n", "unsupported ADD schema 2"),
    ("no activities", "schema = 1\n[qmp.a]\nwords = 'a'\nconditions = "
     "[{signal = 'left_knee', quantity = 'amplitude', min = 1}]\n",
     "no [activity.<name>] entries"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "content", "needle"), ADD_CASES, ids=[c[0] for c in ADD_CASES])
def test_bad_add_is_one_clear_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    case: str,
    content: str | bytes,
    needle: str,
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    add = tmp_path / "add.toml"
    if isinstance(content, bytes):
        add.write_bytes(content)
    else:
        add.write_text(content, encoding="utf-8")
    line = refused(["dad", str(clip), "--add", str(add)], tmp_path, capsys, needle)
    assert str(add) in line


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--window", "0"], "--window: must be in (0, 3600] seconds, got 0.0"),
        (["--window", "1e9"], "--window: must be in (0, 3600] seconds"),
        (["--step", "nan"], "--step: must be in (0, 3600] seconds, got nan"),
        (["--top", "-1"], "--top: must be >= 0, got -1"),
    ],
)
def test_bad_dad_arguments_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], needle: str
) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    refused(["dad", str(clip), *flags], tmp_path, capsys, needle)


def test_missing_add_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    clip = good_pose_file(tmp_path / "clip.npz")
    before = snapshot(tmp_path)
    refused(["dad", str(clip), "--add", str(tmp_path / "no.toml")], tmp_path, capsys,
            "ADD file not found")  # fmt: skip
    assert snapshot(tmp_path) == before
