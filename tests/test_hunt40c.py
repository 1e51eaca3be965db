"""Hunt 40c: the command line's small inconsistencies. An option abbreviated (``segment --tru
F`` taken as ``--truth F``) is refused; ``-k`` is said in the same words by every command
that votes with the nearest cases, as it means the same in each; ``train FOLDER`` says which
pose files there its labels.csv does not list (left out)."""

from __future__ import annotations

import argparse
import dataclasses
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from posecbr.cli import build_parser, main
from tests.badinput import ROOT, assert_unchanged, good_pose_file, snapshot
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


def _parsers() -> list[tuple[list[str], argparse.ArgumentParser]]:
    """Every parser of the command line with the words that reach it: ``posecbr``'s, each
    command's and each ``casebase`` action's."""
    found: list[tuple[list[str], argparse.ArgumentParser]] = []

    def walk(words: list[str], parser: argparse.ArgumentParser) -> None:
        found.append((words, parser))
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk([*words, name], child)

    walk([], build_parser())
    return found


def _required(parser: argparse.ArgumentParser) -> list[str]:
    """Words that give ``parser`` what it requires (a positional, ``--db``, an action), so
    that an option given before them is judged alone."""
    words: list[str] = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            if action.required:  # casebase: its first action, and what that requires
                name, child = next(iter(action.choices.items()))
                words += [name, *_required(child)]
            continue
        if not action.option_strings and action.nargs in (None, "+", 1):
            words.append(str(next(iter(action.choices))) if action.choices else "a.npz")
        elif action.option_strings and action.required:
            words += [action.option_strings[0], "x"]
    return words


def _abbreviations() -> list[tuple[list[str], str, str]]:
    """(the words to a parser, a long option of it, that option less its last letter) for
    every long option of every parser whose shortened spelling is no option of its own."""
    out = []
    for words, parser in _parsers():
        options = {o for a in parser._actions for o in a.option_strings}
        for option in sorted(o for o in options if o.startswith("--") and len(o) >= 4):
            if option[:-1] not in options:
                out.append((words, option, option[:-1]))
    return out


def test_an_abbreviated_option_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``segment REC --db CB --tru F`` was taken as ``--truth F`` (argparse takes any unique
    prefix of an option): a later option sharing the prefix would change what the command
    line means, a typo lands on another option. Refused as a mistyped option is: exit 2, one
    line naming it and the option meant, nothing read or written."""
    pose = good_pose_file(tmp_path / "rec.npz", frames=30)
    truth = tmp_path / "rec.txt"
    truth.write_text("1\n" * 30, encoding="utf-8")
    before = snapshot(tmp_path)
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        main(["segment", str(pose), "--db", str(tmp_path / "cb.sqlite"), "--tru", str(truth)])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith("posecbr segment: error: unrecognized arguments: --tru"), err
    assert "(did you mean '--truth'?); see posecbr segment --help" in err, err
    assert_unchanged(tmp_path, before)


@pytest.mark.parametrize(
    ("argv", "typed", "meant"),
    [
        (["--vers"], "--vers", "--version"),
        (["casebase", "info", "--db", "x", "--js"], "--js", "--json"),
        (["classify", "a.npz", "--db", "x", "--verb"], "--verb", "--verbose"),
        (["train", "d", "--db", "x", "--feature-weight=fisher"], "--feature-weight", None),
    ],
)
def test_no_level_of_the_command_line_takes_a_prefix(
    capsys: pytest.CaptureFixture[str], argv: list[str], typed: str, meant: str | None
) -> None:
    """``posecbr``'s own parser, a command's and a ``casebase`` action's alike (the form
    ``--option=value`` too): exit 2 naming the word typed."""
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unrecognized arguments: " + typed in err, err
    if meant is not None:
        assert f"(did you mean '{meant}'?)" in err, err


def test_every_long_option_of_every_parser_is_taken_whole_and_not_shortened() -> None:
    """Each long option of ``posecbr``, every command and every ``casebase`` action, less its
    last letter, is left unrecognised (the command line then refuses it), and written whole
    it is taken: no option answers to a prefix any more, and none is lost."""
    parser = build_parser()
    taken_by_prefix = []
    for words, own in _parsers():
        required = _required(own)
        _, unknown = parser.parse_known_args([*words, *required])
        assert unknown == [], (words, required, unknown)
    for words, option, short in _abbreviations():
        required = _required(dict((tuple(w), p) for w, p in _parsers())[tuple(words)])
        try:
            _, unknown = parser.parse_known_args([*words, short, *required])
        except SystemExit:  # taken as the option, then short of its value or ambiguous
            unknown = []
        if unknown != [short]:
            taken_by_prefix.append(f"{' '.join(['posecbr', *words])} {short} ({option})")
    assert taken_by_prefix == [], taken_by_prefix
    assert len(_abbreviations()) > 150  # every command's options were tried


def _table_rows() -> dict[str, str]:
    """The README's command table: each command's row."""
    rows = {}
    for line in (ROOT / "README.md").read_text(encoding="utf-8").splitlines():
        found = re.match(r"\| `posecbr (\w+)", line)
        if found:
            rows[found.group(1)] = line
    return rows


#: an option a row of the table names as another command's ("train the case base with
#: `--split windows`" in segment's row): the command that takes it
OTHER_COMMANDS = {("segment", "--split"): "train", ("segment", "--out"): "extract"}


def test_every_long_option_the_readme_table_names_is_taken_whole() -> None:
    """Each ``--option`` the README's command table gives a command is one that command (or,
    for ``casebase``, one of its actions) takes spelt as written: with prefixes refused, a
    shortened spelling in the README would now be refused."""
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    rows = _table_rows()
    assert set(rows) == set(commands.choices), set(commands.choices) ^ set(rows)
    not_taken = []
    for command, row in rows.items():
        for option in sorted(set(re.findall(r"(?<![\w-])--[a-z][\w-]*", row))):
            owner = OTHER_COMMANDS.get((command, option), command)
            words = [
                [owner, *w] for w, _ in _parsers_of(commands.choices[owner])
            ]  # a casebase action's options too
            if not any(_takes(parser, w, option) for w in words):
                not_taken.append(f"{command}: {option}")
    assert not_taken == [], not_taken


def _parsers_of(parser: argparse.ArgumentParser) -> list[tuple[list[str], argparse.ArgumentParser]]:
    """``parser`` itself (no words) and the parsers of its actions, with their names."""
    out: list[tuple[list[str], argparse.ArgumentParser]] = [([], parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            out += [([name], child) for name, child in action.choices.items()]
    return out


def _takes(parser: argparse.ArgumentParser, words: list[str], option: str) -> bool:
    """Whether ``posecbr WORDS... OPTION`` parses with OPTION taken (given a value when it
    takes one), what the parser at ``words`` requires given."""
    own = dict((tuple(w), p) for w, p in _parsers())[tuple(words)]
    action = next((a for a in own._actions if option in a.option_strings), None)
    if action is None:
        return False
    value = [] if action.nargs == 0 else [str(next(iter(action.choices))) if action.choices
                                          else "1"]  # fmt: skip
    required = _required(own)
    if option in required:  # a required option (--db): given once, as judged
        del required[required.index(option) : required.index(option) + 2]
    _, unknown = parser.parse_known_args([*words, option, *value, *required])
    return unknown == []


def _folder_of_classes(root: Path) -> list[str]:
    """Two synthetic arm movements of each of three activities in class folders ``a``,
    ``b``, ``c`` of ``root``: their paths relative to it, in name order."""
    from features.poses import save_pose
    from tests.test_cbr_clips import ACTIVITIES, arm_dataset

    folder = dict(zip(ACTIVITIES, "abc", strict=True))
    X, y = arm_dataset(2, 7)
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        save_pose(seq, root / folder[str(label)] / f"clip{i}.npz")
    return sorted(p.relative_to(root).as_posix() for p in root.glob("*/*.npz"))


def _listing(root: Path, paths: list[str]) -> None:
    rows = "".join(f"{p},{p.split('/')[0]}\n" for p in paths)
    (root / "labels.csv").write_text("path,label\n" + rows, encoding="utf-8")


TRAIN = ["--mirror", "off", "--feature-weights", "none", "--phases", "0", "-k", "1"]


def test_train_of_a_folder_says_the_pose_files_its_labels_csv_does_not_list(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels.csv copied into a folder of class folders lists four of its six clips, and a
    seventh pose file lies beside it: ``train FOLDER`` reads labels.csv alone and left the
    three out in silence. It trains on the four (as before) and says, once, how many were
    left out, the first three by name and how to include them; a hidden file is none."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    data = tmp_path / "data"
    clips = _folder_of_classes(data)  # a/clip0, a/clip3, b/clip1, b/clip4, c/clip2, c/clip5
    listed = [c for c in clips if c not in ("a/clip3.npz", "c/clip5.npz")]
    _listing(data, listed)
    good_pose_file(data / "extra.npz", frames=12)
    good_pose_file(data / ".hidden" / "old.npz", frames=12)
    good_pose_file(data / "b" / "._clip1.npz", frames=12)
    db = tmp_path / "cb.sqlite"
    capsys.readouterr()
    assert main(["train", str(data), "--db", str(db), *TRAIN]) == 0
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if "does not list" in line]
    assert notes == [
        f"note: {data / 'labels.csv'} does not list 3 pose files in {data} (a/clip3.npz,"
        " c/clip5.npz, extra.npz): train reads it alone and left them out; add a row for"
        " each to it (path,label[,subject]) to train with them"
    ], err
    with open_store(db, readonly=True) as store:
        cb = load_classifier(store, "default").classifier.case_base_
    assert len(cb) == 4


def test_train_of_a_folder_whose_labels_csv_lists_every_pose_file_notes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every pose file listed (or the labels CSV named as a file, whose rows the user chose):
    no such note."""
    data = tmp_path / "data"
    clips = _folder_of_classes(data)
    _listing(data, clips)
    capsys.readouterr()
    assert main(["train", str(data), "--db", str(tmp_path / "one.sqlite"), *TRAIN]) == 0
    assert "does not list" not in capsys.readouterr().err
    _listing(data, clips[:4])
    assert main(["train", str(data / "labels.csv"), "--db", str(tmp_path / "two.sqlite"),
                 *TRAIN]) == 0  # fmt: skip
    assert "does not list" not in capsys.readouterr().err


def _case_base_13_29(db: Path) -> Any:
    """The classifier stored in ``db`` (the fixture's: CMU 13_29's windows, k = 5)."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    with open_store(db, readonly=True) as store:
        return load_classifier(store, "default").classifier


@pytest.mark.parametrize("vote", ["as trained", "uniform, balanced"])
def test_segment_k_votes_in_a_window_as_classify_k_in_that_window_as_a_clip(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    vote: str,
) -> None:
    """``segment -k N`` and ``classify -k N`` mean one thing, said in the same words: the N
    nearest cases vote. Each window of a recording (CMU 13_30, 30 fps, against a case base of
    13_29's windows with k = 5) gets, for N = 1, 3, 5, the vote shares the classifier gives
    that window as a clip with k = N, as trained (1/distance) and under a classifier that
    votes uniformly with its classes balanced (as ``train --target correct`` stores it);
    under the latter the windows voted by 1/distance without the balance before. The shares
    of one window are worked out by hand too: a count of each activity among its N nearest
    cases, times the mean count of the activities' cases over its own."""
    from cbr.segmentation import solve_recording
    from features.derived import stretch
    from tests.test_hunt39c import _13_30

    clf = _case_base_13_29(case_base)
    if vote != "as trained":
        clf.set_params(weights="uniform", class_weight="balanced")
    rec = dataclasses.replace(_13_30(shared_data), positions=_13_30(shared_data).positions[:240])
    assert int(clf.k) == 5
    classes = [str(c) for c in clf.classes_]
    counts = np.array([np.sum(clf.case_base_.labels.astype(str) == c) for c in classes])
    assert len(set(counts.tolist())) > 1  # the balance is heard: the activities' counts differ
    for n in (1, 3, 5):
        clf.set_params(k=5)
        done = solve_recording(clf, rec, k=n, chunk_frames=0)
        assert len(done.windows) >= 4
        clf.set_params(k=n)
        for w in done.windows:
            clip = clf.solve([stretch(done.rec, w.start, w.stop)], flag=False)[0]
            np.testing.assert_allclose(w.vote, clip.solution.proba, atol=1e-12)
        if vote != "as trained":  # by hand, the last window
            near = [str(v) for v in done.windows[-1].solved.retrieval.labels[:n]]
            shares = np.array([near.count(c) for c in classes]) * counts.mean() / counts
            np.testing.assert_allclose(done.windows[-1].vote, shares / shares.sum())


def test_every_command_says_k_in_the_same_words(capsys: pytest.CaptureFixture[str]) -> None:
    """``-k N`` of train, classify, compare, segment and watch: "the N nearest cases vote",
    with its default; it was "retrieved cases" in three and "each window votes with its k
    nearest cases" in two, as though the letter meant two things."""
    said = {}
    for command in ("train", "classify", "compare", "segment", "watch"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        found = re.search(r"-k N, --k N (.*?\))", text)
        assert found, (command, text)
        said[command] = found.group(1)
    for words in said.values():
        assert words.startswith("the N nearest cases vote, each weighed by 1/distance"), words
    assert "(default 5)" in said["train"] and "(default 5)" in said["compare"]
    assert "(default: the case base's own, train -k" in said["classify"]
    for command in ("segment", "watch"):
        assert "in each window" in said[command], said[command]
        assert "(default 1; at most the case base's own k" in said[command], said[command]


def test_watch_k_votes_in_a_window_as_the_classifier_votes(
    case_base: Path,  # noqa: F811
    shared_data: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``watch -k 3`` (:class:`cbr.live.LiveSegmenter` with ``k=3``) under a classifier that
    votes uniformly with its classes balanced: each window's vote is worked out by hand from
    its 3 nearest cases (a count of each activity, times the mean count of the activities'
    cases over its own), as ``classify -k 3`` and ``segment -k 3`` vote; it voted by
    1/distance without the balance before."""
    from cbr.live import LiveSegmenter
    from tests.test_hunt39c import _13_30

    clf = _case_base_13_29(case_base)
    clf.set_params(weights="uniform", class_weight="balanced")
    classes = [str(c) for c in clf.classes_]
    counts = np.array([np.sum(clf.case_base_.labels.astype(str) == c) for c in classes])
    cast: list[tuple[Any, np.ndarray]] = []
    judged = LiveSegmenter._judged

    def spy(self: Any, solved: Any, start: int, stop: int) -> tuple[np.ndarray, float]:
        vote, far = judged(self, solved, start, stop)
        cast.append((solved, vote))
        return vote, far

    monkeypatch.setattr(LiveSegmenter, "_judged", spy)
    live = LiveSegmenter(clf, 30.0, k=3)
    for frame in _13_30(shared_data).to_canonical().positions[:240]:
        live.push(frame)
    live.finish()
    assert len(cast) >= 4
    for solved, vote in cast:
        near = [str(v) for v in solved.retrieval.labels[:3]]
        shares = np.array([near.count(c) for c in classes]) * counts.mean() / counts
        np.testing.assert_allclose(vote, shares / shares.sum())


DEMO_CLIP = ROOT / "posecbr" / "demo_data" / "uiprmd" / "m09_s03_e03.npz"


def test_classify_top_0_is_refused_where_dad_top_0_is_every_activity(
    case_base: Path,  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--top 0`` listed no similar case in ``classify --verbose`` and details every activity
    in ``dad``: one option, opposite meanings for one value. ``classify`` refuses 0 in one
    line (as it does a negative one), saying how to list every case, rather than change what
    an old command line means; ``--top 2`` lists two as before."""
    from tests.badinput import refused

    argv = ["classify", str(DEMO_CLIP), "--db", str(case_base), "--verbose"]
    refused([*argv, "--top", "0"], tmp_path, capsys,
            "posecbr classify: error: --top: must be >= 1, got 0: leave it out to list every"
            " similar case (0 listed none, where dad --top 0 details every activity)")  # fmt: skip
    assert main([*argv, "--top", "2"]) == 0
    listed = [line for line in capsys.readouterr().out.splitlines() if line.startswith("    case ")]
    assert len(listed) == 2, listed


def test_dad_top_with_json_is_refused_as_classify_refuses_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``dad --json --top 3`` printed every activity, the option ignored without a word, where
    ``classify --json --top`` is refused (its document holds every case): refused alike, in
    one line, nothing printed. ``dad --json`` alone and ``dad --top 0`` are as before."""
    import json

    from tests.badinput import refused

    refused(["dad", str(DEMO_CLIP), "--json", "--top", "3"], tmp_path, capsys,
            "posecbr dad: error: --top: goes without --json (its document holds every"
            " activity)")  # fmt: skip
    assert main(["dad", str(DEMO_CLIP), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert main(["dad", str(DEMO_CLIP), "--top", "0"]) == 0
    every = capsys.readouterr().out
    assert main(["dad", str(DEMO_CLIP)]) == 0
    default = capsys.readouterr().out
    assert len(doc["activities"]) > 5
    for text, detailed in ((every, len(doc["activities"])), (default, 5)):
        heads = [line for line in text.splitlines() if "weight in order" in line or
                 ": not scored:" in line]  # fmt: skip
        assert len(heads) == detailed, text


def test_compare_param_of_a_similarity_says_how_compare_takes_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --similarity dtw --param band=0.2`` sets the similarity's band; ``compare
    --param`` sets the classifier's parameters, so ``compare --param band=0.2`` is refused,
    and now says which similarity band belongs to and how compare takes it; the way it says
    is accepted (a parameter of the classifier, checked as compare checks it). A key of no
    similarity gets no such words."""
    from cbr.evaluation.methods import check_cbr_params
    from cbr.evaluation.settings import CompareSettings
    from tests.badinput import refused

    data = ROOT / "posecbr" / "demo_data" / "uiprmd"
    out = tmp_path / "out"
    refused(["compare", str(data), "--param", "band=0.2", "--out", str(out)], tmp_path, capsys,
            "--param: unknown case-base parameter(s) band",
            "(band is a parameter of the dtw similarity, as train --param takes it; here"
            " --param similarity_params='{\"band\": VALUE}' with --similarities dtw)")  # fmt: skip
    line = refused(["compare", str(data), "--param", "bogus=1", "--out", str(out)], tmp_path,
                   capsys, "--param: unknown case-base parameter(s) bogus")  # fmt: skip
    assert line.endswith("velocity, weights)") and "as train --param" not in line, line
    settings = CompareSettings(
        similarities=("dtw",), cbr_params={"similarity_params": {"band": 0.2}}
    )
    check_cbr_params(settings)  # refused had band not been dtw's: "has no parameter"
    with pytest.raises(Exception, match="no parameter band"):
        check_cbr_params(
            CompareSettings(
                similarities=("euclidean",), cbr_params={"similarity_params": {"band": 0.2}}
            )  # fmt: skip
        )


DEMO_LABELS = ROOT / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (["--labels", "deep_squat,bogus"], "--labels: no clip labelled 'bogus' in"),
        (["--labels", "bogus"], "--labels: no clip labelled 'bogus' in"),
        (["--subjects", "s01,s99", "--limit", "2"], "--subjects: no clip of subject 's99' in"),
    ],
)
def test_convert_refuses_a_label_or_subject_no_clip_has_as_train_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str], said: str
) -> None:
    """``convert --labels deep_squat,bogus`` converted the deep squats alone without a word
    (and ``--labels bogus`` said the CSV "holds no clip to convert"), where ``train``,
    ``compare`` and ``classify`` refuse an entry no clip has, naming those the data hold: so
    does convert, nothing written (with ``--limit``, checked against every clip of the
    data). The demo's labels.csv holds subjects s01, s02 and s03."""
    from tests.badinput import refused

    out = tmp_path / "out"
    line = refused(["convert", str(DEMO_LABELS), "--out", str(out), *options], tmp_path, capsys,
                   f"posecbr convert: error: {said} {DEMO_LABELS}: its ")  # fmt: skip
    assert (
        ("deep_squat, hurdle_step" in line)
        if "labels" in said
        else line.endswith("its subjects are s01, s02 and s03")
    ), line
    assert not out.exists()


def test_convert_of_labels_and_subjects_the_data_hold_goes_ahead(tmp_path: Path) -> None:
    """Entries every one of which a clip has: converted as before (the limit reached before
    a clip of s02 was, s02 is still one the data hold)."""
    from features.datasets import read_labels_csv

    out = tmp_path / "out"
    argv = ["convert", str(DEMO_LABELS), "--out", str(out), "--labels", "deep_squat",
            "--subjects", "s01,s02", "--limit", "1"]  # fmt: skip
    assert main(argv) == 0
    rows = read_labels_csv(out / "labels.csv")
    assert [(r["label"], r["subject"]) for r in rows] == [("deep_squat", "s01")]


def two_label_files(data: Path) -> Path:
    """``data`` holding the classes' clips (:func:`_folder_of_classes`) and two labels
    CSVs: first.csv of the first four clips, more.csv of the others."""
    clips = _folder_of_classes(data)
    for name, part in (("first.csv", clips[:4]), ("more.csv", clips[4:])):
        rows = "".join(f"{p},{p.split('/')[0]}\n" for p in part)
        (data / name).write_text("path,label\n" + rows, encoding="utf-8")
    return data


def test_train_append_without_name_adds_to_the_stores_only_case_base(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train MORE --db CB --append`` where CB holds one case base, named x: added to x, as
    ``classify``, ``segment`` and ``watch`` take the store's only one without ``--name``;
    it was refused ("no case base named 'default' (case bases here: x)")."""
    from casebase_store import open_store
    from cbr.stored import load_classifier

    data = two_label_files(tmp_path / "data")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data / "first.csv"), "--db", str(db), "--name", "x", *TRAIN]) == 0
    capsys.readouterr()
    assert main(["train", str(data / "more.csv"), "--db", str(db), "--append"]) == 0, (
        capsys.readouterr().err
    )
    with open_store(db, readonly=True) as store:
        assert [cb.name for cb in store.list_case_bases()] == ["x"]
        assert len(load_classifier(store, "x").classifier.case_base_) == 6
