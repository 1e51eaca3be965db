"""Hunt 38o: a researcher comparing methods (``posecbr compare``) on the data README shows and
on long recordings.

``compare --labels deep_squat --subjects s99`` (a subject the data do not have) said
"--labels: no clip labelled 'deep_squat' ... passes the other filters", blaming the label
that is there for the subject that is not; ``train`` named the subject. Now a value the
data have nowhere is named first, whichever flag gave it, with the values the data have.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_compare_names_a_subject_the_data_lack_not_the_label(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo holds subjects s01, s02 and s03 (its labels.csv): s99 is none of them."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat", "--subjects", "s99", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"--subjects: no clip of subject 's99' in {DEMO}: its subjects are s01, s02 and s03"
    )


def test_compare_names_a_label_the_data_lack_though_a_subject_is_also_wrong(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both flags name a value the data lack: the labels are checked first, as before."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat,nope", "--subjects", "s01,s99",
            "--json", str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert f"--labels: no clip labelled 'nope' in {DEMO}: its labels are deep_squat," in line


# `compare --peers minirocket` without sktime or aeon ran its minutes and printed a table
# without the one peer asked for ("minirocket skipped: ..."). Named in --peers, a peer that
# cannot run is now refused before any clip is read; not given, it is skipped with a note.


@pytest.mark.parametrize("peers", ["minirocket", "dtw-knn,minirocket"])
def test_a_peer_asked_for_that_cannot_run_is_refused_before_the_run(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    peers: str,
) -> None:
    import cbr.evaluation.methods as methods

    monkeypatch.setattr(methods, "minirocket_backend", lambda: None)  # neither installed
    argv = ["compare", str(DEMO), "--peers", peers, "--json", str(tmp_path / "r.json")]
    line = refused(argv, tmp_path, capsys)
    assert line == (
        "posecbr compare: error: --peers: minirocket cannot run here: MiniRocket needs sktime"
        " or aeon, neither is installed (pip install -e '.[compare]' installs sktime)"
    )


def test_peers_not_given_are_every_peer_and_one_that_cannot_run_is_not_refused(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import cbr.evaluation.methods as methods
    from posecbr.cli import build_parser
    from posecbr.commands.compare import _settings, check_peers_can_run

    monkeypatch.setattr(methods, "minirocket_backend", lambda: None)
    args = build_parser().parse_args(["compare", str(DEMO)])
    settings = _settings(args)
    assert settings.peers == ("dtw-knn", "minirocket")
    check_peers_can_run(args, settings)  # skipped later, with a note, as before
    args = build_parser().parse_args(["compare", str(DEMO), "--peers", "none"])
    assert _settings(args).peers == ()


# `compare --target correct` prints the accuracy per movement under its table (README: "from
# 64 % on the inline lunge to 93 % on scaption: compare prints the accuracy per movement"),
# but its --csv (and --out's results.csv) had no such column, nor which method the McNemar
# p-values test against: a paper's table made from the CSV lost both. Now each row has
# accuracy:GROUP and mcnemar_vs.


def test_csv_holds_the_accuracy_per_movement_the_table_prints(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_json, out_csv = tmp_path / "c.json", tmp_path / "c.csv"
    rc = main([
        "compare", str(DEMO), "--labels", "deep_squat,hurdle_step", "--target", "correct",
        "--similarities", "euclidean", "--features", "fluents", "--peers", "dtw-knn",
        "--explain", "0", "--json", str(out_json), "--csv", str(out_csv),
    ])  # fmt: skip
    assert rc == 0
    printed = capsys.readouterr().out
    with open(DEMO / "labels.csv", newline="") as fh:
        movement_of = {Path(r["path"]).name: r["label"] for r in csv.DictReader(fh)}
    res = json.loads(out_json.read_text())
    movement = np.array([movement_of[c["clip"]] for c in res["clips"]])
    target = np.array([c["target"] for c in res["clips"]])
    with open(out_csv, newline="") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    scored = [m for m in res["methods"] if m["status"] == "ok"]
    assert {m["name"] for m in scored} == {"cbr fluents/euclidean", "dtw-knn"}
    for i, m in enumerate(scored):  # the table's columns: the scored methods in order
        hit = np.array(m["predictions"]) == target
        row = rows[m["name"]]
        for g in ("deep_squat", "hurdle_step"):  # 18 clips each: 3 subjects x 6
            assert (movement == g).sum() == 18
            assert float(row[f"accuracy:{g}"]) == pytest.approx(hit[movement == g].mean(), abs=1e-6)
            line = next(x for x in printed.splitlines() if x.startswith(g + " "))
            assert line.split()[1 + i] == f"{100 * float(row[f'accuracy:{g}']):.1f}"
        assert row["mcnemar_vs"] == res["best"]


# `compare --cv loso` on one subject (or on clips without one) ran stratified k-fold over
# clips with a note and exit 0: figures of the same person in training and test, from a run
# whose command line says leave-one-subject-out. Asked for by name, it is now refused before
# the run; the default (no --cv) still falls back with a note (test_compare_cli).


def test_loso_asked_for_on_one_subject_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["compare", str(DEMO), "--subjects", "s01", "--cv", "loso", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr compare: error: --cv: leave-one-subject-out is impossible in {DEMO}: only"
        " one subject (s01); --cv kfold cross-validates over clips (the same person can be in"
        " training and test)"
    )


def test_loso_asked_for_on_clips_without_subjects_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV with no subject column: 4 clips, none with a subject."""
    data = tmp_path / "data"
    data.mkdir()
    rows = ["path,label"]
    for k in range(4):  # a person standing, 2 s at 30 fps, with no subject
        good_pose_file(data / f"c{k}.npz", frames=60)
        rows.append(f"c{k}.npz,{'squat' if k < 2 else 'lunge'}")
    (data / "labels.csv").write_text("\n".join(rows) + "\n")
    argv = ["compare", str(data / "labels.csv"), "--cv", "loso", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(": 4 clips have no subject; --cv kfold cross-validates over clips"
                         " (the same person can be in training and test)")  # fmt: skip


# `posecbr dad` of a long recording (CMU 13_31: seven exercises in 25 s) ranked seven
# activities at 100 %, none of them its exercises, "tied with" six others, and said nothing
# of why: every activity's QMPs are sought in order across all the clip's windows. A clip
# longer than 10 s now gets a note saying DAD gives it one answer, and what segments it.


@pytest.mark.parametrize(("seconds", "noted"), [(11.0, True), (9.0, False)])
def test_dad_notes_a_clip_longer_than_ten_seconds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], seconds: float, noted: bool
) -> None:
    clip = good_pose_file(tmp_path / "long.npz", frames=int(seconds * 30))  # 30 fps
    assert main(["dad", str(clip)]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith(f"long.npz: {seconds:.1f} s, ")
    note = (
        f"note: long.npz lasts {seconds:.1f} s, longer than 10 s: DAD gives the whole clip one"
        " answer, each activity's QMPs sought in order across all its windows, so a recording"
        " of several activities can meet many in full; posecbr segment labels each activity"
        " of a long recording (with a case base)\n"
    )
    assert captured.err == (note if noted else "")
