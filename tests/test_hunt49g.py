"""Hunt 49g: library refusals that told a Python caller to type a command-line option.

``cbr.training.append_plan(db, name, target="corect")`` was refused with "--target: ... its
cases cannot take --target corect": an option the caller never typed and cannot type. The
library names its arguments now, in its sentences too (`` `target='corect'` ``), and the
commands say them as their options (``posecbr.arguments.as_options``): the command lines'
words are those of before.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from features.errors import PosecbrError
from posecbr.arguments import said_as_options
from tests.badinput import refused, small_case_base

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _refusal(call: object) -> PosecbrError:
    with pytest.raises(PosecbrError) as raised:
        call()  # type: ignore[operator]
    return raised.value


def test_arguments_named_in_a_sentence_are_said_as_the_options_given() -> None:
    """Each form, worked out by hand from the option each argument maps to."""
    options = {"k": "--k", "target": "--target", "new_label": "--new-label", "jobs": "--jobs"}
    assert said_as_options("give `k=6` or less", options) == "give --k 6 or less"
    assert said_as_options("cannot take `target='corect'`", options) == (
        "cannot take --target corect"
    )
    assert said_as_options('no value for `target="a b"`', options) == "no value for --target a b"
    assert said_as_options("pass `new_label=True` as well", options) == "pass --new-label as well"
    assert said_as_options("try fewer `jobs`", options) == "try fewer --jobs"
    # an argument the command has no option for stays in the library's words, as does text
    # that only looks like one (a value of the user's, unmarked)
    assert said_as_options("keep more with `trim`; jobs=2, k=3", options) == (
        "keep more with `trim`; jobs=2, k=3"
    )


def test_append_plan_names_its_arguments_and_train_says_its_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A target the case base does not predict, cases of another kind, a store of several
    case bases with no name: the Python call is told of ``target``, ``cases`` and ``name``
    (before: "--target", "--split", "--name"); ``train --append`` and ``classify`` say the
    options, word for word as before."""
    from casebase_store import open_store
    from cbr.training import append_plan

    db = small_case_base(tmp_path)  # a case base "default" of whole clips, predicting labels
    exc = _refusal(lambda: append_plan(db, "default", target="corect"))
    assert exc.source == "target" and "--" not in str(exc), str(exc)
    assert str(exc) == (
        "target: case base 'default' predicts 'label', not 'corect': its cases cannot take"
        " `target='corect'`"
    )
    exc = _refusal(lambda: append_plan(db, "default", cases="windows"))
    assert exc.source == "cases" and "--" not in str(exc), str(exc)
    assert str(exc).endswith("not windows: add to it with `cases='clips'`"), str(exc)

    clip = next((tmp_path / "train").rglob("*.npz"))
    more = tmp_path / "more.csv"
    more.write_text(f"path,label\n{clip},x\n")
    argv = ["train", str(more), "--db", str(db), "--append"]
    refused([*argv, "--target", "corect"], tmp_path, capsys,
            "error: --target: case base 'default' predicts 'label', not 'corect': its cases"
            " cannot take --target corect")  # fmt: skip
    refused([*argv, "--split", "windows"], tmp_path, capsys,
            "error: --split: case base 'default' holds clips (trained with --split clips), not"
            " windows: add to it with --split clips")  # fmt: skip

    with open_store(db) as store:  # a second case base beside "default"
        whole = store.read_whole("default")
        with store.transaction() as tx:
            tx.copy_case_base(whole, "b")
        exc = _refusal(lambda: store.choose(None))
    assert str(exc).endswith("case bases b, default: choose one with `name`"), str(exc)
    refused(["classify", str(clip), "--db", str(db)], tmp_path, capsys,
            "case bases b, default: choose one with --name")  # fmt: skip


def test_a_refusal_of_an_argument_names_it_and_compare_says_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Stratified folds with a class of one clip in a group: the Python call is refused of
    ``cv`` (before: of "--cv kfold", an option and its value), ``compare`` says "--cv"; and
    an empty store path is refused of ``url_or_path`` (before: "--db"), ``classify`` and
    ``train --append`` say "--db" as before."""
    from casebase_store import open_store
    from cbr.evaluation.compare import run_compare
    from cbr.evaluation.settings import CompareSettings
    from features.datasets import load_dataset

    # subject s0 has one clip of each class, s1 the other: within a subject, a single clip
    names = [*sorted(DEMO.glob("m01_s01_*.npz"))[:2], *sorted(DEMO.glob("m07_s01_*.npz"))[:2]]
    labels = ["a", "a", "b", "b"]
    rows = [f"{p},{lab},s{i % 2}" for i, (p, lab) in enumerate(zip(names, labels, strict=True))]
    csv = tmp_path / "one.csv"
    csv.write_text("path,label,subject\n" + "\n".join(rows) + "\n")
    settings = CompareSettings(cv="kfold", folds=2, k=1, within="subject",
                               similarities=("euclidean",), features=("fluents",), peers=(),
                               dad=False, explain=0)  # fmt: skip
    exc = _refusal(lambda: run_compare(load_dataset(csv), settings))
    assert exc.source == "cv" and "--" not in str(exc), str(exc)
    argv = ["compare", str(csv), "--cv", "kfold", "--folds", "2", "--k", "1", "--within",
            "subject", "--similarities", "euclidean", "--features", "fluents", "--peers",
            "none", "--no-dad", "--explain", "0", "--json", str(tmp_path / "r.json")]  # fmt: skip
    refused(argv, tmp_path, capsys, "error: --cv: a class has a single clip in some group")

    exc = _refusal(lambda: open_store(""))
    assert str(exc) == "url_or_path: is empty: name a case base file (SQLite) or a SQLAlchemy URL"
    for command in (["classify", str(names[0])], ["train", str(csv), "--append"]):
        refused([*command, "--db", ""], tmp_path, capsys,
                "error: --db: is empty: name a case base file")  # fmt: skip


def test_a_margin_judge_refused_advises_judge_ofs_name_and_segment_says_unknown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base of two activities cannot calibrate a margin judge: ``judge_of(clf,
    "spread-margin")`` advises its own ``name='held-out'`` (before: "use --unknown held-out",
    an option of a command the caller never ran); ``segment`` says "--unknown held-out" as
    before."""
    import numpy as np

    from cbr.estimator import CaseBaseClassifier
    from cbr.training import store_fitted
    from cbr.unknown import judge_of
    from features.poses import PoseSequence, save_pose
    from tests.test_cbr_clips import arm_dataset

    X, y = arm_dataset(3, seed=3)
    two = sorted(set(y.tolist()))[:2]
    keep = [i for i, v in enumerate(y.tolist()) if v in two]
    clips, labels = [X[i] for i in keep], [str(y[i]) for i in keep]
    clf = CaseBaseClassifier(k=1).fit(clips, labels)
    exc = _refusal(lambda: judge_of(clf, "spread-margin"))
    assert "use `name='held-out'`" in str(exc) and "--" not in str(exc), str(exc)

    db = tmp_path / "two.sqlite"
    store_fitted(db, "two", clf, labels)
    rec = save_pose(PoseSequence(np.concatenate([c.positions for c in clips]),
                                 clips[0].joint_names, 30.0), tmp_path / "r.npz")  # fmt: skip
    refused(["segment", str(rec), "--db", str(db)], tmp_path, capsys,
            "fewer than three activities", "(use --unknown held-out, or train with")  # fmt: skip
