"""Hunt 47c: small command-line defects a previous session found and left.

1. ``convert ... --episodes 1,99`` over data whose clips have no episode 99 converted
   episode 1 and ignored 99 without a word: refused naming the episodes the data have, as
   ``--subjects`` and ``--movements`` are.
2. ``train --append`` without ``--name`` into a store of several case bases added to the one
   named ``default`` where ``classify``, ``segment`` and ``watch``, which its help said it
   followed, refuse such a store: refused as they refuse it.
3. ``dad CLIP --json`` lacked the best match and the activities tied with it, which the text
   says.
4. ``--plot newdir/`` (a folder not there yet) was refused as no picture's name: a name
   ending in "/" is a folder, made as ``convert --out DIR`` makes its own; a picture named
   in a missing folder is refused naming the folder, as every output file is.
5. ``--db "me:PW@host/db"`` (a database URL without its scheme) was taken for a file's name
   and printed whole, password included.
7. ``report RESULTS --out data/labels.csv`` replaced the CSV with the HTML page.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import refused
from tests.moves import clip


@pytest.fixture
def squat_npz(tmp_path: Path) -> Path:
    """A synthetic squat of 3 s at 30 fps (tests/moves.py) as a pose file."""
    return save_pose(clip("squat", seconds=3.0), tmp_path / "squat.npz")


# ---- 1. convert --episodes names the episodes the data have ----------------------------


def test_convert_refuses_an_episode_no_clip_has_naming_those_there(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """UI-PRMD's files are named ``..._e01`` to ``..._e10`` (data README, the file names)."""
    argv = ["convert", str(shared_data / "ui-prmd"), "--movements", "m01", "--subjects", "s01",
            "--correct", "--episodes", "1,99", "--out", str(tmp_path / "out")]  # fmt: skip
    refused(
        argv,
        tmp_path,
        capsys,
        "--episodes: no clip of episode '99' in",
        ": its episodes are 1, 2, 3, 4, 5, 6, 7, 8, 9 and 10",
    )


def test_convert_refuses_an_episode_the_other_filters_leave_out(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """HDM05's squats: takes 1-12 are actor bd's, 13-24 bk's (the file names): take 13 is
    in the data, but not bd's."""
    folder = shared_data / "hdm05" / "train" / "10"
    argv = ["convert", str(folder), "--subjects", "bd", "--episodes", "12,13",
            "--out", str(tmp_path / "out")]  # fmt: skip
    refused(argv, tmp_path, capsys, "--episodes: no clip of episode '13' in", "passes the other")


def test_convert_takes_a_range_as_a_bound(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--episodes 9-12`` over episodes 1-10: episodes 9 and 10 converted, not refused."""
    out = tmp_path / "out"
    argv = ["convert", str(shared_data / "ui-prmd"), "--movements", "m01", "--subjects", "s01",
            "--correct", "--episodes", "9-12", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    assert sorted(p.name for p in out.glob("*.npz")) == ["m01_s01_e09.npz", "m01_s01_e10.npz"]


# ---- 2. train --append takes the store's only case base, as classify does ---------------


def test_train_append_without_name_refuses_a_store_of_several(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two case bases of four clips, ``default`` and ``other``; two more clips appended
    without ``--name``: they went to ``default`` without a word."""
    from tests.test_hunt40c import TRAIN, two_label_files

    data = two_label_files(tmp_path / "data")
    db = tmp_path / "cb.sqlite"
    for name in ("default", "other"):
        argv = ["train", str(data / "first.csv"), "--db", str(db), "--name", name, *TRAIN]
        assert main(argv) == 0
    capsys.readouterr()
    said = refused(
        ["train", str(data / "more.csv"), "--db", str(db), "--append"],
        tmp_path,
        capsys,
        "the store holds case bases default, other: choose one with --name",
    )
    # classify refuses the store in the same words
    assert main(["classify", str(data / "a" / "clip0.npz"), "--db", str(db)]) == 1
    assert capsys.readouterr().err.strip().split("error: ")[1] == said.split("error: ")[1]


# ---- 3. dad --json says what the text says ---------------------------------------------


def test_dad_json_gives_the_best_match_and_the_activities_tied_with_it(
    shared_data: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An HDM05 squat: the text names the best match and those tied with it; the document
    gives the same, by the rule the text follows (the top activity, when some of its QMPs
    were met; tied: scored the same)."""
    amc = shared_data / "hdm05" / "train" / "10" / "HDM_bd_squat1Reps_001_120.amc"
    assert main(["dad", str(amc), "--top", "0"]) == 0
    text = capsys.readouterr().out.splitlines()
    assert main(["dad", str(amc), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    words = {a["activity"]: a["words"] for a in doc["activities"]}
    top = doc["activities"][0]
    assert top["met_weight"] > 0
    assert doc["best"] == top["activity"]
    tied = [a["activity"] for a in doc["activities"][1:] if a["score"] == top["score"]]
    assert tied, "the squat is expected to tie (squat and sit to stand both met in full)"
    assert doc["tied_with"] == tied
    best_line = next(line for line in text if line.startswith("best match: "))
    assert best_line.startswith(f"best match: {words[doc['best']]} (")
    assert best_line.endswith(f"; tied with {', '.join(words[a] for a in tied)})")
    assert (doc["window_s"], doc["step_s"]) == (4.0, 1.0)  # the defaults, as the text says
    assert f"of up to {doc['window_s']:g} s" in text[0]


# ---- 4. --plot DIR/ makes the folder -------------------------------------------------


@pytest.mark.parametrize("command", ["reps", "describe"])
def test_plot_ending_in_a_slash_is_a_folder_made_for_the_picture(
    command: str, squat_npz: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "new" / "pictures"
    assert main([command, str(squat_npz), "--plot", f"{folder}/"]) == 0, capsys.readouterr().err
    assert [p.name for p in folder.iterdir()] == ["squat.png"]
    assert (folder / "squat.png").read_bytes().startswith(b"\x89PNG\r\n\x1a\n")


@pytest.mark.parametrize("command", ["reps", "describe"])
def test_plot_in_a_missing_folder_or_with_no_suffix_names_the_problem(
    command: str, squat_npz: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    new = tmp_path / "new"
    refused([command, str(squat_npz), "--plot", str(new / "x.png")], tmp_path, capsys,
            f"{new}: the folder of the picture does not exist")  # fmt: skip
    made = f"got 'no suffix'); a folder to be made for it is written ending in / ({new}/)"
    refused([command, str(squat_npz), "--plot", str(new)], tmp_path, capsys,
            f"{new}: the picture must be a file name ending in a format matplotlib writes",
            made)  # fmt: skip


# ---- 5. a database URL without its scheme ---------------------------------------------


@pytest.mark.parametrize("command", ["classify", "train"])
def test_a_database_url_without_its_scheme_is_refused_its_password_hidden(
    command: str, squat_npz: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    line = refused(
        [command, str(squat_npz), "--db", "me:s3cret@dbhost/cases"],
        tmp_path,
        capsys,
        "me:***@dbhost/cases: looks like a database URL without its scheme",
    )
    assert "s3cret" not in line


# ---- 7. report writes HTML only to an HTML name ---------------------------------------


def test_report_refuses_an_out_that_is_no_html_name(
    compared_small: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copy(compared_small[0] / "run.json", tmp_path / "run.json")
    labels = tmp_path / "data" / "labels.csv"
    labels.parent.mkdir()
    labels.write_text("path,label\na.npz,squat\n", encoding="utf-8")
    said = f"{labels}: the report is an HTML page: name it .html or .htm (got '.csv')"
    refused(["report", str(tmp_path / "run.json"), "--out", str(labels)], tmp_path, capsys, said)
