"""Bugs found by hunting as a new user would in the less-tested commands (``report``, ...).
Each refusal is one line naming the file and the problem, exit 1, nothing written
(:func:`tests.badinput.refused`); each answer is checked against a value worked out by hand."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused

# ---- report ---------------------------------------------------------------------------------


def test_report_on_a_results_file_nested_too_deeply_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A results file of 100,000 nested lists (JSON, but no comparison's results): json's
    decoder ran out of recursion and the command ended in a RecursionError traceback."""
    results = tmp_path / "results.json"
    results.write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
    refused(["report", str(results), "--out", str(tmp_path / "report.html")], tmp_path, capsys,
            f"{results}: not a JSON results file (nested too deeply)")  # fmt: skip


def test_report_on_a_results_file_of_gigabytes_is_refused_before_reading_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 1.1 GiB file named results.json (sparse: no disk used) was read whole into memory
    before json could refuse it; refused from its size in one line, no page written."""
    from posecbr.cli import main

    results = tmp_path / "results.json"
    with results.open("wb") as fh:
        fh.truncate(1024**3 + 1024**3 // 10)
    page = tmp_path / "report.html"
    assert main(["report", str(results), "--out", str(page)]) == 1
    err = capsys.readouterr().err
    assert err == (f"posecbr report: error: {results}: is 1.18 GB: larger than any compare"
                   " results file (the limit is 1.07 GB; the wrong file?)\n")  # fmt: skip
    assert not page.exists() and results.stat().st_size == 1024**3 + 1024**3 // 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]


@pytest.fixture(scope="module")
def compared_folder(swapped_compare: tuple[Path, Path, dict[str, str]]) -> Path:
    """One ``compare --out`` on ten demo clips (tests/test_compare_bad_input.py's, made once
    in the session): its results folder (results.json, results.csv, the pictures)."""
    return swapped_compare[1]


def test_the_report_command_compare_suggests_can_be_run_again(
    compared_folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """compare ends with "report: posecbr report DIR --out DIR/report.html". Run a second
    time (after another compare into the folder, say), it was refused: "the report would
    overwrite an input (report.html)", every file of the folder counting as an input, the
    previous report too. The report is the command's own output: it is written again."""
    import shutil

    from posecbr.cli import main

    folder = tmp_path / "cmp"
    shutil.copytree(compared_folder, folder)
    capsys.readouterr()
    page = folder / "report.html"
    assert main(["report", str(folder), "--out", str(page)]) == 0
    first = page.read_text(encoding="utf-8")
    page.write_text("an old report\n", encoding="utf-8")
    assert main(["report", str(folder), "--out", str(page)]) == 0
    captured = capsys.readouterr()
    assert captured.err == f"report written to {page}\n" * 2  # nothing else said
    assert page.read_text(encoding="utf-8") == first  # the page again, not the old one


def test_report_over_the_results_table_beside_the_results_file_is_refused(
    compared_folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The results file named instead of its folder (README: ``posecbr report
    cmp/results.json``): ``--out cmp/results.csv`` replaced compare's table with the page,
    which the folder's form refuses."""
    import shutil

    folder = tmp_path / "cmp"
    shutil.copytree(compared_folder, folder)
    table = folder / "results.csv"
    assert table.is_file()
    refused(["report", str(folder / "results.json"), "--out", str(table)], tmp_path, capsys,
            f"{table}: the report would overwrite an input ({table})")  # fmt: skip


# ---- train, compare: --param ----------------------------------------------------------------


@pytest.mark.parametrize("command", ["train", "compare"])
def test_a_param_value_nested_too_deeply_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    """``--param k=[[[...`` (a VALUE is read as JSON when it parses): 5,000 nested lists
    ended in a RecursionError traceback."""
    from tests.badinput import good_pose_file

    data = tmp_path / "data"
    data.mkdir()
    for i in range(2):
        good_pose_file(data / f"clip{i}.npz", label="squat", subject=f"s{i}")
    extra = ["--db", str(tmp_path / "cb.sqlite")] if command == "train" else []
    value = "[" * 5000 + "]" * 5000
    refused([command, str(data), *extra, "--param", f"band={value}"], tmp_path, capsys,
            "--param: the value of band is nested too deeply")  # fmt: skip


# ---- compare: its notes name clips ----------------------------------------------------------


def test_compare_prints_a_clip_name_in_a_note_with_its_control_characters_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that shows nobody is left out and named in a note on stderr; its file name,
    which holds an OSC escape (it retitles the terminal), went out raw (README, "Bad input":
    names and paths are printed with control characters escaped)."""
    import numpy as np

    from posecbr.cli import main
    from tests.test_compare_bad_input import DEMO, FAST, _swapped_data

    labels = _swapped_data(tmp_path / "data")
    name = "blank\x1b]0;pwned\x07.npz"
    blank = dict(np.load(DEMO / "m01_s03_e02.npz"))
    blank["positions"] = np.full_like(blank["positions"], np.nan)
    np.savez(tmp_path / "data" / name, **blank)  # type: ignore[arg-type]
    with labels.open("a", encoding="utf-8") as f:
        f.write(f"{name},standing_shoulder_abduction,s03\n")
    capsys.readouterr()
    assert (
        main(["compare", str(labels), *FAST, "--no-dad", "--json", str(tmp_path / "r.json")]) == 0
    )
    out, err = capsys.readouterr()
    assert "note: left out 1 clip that shows no person: " in err
    assert "blank\\x1b]0;pwned\\x07.npz" in err
    assert "\x1b" not in err and "\x07" not in err and "\x1b" not in out
