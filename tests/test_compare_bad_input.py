"""`posecbr compare` and `posecbr report` given bad or hostile input (issue 15): one clear line,
exit status 1, and every file involved unchanged (sha256 of the whole folder before and after,
so no stray temporary file either); results written before any picture, and a picture that
fails is reported, not fatal.

The data: ten real UI-PRMD Kinect clips of the bundled demo (deep squats and shoulder
abductions of three subjects) with their labels swapped on purpose. DAD needs no training: its
rules recognise the movements actually performed, so against the swapped labels it scores
exactly 0 %, while the case base learns the labels as given and scores exactly 100 %: the two
accuracies whose Wilson bounds used to end the run (issue 15, item 7).
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from posecbr.cli import main

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
SWAPPED = {"m01": "standing_shoulder_abduction", "m07": "deep_squat"}
EPISODES = {"s01": (1, 2), "s02": (1, 2), "s03": (1,)}
FAST = ["--similarities", "euclidean", "--features", "fluents", "--peers", "none"]
XSS = "<script>alert(1)</script>"


def snapshot(folder: Path) -> dict[str, str]:
    """sha256 of every file under ``folder`` (and "dir" for every folder), by relative path."""
    return {
        str(p.relative_to(folder)): "dir"
        if p.is_dir()
        else hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
    }


def _swapped_data(folder: Path) -> Path:
    """Ten demo clips copied into ``folder`` with a labels.csv that swaps their movements."""
    folder.mkdir()
    rows = ["path,label,subject"]
    for movement, label in SWAPPED.items():
        for subject, episodes in EPISODES.items():
            for e in episodes:
                name = f"{movement}_{subject}_e0{e}.npz"
                shutil.copy(DEMO / name, folder / name)
                rows.append(f"{name},{label},{subject}")
    (folder / "labels.csv").write_text("\n".join(rows) + "\n")
    return folder / "labels.csv"


def _one_error_line(capsys: pytest.CaptureFixture[str], command: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"posecbr {command}: error: ")
    return err[0]


@pytest.fixture(scope="module")
def compared(
    swapped_compare: tuple[Path, Path, dict[str, str]],
) -> tuple[Path, Path, dict[str, str]]:
    """One `compare --out` on the swapped clips: the labels file, the results folder, and the
    snapshot of the data folder taken before the run (made once in the session, for
    tests/test_hunt22b.py too: tests/conftest.py)."""
    return swapped_compare


def test_a_method_at_100_and_one_at_0_percent_completes_with_every_picture(
    compared: tuple[Path, Path, dict[str, str]],
) -> None:
    labels, out, before = compared
    assert snapshot(labels.parent) == before  # the inputs are untouched
    res = json.loads((out / "results.json").read_text())
    acc = {m["name"]: m for m in res["methods"]}
    cbr, dad = acc["cbr fluents/euclidean"], acc["dad"]
    assert cbr["accuracy"] == 1.0 and dad["accuracy"] == 0.0  # the premise of this test
    # each interval holds its own proportion and stays in [0, 1]
    assert 0.0 < cbr["accuracy_ci"][0] < 1.0 and cbr["accuracy_ci"][1] == 1.0
    assert dad["accuracy_ci"][0] == 0.0 and 0.0 < dad["accuracy_ci"][1] < 1.0
    pics = res["pictures"]
    files = [pics["accuracy"], pics["prevalence"]]
    files += [c["file"] for c in pics["confusion"]] + [t["file"] for t in pics["timelines"]]
    assert [c["method"] for c in pics["confusion"]] == ["cbr fluents/euclidean", "dad"]
    assert len(pics["timelines"]) == 2
    for f in files:
        assert (out / f).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not any("failed" in n for n in res["notes"])


def test_results_are_written_before_any_picture(
    compared: tuple[Path, Path, dict[str, str]],
) -> None:
    _, out, _ = compared
    res = json.loads((out / "results.json").read_text())
    written = (out / "results.csv").stat().st_mtime_ns  # written once, before the pictures
    pictures = [out / res["pictures"]["accuracy"], out / res["pictures"]["prevalence"]]
    assert all(written <= p.stat().st_mtime_ns for p in pictures)


def test_a_picture_that_fails_is_reported_and_the_results_are_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    labels = _swapped_data(tmp_path / "data")
    blocker = tmp_path / "out" / "accuracy.png"  # a folder where the picture should go
    (blocker / "keep.txt").parent.mkdir(parents=True)
    (blocker / "keep.txt").write_text("mine")
    before = snapshot(tmp_path)
    assert (
        main(["compare", str(labels), *FAST, "--explain", "0", "--out", str(tmp_path / "out")]) == 0
    )
    err = capsys.readouterr().err
    failed = [line for line in err.splitlines() if line.startswith("picture accuracy failed: ")]
    assert len(failed) == 1 and str(blocker) in failed[0]
    after = snapshot(tmp_path)
    assert {k: v for k, v in after.items() if k in before} == before  # nothing replaced
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    assert "accuracy" not in res["pictures"] and failed[0] in res["notes"]
    assert [m["status"] for m in res["methods"]] == ["ok", "ok"]
    assert (tmp_path / "out" / "results.csv").read_text().startswith("method,")
    # the other pictures were drawn all the same
    assert res["pictures"]["prevalence"] and len(res["pictures"]["confusion"]) == 2
    assert not [p for p in after if p.endswith(".tmp")]


# name, arguments after the data (paths relative to the test folder), expected message
REFUSED = [
    ("json at a folder", ["--json", "folder"], "folder: the JSON output is a folder, not a file"),
    ("csv at a folder", ["--csv", "folder"], "folder: the CSV output is a folder, not a file"),
    ("json in a missing folder", ["--json", "nope/r.json"],
     "nope: the folder of the JSON output does not exist"),
    ("json over the labels", ["--json", "data/labels.csv"],
     "data/labels.csv: the JSON output would overwrite an input"),
    ("csv over a clip", ["--csv", "data/m01_s01_e01.npz"],
     "data/m01_s01_e01.npz: the CSV output would overwrite an input"),
    ("out at a file", ["--out", "data/labels.csv"],
     "data/labels.csv: --out must be a folder, and this is a file"),
    ("out in a missing folder", ["--out", "nope/deeper"],
     "nope: the folder for --out does not exist"),
    # the CSV written second replaced the JSON
    ("json and csv one file", ["--json", "r.json", "--csv", "r.json"],
     "r.json: the JSON output and the CSV output are the same file"),
    ("json in the out folder", ["--out", "res", "--json", "res/results.json"],
     "res/results.json: the JSON output and the results file are the same file"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "message"), [r[1:] for r in REFUSED], ids=[r[0] for r in REFUSED])
def test_an_output_that_cannot_be_written_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    labels = _swapped_data(tmp_path / "data")
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder" / "kept.json").write_text("{}")
    before = snapshot(tmp_path)
    args = [a if a.startswith("--") else str(tmp_path / a) for a in args]
    assert main(["compare", str(labels), *FAST, *args]) == 1
    line = _one_error_line(capsys, "compare")
    assert f"error: {tmp_path}/{message}" in line
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize(("flag", "what"), [("--csv", "CSV"), ("--json", "JSON")])
def test_an_output_over_the_label_file_of_a_folder_given_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flag: str, what: str
) -> None:
    """The data given as a folder: its labels.csv is read, so it is an input too (it was
    replaced by the results table, and the folder could no longer be read)."""
    labels = _swapped_data(tmp_path / "data")
    before = snapshot(tmp_path)
    assert main(["compare", str(labels.parent), *FAST, flag, str(labels)]) == 1
    line = _one_error_line(capsys, "compare")
    assert line.endswith(f"{labels}: the {what} output would overwrite an input ({labels})")
    assert snapshot(tmp_path) == before


def test_a_json_output_in_the_folder_out_makes_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--out res --json res/mine.json`` was refused: res did not exist yet."""
    labels = _swapped_data(tmp_path / "data")
    res = tmp_path / "res"
    argv = ["compare", str(labels), *FAST, "--no-dad", "--explain", "0", "--out", str(res),
            "--json", str(res / "mine.json")]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    assert json.loads((res / "mine.json").read_text()) == json.loads(
        (res / "results.json").read_text()
    )


@pytest.mark.parametrize(
    ("option", "message"),
    [
        # a traceback from numpy after the whole cross-validation
        (["--seed", "-1"], "--seed: must be in 0 to 2**32 - 1, got -1"),
        # clamped: every case voted and the figures changed with the folds' sizes
        (
            ["--k", "7"],
            "--k: must be at most 6, the training clips of the smallest fold, got 7"
            " (5 unless given): give --k 6 or less",
        ),
    ],
)
def test_a_seed_or_k_that_cannot_hold_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: list[str], message: str
) -> None:
    """Ten clips of three subjects (s01 and s02 four each, s03 two): a fold holding out s01
    trains on 6, the fewest."""
    labels = _swapped_data(tmp_path / "data")
    before = snapshot(tmp_path)
    argv = ["compare", str(labels), *FAST, *option, "--json", str(tmp_path / "r.json")]
    assert main(argv) == 1
    assert _one_error_line(capsys, "compare").endswith(f"error: {message}")
    assert snapshot(tmp_path) == before


def test_a_clip_that_shows_nobody_is_left_out_of_every_method_and_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An all-NaN clip among the ten: it failed the case base ("shows no person") while DAD,
    which needs no description, went on, and DAD was crowned best with exit 0. Now it is left
    out of every method, said so, and the others compare as without it: the case base
    learns the labels as given (100 %), DAD the movements performed (0 %)."""
    import numpy as np

    labels = _swapped_data(tmp_path / "data")
    blank = dict(np.load(DEMO / "m01_s03_e02.npz"))
    blank["positions"] = np.full_like(blank["positions"], np.nan)
    np.savez(tmp_path / "data" / "blank.npz", **blank)  # type: ignore[arg-type]
    with labels.open("a") as f:
        f.write("blank.npz,standing_shoulder_abduction,s03\n")
    out = tmp_path / "r.json"
    assert main(["compare", str(labels), *FAST, "--json", str(out)]) == 0
    out_text, err = capsys.readouterr()
    assert f"note: left out 1 clip that shows no person: {tmp_path}/data/blank.npz" in err
    # DAD's wrong clips explained on stdout (they went only to --json and --out before)
    assert "\nm01_s01_e01.npz: standing_shoulder_abduction, answered deep_squat by dad\n" in (
        out_text
    )
    assert "  The true activity: standing shoulder abduction" in out_text
    res = json.loads(out.read_text())
    acc = {m["name"]: m["accuracy"] for m in res["methods"]}
    assert acc == {"cbr fluents/euclidean": 1.0, "dad": 0.0}
    assert res["dataset"]["n_clips"] == 10


# ---------------------------------------------------------------------------- report


def _edited(
    compared: tuple[Path, Path, dict[str, str]], tmp_path: Path, edit: Callable[[dict], Any]
) -> Path:
    """A copy of the results folder whose results.json went through ``edit``."""
    folder = tmp_path / "results"
    shutil.copytree(compared[1], folder)
    doc = json.loads((folder / "results.json").read_text())
    edit(doc)
    (folder / "results.json").write_text(json.dumps(doc))
    return folder


def _drop(path: tuple[Any, ...]) -> Callable[[dict], None]:
    def edit(doc: dict) -> None:
        for key in path[:-1]:
            doc = doc[key]
        del doc[path[-1]]

    return edit


def _put(path: tuple[Any, ...], value: Any) -> Callable[[dict], None]:
    def edit(doc: dict) -> None:
        for key in path[:-1]:
            doc = doc[key]
        doc[path[-1]] = value

    return edit


BAD_RESULTS = [
    ("missing dataset", _drop(("dataset",)), "missing key 'dataset'"),
    ("missing accuracy", _drop(("methods", 1, "accuracy")), "missing key 'methods[1].accuracy'"),
    ("missing class count", _drop(("dataset", "class_counts")),
     "missing key 'dataset.class_counts'"),
    ("html in a number", _put(("methods", 0, "fit_s"), "<img src=x onerror=alert(1)>"),
     "key 'methods[0].fit_s' must be a number, got a string"),
    ("html in an interval", _put(("methods", 0, "accuracy_ci"), [XSS, 1.0]),
     "key 'methods[0].accuracy_ci[0]' must be a number, got a string"),
    ("picture up and out", _put(("pictures", "accuracy"), "../../etc/passwd"),
     "key 'pictures.accuracy' is '../../etc/passwd', not a file inside the results folder"),
    ("picture by absolute path", _put(("pictures", "timelines", 0, "file"), "/etc/passwd"),
     "key 'pictures.timelines[0].file' is '/etc/passwd', not a file inside the results folder"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("edit", "message"), [b[1:] for b in BAD_RESULTS], ids=[b[0] for b in BAD_RESULTS]
)
def test_report_refuses_bad_results_with_one_line(
    compared: tuple[Path, Path, dict[str, str]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    edit: Callable[[dict], Any],
    message: str,
) -> None:
    folder = _edited(compared, tmp_path, edit)
    before = snapshot(tmp_path)
    assert main(["report", str(folder), "--out", str(tmp_path / "report.html")]) == 1
    line = _one_error_line(capsys, "report")
    assert line == f"posecbr report: error: {folder / 'results.json'}: {message}"
    assert snapshot(tmp_path) == before  # no page, no temporary file


@pytest.mark.parametrize("kind", ["link out of the folder", "not a picture"])
def test_report_embeds_only_png_files_inside_the_results_folder(
    compared: tuple[Path, Path, dict[str, str]],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    kind: str,
) -> None:
    secret = tmp_path / "secret.txt"
    secret.write_text("password")
    folder = _edited(compared, tmp_path, _put(("pictures", "accuracy"), "sneaky.png"))
    if kind == "link out of the folder":
        (folder / "sneaky.png").symlink_to(secret)
        want = "picture 'sneaky.png' lies outside the results folder"
    else:
        (folder / "sneaky.png").write_text("password")
        want = "picture 'sneaky.png' is not a PNG image"
    before = snapshot(tmp_path)
    assert main(["report", str(folder), "--out", str(tmp_path / "report.html")]) == 1
    assert _one_error_line(capsys, "report").endswith(f"results.json: {want}")
    assert snapshot(tmp_path) == before


def test_report_refuses_to_overwrite_its_results(
    compared: tuple[Path, Path, dict[str, str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = _edited(compared, tmp_path, lambda doc: None)
    (folder / "results.csv").write_text("method,accuracy\n")  # compare's table beside it
    before = snapshot(tmp_path)
    for name in ("results.json", "results.csv"):  # the CSV was replaced by the page
        results = folder / name
        assert main(["report", str(folder), "--out", str(results)]) == 1
        line = _one_error_line(capsys, "report")
        assert line.endswith(f"{results}: the report would overwrite an input ({results})")
        assert snapshot(tmp_path) == before


def _replace_everywhere(value: Any, old: str, new: str) -> Any:
    """``value`` with ``old`` replaced by ``new`` in every string and every key."""
    if isinstance(value, str):
        return value.replace(old, new)
    if isinstance(value, list):
        return [_replace_everywhere(v, old, new) for v in value]
    if isinstance(value, dict):
        return {k.replace(old, new): _replace_everywhere(v, old, new) for k, v in value.items()}
    return value


def test_report_escapes_every_value_from_the_results(
    compared: tuple[Path, Path, dict[str, str]], tmp_path: Path
) -> None:
    attribute = "x' onmouseover='alert(2)"

    def hostile(doc: dict) -> None:
        # a class name (also in clips, predictions, per-class keys, explanations), a method
        # name, a note, the source, the machine, the target: everything a page shows
        doc.update(_replace_everywhere(doc, "deep_squat", XSS))
        doc.update(_replace_everywhere(doc, "cbr fluents/euclidean", attribute))
        doc["notes"].append(XSS)
        doc["dataset"]["source"] = f"/data/{XSS}"
        doc["machine"]["platform"] = XSS
        doc["settings"]["target"] = XSS

    folder = _edited(compared, tmp_path, hostile)
    assert main(["report", str(folder), "--out", str(tmp_path / "report.html")]) == 0
    page = (tmp_path / "report.html").read_text()
    assert "<script" not in page.lower()  # the page has no script of its own
    assert "onmouseover='" not in page
    escaped = "&lt;script&gt;alert(1)&lt;/script&gt;"
    assert page.count(escaped) >= 6
    assert "x&#x27; onmouseover=&#x27;alert(2)" in page
    # the explanations of DAD's errors (the true movement is the hostile class) are shown
    assert "DAD chose " in page
