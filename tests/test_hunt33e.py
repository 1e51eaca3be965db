"""A new user's walkthrough (hunt 33e): the README from the top, every command's help, the
JSON outputs, plausible mistakes and the words and units the commands share."""

from __future__ import annotations

import argparse
import os
import shlex
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cbr.dad import detect
from features.errors import DataError
from features.fileio import check_output
from features.qmp import fit_signals
from features.qmp.add import evaluate_criteria, load_add
from posecbr.cli import build_parser, main
from tests.badinput import good_pose_file, refused, small_case_base
from tests.bodies import standing, to_sequence


@pytest.fixture
def stream_link(tmp_path: Path) -> Iterator[Path]:
    """``root/out.png``, a link to ``/proc/self/fd/N`` for a file this process has open,
    as ``/dev/stdout`` is a link to ``/proc/self/fd/1`` (a regular file at its end when
    standard output is redirected to one: ``posecbr ... --json /dev/stdout > results``)."""
    root = tmp_path / "root"
    root.mkdir()
    with open(tmp_path / "redirected.txt", "w") as stream:
        link = root / "out.png"
        link.symlink_to(f"/proc/self/fd/{stream.fileno()}")
        assert link.is_file()  # what let it through: the link leads to a regular file
        yield link


def test_check_output_refuses_a_name_of_an_open_stream(stream_link: Path) -> None:
    # before: accepted, and the writer's rename then replaced the link itself with a file: run
    # as root with standard output redirected, `compare --json /dev/stdout` made /dev/stdout
    # an ordinary file for every process on the machine
    for path in (stream_link, Path(f"/proc/self/fd/{os.open(os.devnull, os.O_RDONLY)}")):
        with pytest.raises(DataError, match="names standard output or another open stream"):
            check_output(path, what="report")
    assert check_output(stream_link.parent / "real.json") == stream_link.parent / "real.json"


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="no /proc")
def test_describe_plot_to_a_name_of_standard_output_is_refused(
    stream_link: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clip = good_pose_file(stream_link.parent / "clip.npz", frames=12)
    line = refused(["describe", str(clip), "--plot", str(stream_link)], stream_link.parent,
                   capsys, "out.png: names standard output")  # fmt: skip
    assert line.endswith("name a file for the picture")
    assert stream_link.is_symlink()


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="no /proc")
def test_train_db_to_a_name_of_standard_output_is_refused(
    stream_link: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the SQLite database was written through the link into the redirected output
    data = stream_link.parent / "data"
    for label in ("stand", "wait"):
        (data / label).mkdir(parents=True)
        for i in range(2):
            good_pose_file(data / label / f"c{i}.npz", frames=40)
    refused(["train", str(data), "--db", str(stream_link)], stream_link.parent, capsys,
            "out.png: names standard output", "case base file")  # fmt: skip
    assert (stream_link.parent.parent / "redirected.txt").read_bytes() == b""


@pytest.mark.parametrize(
    ("argv", "command"),
    [
        (["classify", "clip.npz", "--db", "cb.sqlite", "--verbse"], "posecbr classify"),
        (["casebase", "info", "--db", "cb.sqlite", "--jsn"], "posecbr casebase info"),
        (["describe", "clip.npz", "other.npz"], "posecbr describe"),
    ],
)
def test_an_unknown_argument_is_refused_by_the_command_it_was_given_to(
    argv: list[str], command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "posecbr: error: unrecognized arguments: --verbse; see posecbr --help", whose
    # help lists the commands, not the options of the command the typo was made in
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{command}: error: unrecognized arguments: {argv[-1]}")
    assert err.endswith(f"; see {command} --help\n") and err.count("\n") == 1


def test_an_unknown_argument_before_the_command_is_still_posecbrs(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["--jsn"])
    assert capsys.readouterr().err.startswith("posecbr: error: unrecognized arguments: --jsn;")


def _options(parser: argparse.ArgumentParser, name: str = "posecbr") -> Iterator[tuple[str, Any]]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub, child in action.choices.items():
                yield from _options(child, f"{name} {sub}")
        elif action.option_strings and action.help != argparse.SUPPRESS:
            yield name, action


def _subcommand(name: str) -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    found: argparse.ArgumentParser = sub.choices[name]
    return found


def test_every_option_with_a_default_says_it_in_its_help() -> None:
    # before: `train --similarity`, `--mirror`, `--feature-weights`, `--phases`, `--name`,
    # `demo --out`, `watch --speed`, `--stall`, `--unknown`, `compare --peers`, `--k`,
    # `--jobs`, `--seed` and `--explain` left their default unsaid
    silent = [
        f"{command} {action.option_strings[-1]}"
        for command, action in _options(build_parser())
        if action.nargs != 0
        and action.default not in (None, [], argparse.SUPPRESS)
        and "default" not in (action.help or "").lower()
        and f"({action.default})" not in (action.help or "")
    ]
    assert silent == []


def test_train_help_says_the_defaults_it_fills_in_itself() -> None:
    # these options default to None (so that --append can tell them unset) and get their
    # value in `train`: argparse's default says nothing, so the help must
    train = _subcommand("train")
    helps = {
        a.option_strings[-1]: " ".join((a.help or "").split())
        for a in train._actions
        if a.option_strings
    }
    assert "(default euclidean)" in helps["--similarity"]
    assert "auto (the default)" in helps["--mirror"]
    assert "default: auto" in helps["--feature-weights"]
    assert "auto (the default)" in helps["--phases"]
    assert "(default: keep all)" in helps["--trim"]


def test_dad_says_why_a_qmp_was_not_met_in_degrees_as_its_words_do() -> None:
    # before: "arms kept within about 115 degrees of the torso: not met; needs left armpit
    # mean at most 2 rad (observed 2.35 rad)": the ADD's radians beside the words' degrees,
    # where every other output (describe, classify, reps) gives angles in degrees
    add = load_add()
    names = add.signals
    t = np.arange(120) / 30.0
    values = np.full((len(t), len(names)), 1.5) + 1e-4 * np.arange(len(names))
    values[:, names.index("left_armpit")] = 2.35  # 134.6°
    values[:, names.index("right_armpit")] = 0.5  # 28.6°, within
    res = evaluate_criteria(add, fit_signals(values, 30.0, names))
    q = res.names.index("arms_below_shoulders")
    assert res.observable[0, q] and not res.met[0, q]
    assert res.failed[q] == ("left armpit mean at most 115° (observed 135°)",)


def test_dad_explanation_in_compare_gives_the_score_as_dad_does() -> None:
    # before: compare's explanation of a DAD error said "(score 0.78)" where `posecbr dad`
    # says "78 % of its QMPs in order"
    still = to_sequence(*[standing()] * 90, fps=30.0)
    squat = next(a for a in detect(still).activities if a.activity == "squat")
    share = f"{100 * squat.score:.0f} % of its QMPs in order"
    assert squat.in_words().startswith(f"squat ({share}); met: ")


@pytest.mark.parametrize(
    ("options", "needles"),
    [
        (["--similarity", "dtwx"], ("error: --similarity: unknown similarity 'dtwx'",)),
        # the help's example was "--param band=0.2", a parameter of dtw, not of the default
        (["--param", "band=0.2"], ("error: --param: similarity 'euclidean' has no parameter",)),
    ],
)
def test_train_names_the_option_of_a_bad_similarity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str], needles: tuple[str]
) -> None:
    # before: "posecbr train: error: similarity: unknown similarity 'dtwx' ...": the
    # registry's field, not the option the user typed
    data = tmp_path / "data"
    for label in ("stand", "wait"):
        (data / label).mkdir(parents=True)
        good_pose_file(data / label / "c.npz", frames=40)
    refused(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), *options], tmp_path,
            capsys, *needles)  # fmt: skip


def test_train_help_example_of_a_similarity_parameter_names_its_similarity() -> None:
    train = _subcommand("train")
    (param,) = [a for a in train._actions if "--param" in a.option_strings]
    assert "--similarity dtw --param band=0.2" in str(param.help)


def test_a_change_in_torso_lengths_says_its_unit_once() -> None:
    # before: "left elbow height (highest) 1.31 torso lengths → 0.81 torso lengths" (hunt
    # 27g's fix said a confidence's words once, but not a unit written after the value)
    from cbr.explain import Claim, _change_text

    height = Claim("change", "c", "f", "left elbow height (highest)", 1.313, "torso lengths",
                   there=0.807)  # fmt: skip
    assert _change_text(height) == "left elbow height (highest) 1.31 → 0.81 torso lengths"
    unseen = Claim("change", "c", "f", "left hip height", None, "torso lengths", there=-0.5)
    assert _change_text(unseen) == "left hip height not seen → -0.50 torso lengths"


def test_compare_help_says_its_json_is_a_file_unlike_the_other_commands() -> None:
    # `posecbr compare DATA --json` (as every other command takes it) was refused "expected
    # one argument", and its help said only "write all results as JSON"
    compare = _subcommand("compare")
    (json_,) = [a for a in compare._actions if "--json" in a.option_strings]
    assert "unlike other commands' --json" in str(json_.help)
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    assert "`--json FILE`, `--csv FILE`: files, unlike other commands' `--json`" in readme


@pytest.mark.parametrize(
    ("spoil", "needle"),
    [
        ("labels", "frames: the label file is a folder, not a file"),
        ("names", "frames: the label names file is a folder, not a file"),
        ("missing", "nowhere.txt: no such label file"),
    ],
)
def test_a_label_file_that_is_a_folder_or_missing_is_said_as_other_inputs_are(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], spoil: str, needle: str
) -> None:
    # before: "cannot read the label file ([Errno 21] Is a directory: 'frames')", Python's
    # words where every other input says "is a folder, not a file" or "no such file"
    clip = good_pose_file(tmp_path / "rec.npz", frames=60)
    folder = tmp_path / "frames"
    folder.mkdir()
    labels = tmp_path / "labels.txt"
    labels.write_text("1 " * 60)
    names = tmp_path / "names.txt"
    names.write_text("1 stand\n")
    given = {
        "labels": [str(folder), "--label-names", str(names)],
        "names": [str(labels), "--label-names", str(folder)],
        "missing": [str(tmp_path / "nowhere.txt")],
    }[spoil]
    line = refused(["train", str(clip), "--db", str(tmp_path / "cb.sqlite"), "--frame-labels",
                    *given], tmp_path, capsys, needle)  # fmt: skip
    assert "Errno" not in line


@pytest.mark.parametrize(
    ("kind", "needle"),
    [
        ("pose", "(a NumPy file, such as a pose file: --db takes the case base file)"),
        ("csv", "(a text file, such as a labels CSV: --db takes the case base file)"),
        ("junk", "(corrupt or not a database)"),
    ],
)
def test_db_given_an_input_file_says_what_that_file_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, needle: str
) -> None:
    # before: "classify cb.sqlite --db clip.npz" (the two swapped) said only "clip.npz: not a
    # readable SQLite database (corrupt or not a database)"
    clip = good_pose_file(tmp_path / "clip.npz", frames=12)
    db = {"pose": clip, "csv": tmp_path / "labels.csv", "junk": tmp_path / "junk.sqlite"}[kind]
    if kind == "csv":
        db.write_text("path,label\nclip.npz,stand\n")
    if kind == "junk":
        db.write_bytes(bytes(range(256)) * 8)
    refused(["classify", str(clip), "--db", str(db)], tmp_path, capsys,
            f"{db.name}: not a readable SQLite database {needle}")  # fmt: skip


@pytest.mark.parametrize(
    ("options", "needle"),
    [
        (["--states", "foo"], "error: --states: must be one of angles, instantaneous, all"),
        (["--length", "5000"], "error: --length: must be a whole number of frames from 2 to"),
        (["-k", "0"], "error: -k: must be a positive integer, got 0"),
        (["--phases", "x"], "error: --phases: must be auto or a whole number, got 'x'"),
        (["--similarity", "dtw", "--feature-weights", "fisher"],
         "error: --feature-weights: learned feature weights need clip summaries or QMP"),
    ],
)  # fmt: skip
def test_train_names_the_option_of_a_bad_model_parameter(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str], needle: str
) -> None:
    # before: "states: states must be one of ...", "k: k must be ...", "--phases: --phases
    # must be ...", "feature_weights: ... (summary=True or QMP features, with
    # similarity='euclidean')": the estimator's parameter (and Python's words), not the option
    data = tmp_path / "data"
    for label in ("stand", "wait"):
        (data / label).mkdir(parents=True)
        good_pose_file(data / label / "c.npz", frames=40)
    line = refused(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), *options],
                   tmp_path, capsys, needle)  # fmt: skip
    assert "summary=True" not in line


def test_every_command_help_says_what_the_command_does(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # before: `posecbr thresholds --help` and every `posecbr casebase ACTION --help` gave
    # the usage and the options alone
    commands = [
        ["thresholds"],
        *[["casebase", a] for a in ("info", "list", "export", "copy", "trim", "upgrade")],
    ]
    for argv in commands:
        with pytest.raises(SystemExit):
            main([*argv, "--help"])
        out = capsys.readouterr().out
        description = out.split("\n\n")[1]
        assert not description.startswith(("options:", "positional")), (argv, out)
    with pytest.raises(SystemExit):
        main(["casebase", "trim", "--help"])
    assert "Run a maintenance editor and deactivate dropped cases." in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["classfy", "clip.npz"],
         "posecbr: error: argument COMMAND: invalid choice: 'classfy' (choose from "),
        (["casebase", "inf", "--db", "cb.sqlite"],
         "posecbr casebase: error: argument ACTION: invalid choice: 'inf' (choose from "),
        (["describe", "clip.npz", "--jsn"],
         "posecbr describe: error: unrecognized arguments: --jsn (did you mean '--json'?); "
         "see posecbr describe --help"),
        (["train", "data", "--db", "cb.sqlite", "--similarty", "dtw"],
         "posecbr train: error: unrecognized arguments: --similarty dtw (did you mean "
         "'--similarity'?); see posecbr train --help"),
    ],
)  # fmt: skip
def test_a_mistyped_command_or_option_gets_a_guess(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the choices or the help alone; `classify --feedback` already guessed a label
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(said) and err.count("\n") == 1, err
    if "invalid choice" in said:
        wanted = {"classfy": "classify", "inf": "info"}[
            argv[0] if argv[0] != "casebase" else argv[1]
        ]
        assert f"(did you mean '{wanted}'?); see posecbr" in err


def test_nothing_is_guessed_when_nothing_is_close(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["describe", "clip.npz", "--zzz"])
    assert capsys.readouterr().err == (
        "posecbr describe: error: unrecognized arguments: --zzz; see posecbr describe --help\n"
    )


def test_compare_prints_a_report_command_that_can_be_pasted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "report: posecbr report my results --out my results/report.html", which a
    # shell reads as four arguments
    from tests.test_cbr_cli import _write_classes

    data = _write_classes(tmp_path / "data", 4, 3)
    out = tmp_path / "my results"
    argv = ["compare", str(data), "--similarities", "euclidean", "--features", "fluents",
            "--no-dad", "--peers", "none", "--explain", "0", "--cv", "kfold", "--folds", "2",
            "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]  # where the files went: stderr
    command = last.split("report: ", 1)[1]
    assert shlex.split(command) == ["posecbr", "report", str(out), "--out",
                                    str(out / "report.html")]  # fmt: skip
    assert main(shlex.split(command)[1:]) == 0
    assert (out / "report.html").is_file()


@pytest.mark.parametrize("command", ["convert", "reps", "segment", "watch"])
def test_help_shows_no_sphinx_markup(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    # before: these commands' --help was their module docstring as written for Sphinx:
    # "``posecbr reps CLIP``: ... (:mod:`features.repetitions`)"
    with pytest.raises(SystemExit):
        main([command, "--help"])
    out = capsys.readouterr().out
    assert "``" not in out and ":mod:" not in out and ":func:" not in out
    assert f"`posecbr {command} " in out


def test_classify_subjects_matching_no_clip_names_the_filter(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: "labels.csv: no clips found", the filter that left them all out unsaid (a
    # subject matching some clips but not all was already named)
    for i in range(2):
        good_pose_file(tmp_path / f"c{i}.npz", frames=12)
    csv = tmp_path / "labels.csv"
    csv.write_text("path,label,subject\nc0.npz,stand,s01\nc1.npz,stand,s02\n")
    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()  # what training it printed
    # with the subjects the data have, as train and compare name them (hunt 38z)
    line = f"error: --subjects: no clip of subject 's09' in {csv}: its subjects are s01 and s02"
    refused(["classify", str(csv), "--db", str(db), "--subjects", "s09"], tmp_path, capsys, line)
