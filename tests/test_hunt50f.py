"""Hunt 50f: posecbr used as a library, as a robotics engineer would.

- the four packages are typed (``py.typed``), so ``mypy --strict`` checks a user's script
  calling them rather than skipping them ("missing library stubs or py.typed marker");
- a store used after its ``with`` block is refused as closed: it connected again, and where
  its SQLite file had been deleted meanwhile made an empty one of that name; a write to a
  file deleted while the store was open is said as such, not "a readonly database";
- ``segment``, ``LiveSegmenter`` and ``judge_of`` given ``load_classifier``'s
  ``StoredClassifier`` (or None) in place of its classifier say so, naming ``clf``, where
  they said it was "not fitted yet: call 'fit'";
- ``cut_recording`` takes label codes of a float type (``np.loadtxt``'s), where 6.0 was
  refused as "not a whole number", and says a NaN is a missing label.
"""

from __future__ import annotations

import copy
import pickle
import re
import tomllib
import typing
from collections.abc import Iterable
from dataclasses import replace
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

from casebase_store import StoreError, open_store
from cbr.dad.classifier import DADClassifier
from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from cbr.segmentation import segment
from cbr.stored import load_classifier
from cbr.training import append, cut, cut_recording, store_fitted, train
from cbr.unknown import judge_of
from features.datasets import dataset_entries, load_clip, load_dataset
from features.errors import InputError, ParameterError
from features.pose_estimation import estimate_poses, open_video, stream_poses
from features.poses import PoseSequence, load_pose, save_pose
from tests.test_cbr_clips import arm_dataset

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("features", "casebase_store", "cbr", "posecbr")


# on one xdist worker: the module's arm_store made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt50f")


@pytest.fixture(scope="module")
def arm_store(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
    tmp_path_factory: pytest.TempPathFactory,
) -> Path:
    """``arm_k3``'s classifier stored as case base "arms" (not to be changed: copy it)."""
    clf, _, labels = arm_k3
    db = tmp_path_factory.mktemp("arm-store") / "arms.sqlite"
    store_fitted(db, "arms", clf, labels)
    return db


def test_every_package_is_typed() -> None:
    """PEP 561: a package's type hints are read by a type checker only when it ships a
    ``py.typed`` marker, installed with it."""
    for package in PACKAGES:
        assert files(package).joinpath("py.typed").is_file(), package
    with open(ROOT / "pyproject.toml", "rb") as f:
        package_data = tomllib.load(f)["tool"]["setuptools"]["package-data"]
    assert "py.typed" in package_data["*"]


@pytest.mark.parametrize("readonly", [True, False])
def test_a_store_used_after_it_is_closed_is_refused(
    arm_store: Path, tmp_path: Path, readonly: bool
) -> None:
    db = tmp_path / "cb.sqlite"
    db.write_bytes(arm_store.read_bytes())
    with open_store(db, readonly=readonly) as store:
        assert [i.name for i in store.list_case_bases()] == ["arms"]
    db.unlink()  # deleted (or moved) after the block: the store must not make it again
    for read in (store.list_case_bases, lambda: load_classifier(store, "arms")):
        with pytest.raises(StoreError, match=r"cb\.sqlite: the store is closed .*open_store"):
            read()
    assert list(tmp_path.iterdir()) == []


def test_a_write_to_a_file_deleted_while_open_says_so(arm_store: Path, tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    db.write_bytes(arm_store.read_bytes())
    with open_store(db) as store:
        whole = store.read_whole("arms")
        db.unlink()
        with pytest.raises(StoreError, match="deleted or moved while the store was open"):
            with store.transaction() as tx:
                tx.copy_case_base(whole, "copy")
    assert list(tmp_path.iterdir()) == []


def test_a_stored_classifier_for_its_classifier_is_named(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]], arm_store: Path
) -> None:
    """load_classifier's result holds the classifier: given whole, or None, the call says
    what ``clf`` must be (an InputError, a ValueError), not that it needs fitting."""
    _, rec, _ = arm_k3
    with open_store(arm_store, readonly=True) as store:
        stored = load_classifier(store, "arms")
    calls = {
        "segment": lambda clf: segment(clf, rec),
        "LiveSegmenter": lambda clf: LiveSegmenter(clf, rec.fps),
        "judge_of": lambda clf: judge_of(clf, "held-out"),
    }
    for name, call in calls.items():
        with pytest.raises(InputError, match=r"^clf: must be a fitted CaseBaseClassifier") as e:
            call(stored)
        assert "got a StoredClassifier (its .classifier, a CaseBaseClassifier, is one)" in str(
            e.value
        ), name
        with pytest.raises(InputError, match=r"^clf: .*, got None$"):
            call(None)
    judge_of(stored.classifier, "held-out")  # what it holds is one


def test_cut_recording_takes_codes_of_a_float_type(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """``np.loadtxt`` reads a label file's codes as floats (6.0): the same codes as integers
    cut the same stretches with the same names."""
    clf, rec, labels = arm_k3
    lengths = [x.n_frames for x in arm_dataset(3, seed=3)[0]]  # the clips laid end to end
    assert sum(lengths) == rec.n_frames
    names = {i + 1: str(c) for i, c in enumerate(clf.classes_)}
    codes = np.repeat([1 + list(clf.classes_).index(v) for v in labels], lengths)
    ends = np.cumsum(lengths)
    as_ints, int_labels = cut_recording(rec, codes, "clips", names=names)
    as_floats, float_labels = cut_recording(rec, codes.astype(np.float64), "clips", names=names)
    assert float_labels == int_labels == labels  # each clip of another movement than the last
    where = [(p.metadata["frame_offset"], p.n_frames) for p in as_floats]
    assert where == [(int(end - n), n) for end, n in zip(ends, lengths, strict=True)]
    assert [(p.metadata["frame_offset"], p.n_frames) for p in as_ints] == where
    gap = codes.astype(np.float64)
    gap[5] = np.nan
    with pytest.raises(InputError, match=r"^frame_labels: frame_labels\[5\] is nan: a label is"
                                         r" missing"):  # fmt: skip
        cut_recording(rec, gap, "clips", names=names)
    with pytest.raises(
        InputError, match=rf"frame_labels\[0\] is {codes[0] + 0.5}: a label is text"
    ):
        cut_recording(rec, codes + 0.5, "clips", names=names)


def test_append_takes_what_train_takes_and_refuses_a_set(arm_store: Path, tmp_path: Path) -> None:
    """``append``'s clips as ``train``'s: any ordered iterable (a generator was a raw
    TypeError, "has no len()"), not a set, whose order is not the labels' (it was taken, each
    clip stored under another's label as the set happened to order them)."""
    db = tmp_path / "cb.sqlite"
    db.write_bytes(arm_store.read_bytes())
    X, y = arm_dataset(1, seed=4)  # three clips the case base does not hold
    X = [replace(x, source=f"new{i}") for i, x in enumerate(X)]  # not "synthetic" frames 0-N
    labels = [str(v) for v in y]
    with pytest.raises(InputError, match=r"^clips: .*got a set .*its order is not the clips'"):
        append(db, "arms", set(X), labels)
    with pytest.raises(InputError, match=r"^clips: clips\[1\] is a ndarray, not a PoseSequence"):
        append(db, "arms", [X[0], X[1].positions], labels[:2])
    with open_store(db, readonly=True) as store:
        before = store.count_cases("arms")
    result = append(db, "arms", (x for x in X), labels)
    assert result.n_cases == len(X)
    with open_store(db, readonly=True) as store:
        assert store.count_cases("arms") == before + len(X)
        cases = store.load_cases("arms")
    assert list(cases.labels[-len(X) :]) == labels  # each clip under its own label


def test_train_names_its_own_arguments_and_takes_label_arrays(tmp_path: Path) -> None:
    """The estimator's refusal of one activity named its ``y``; ``train``'s is ``labels``.
    Its hints take what it takes: labels as an array, clips as any iterable."""
    X, _ = arm_dataset(1, seed=5)
    with pytest.raises(InputError, match=r"^labels: the training set has only one activity"):
        train(tmp_path / "cb.sqlite", "one", X, ["raise"] * len(X), CaseBaseClassifier())
    assert not (tmp_path / "cb.sqlite").exists()
    for function, argument in ((train, "labels"), (cut, "labels"), (append, "labels"),
                               (cut_recording, "frame_labels")):  # fmt: skip
        assert np.ndarray in typing.get_args(typing.get_type_hints(function)[argument])
    for function in (train, cut, append):
        assert typing.get_type_hints(function)["clips"] == Iterable[PoseSequence]


def test_states_of_the_wrong_kind_or_name_are_named() -> None:
    """``states``: a group's name or a list of column names. 5 or None was a raw TypeError
    ("'int' object is not iterable"), b"angles" the states 97, 110, ...; a mistyped name was
    found when the first clip was described and said of ``features``, as a stored case
    base's state the fluent table "no longer has"."""
    X, y = arm_dataset(1, seed=3)
    groups = "must be one of angles, instantaneous, all or a list of state names"
    for states in (5, None, b"angles", [5], {"left_arm_bent.bent": 1}):
        with pytest.raises(
            ParameterError, match=rf"^states: {groups}, got {re.escape(repr(states))}$"
        ):
            CaseBaseClassifier(states=states).fit(X, y)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=rf"^states: {groups}, got none$"):
        CaseBaseClassifier(states=()).fit(X, y)
    with pytest.raises(
        ParameterError,
        match=r"^states: no column of that name: 'left_arm_bent\.bnt', 'angle:left_kne' \(did you"
        r" mean 'left_arm_bent\.bent'\?\)$",
    ):
        CaseBaseClassifier(states=["left_arm_bent.bnt", "angle:left_kne"]).fit(X, y)


def test_a_masked_array_is_missing_where_masked() -> None:
    """A tracker's masked array: a masked joint is a lost one, NaN, not the value under the
    mask (``np.asarray`` keeps it: the joint was read where the tracker lost it). The array
    given is not changed."""
    X, _ = arm_dataset(1, seed=3)
    xyz = np.array(X[0].positions)
    mask = np.zeros(xyz.shape, dtype=bool)
    mask[3:9, 11] = True  # the left shoulder lost for six frames
    given = np.ma.masked_array(xyz.copy(), mask=mask)
    seq = PoseSequence(given, X[0].joint_names, X[0].fps)
    expected = xyz.copy()
    expected[3:9, 11] = np.nan
    np.testing.assert_array_equal(seq.positions, expected)
    np.testing.assert_array_equal(given.data, xyz)
    conf = np.ma.masked_array(np.ones(xyz.shape[:2]), mask=mask[..., 0])
    seen = PoseSequence(xyz, X[0].joint_names, X[0].fps, confidence=conf).confidence
    assert seen is not None and np.isnan(seen[3:9, 11]).all() and np.sum(np.isnan(seen)) == 6


def test_dad_refuses_a_set_of_clips() -> None:
    """``DADClassifier`` took a set of clips, its answers or labels in the set's order, not
    the clips' (``CaseBaseClassifier`` refused it already); its refusals said "X: X must"."""
    X, y = arm_dataset(1, seed=3)
    with pytest.raises(
        InputError, match=r"^X: must be a sequence .* got a set \(set\): its order is not the"
    ):
        DADClassifier().fit(set(X), y)
    with pytest.raises(InputError, match=r"^X: must be a sequence .* got a float64 array"):
        DADClassifier().fit(X[0].positions, y[:1])


def test_a_loaded_case_base_prints_in_a_few_lines(arm_store: Path) -> None:
    """``load_classifier``'s result printed (a notebook shows it) held its columns' names and
    words, its measure's weights and the whole model document: 523,611 characters for a case
    base of 80 cases; the case base's own repr every column name and word too."""
    with open_store(arm_store, readonly=True) as store:
        stored = load_classifier(store, "arms")
    text = repr(stored)
    assert "name='arms'" in text and f"n_cases={stored.info.n_cases}" in text
    for left_out in (
        "model=",
        "feature_names=",
        "feature_words=",
        "feature_config=",
        "similarity=",
    ):
        assert left_out not in text
    cb = stored.classifier.case_base_
    assert len(cb.names) > 100  # what its repr printed, with as many words
    assert repr(cb).startswith(f"CaseBase({len(cb.labels)} cases of 3 labels, problems ")
    assert len(repr(cb)) < 500 and "\n" not in repr(cb)
    assert len(text) < 2000


def test_a_store_is_not_pickled_saying_why(arm_store: Path) -> None:
    """A store given to a worker process: pickle said "Can't pickle local object
    'create_engine.<locals>.connect'"; the store is a connection, its file is what travels."""
    with open_store(arm_store, readonly=True) as store:
        for copy_of in (pickle.dumps, copy.deepcopy):
            with pytest.raises(
                StoreError, match=r"arms\.sqlite: a case base store is a connection"
            ):
                copy_of(store)
        assert [i.name for i in store.list_case_bases()] == ["arms"]  # still open, as it was


def test_train_to_no_store_makes_no_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``train(None, ...)`` (an unset variable) fitted, then stored the case base in a file
    named "None" and said it had been "stored before" an error naming ``url_or_path``."""
    monkeypatch.chdir(tmp_path)
    X, y = arm_dataset(1, seed=3)
    for db in (None, b"cb.sqlite", 5):
        with pytest.raises(
            StoreError, match=r"^db: a case base is a file path or a SQLAlchemy URL"
        ):
            train(db, "arms", X, y, CaseBaseClassifier())  # type: ignore[arg-type]
        with pytest.raises(StoreError, match=r"^db: "):
            append(db, "arms", X, y)  # type: ignore[arg-type]
    assert list(tmp_path.iterdir()) == []


def test_a_path_that_is_none_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An unset variable for a file: ``Path(None)``'s "expected str, bytes or os.PathLike
    object, not NoneType" (a raw TypeError), and ``stream_poses(None)`` "None: cannot open
    stream"; nothing is written ("None.npz")."""
    monkeypatch.chdir(tmp_path)
    X, _ = arm_dataset(1, seed=3)
    calls = {
        "path": (
            lambda p: save_pose(X[0], p),
            load_pose,
            load_clip,
            load_dataset,
            dataset_entries,
            open_video,
        ),
        "video_path": (estimate_poses,),
        "source": (stream_poses,),
    }
    for argument, functions in calls.items():
        for function in functions:
            for value in (None, 5.0):
                with pytest.raises(InputError, match=rf"^{argument}: must be a .*, got {value}$"):
                    function(value)
    assert list(tmp_path.iterdir()) == []


def test_solve_flag_is_true_or_false(
    arm_k3: tuple[CaseBaseClassifier, PoseSequence, list[str]],
) -> None:
    """``solve(X, flag="no")`` judged the flag all the same ("no" is truthy)."""
    clf, _, _ = arm_k3
    X, _ = arm_dataset(1, seed=6)
    for flag in ("no", 0, None):
        with pytest.raises(InputError, match=rf"^flag: must be True or False, got {flag!r}$"):
            clf.solve(X, flag=flag)  # type: ignore[arg-type]
    assert [s.unlike_cases for s in clf.solve(X, flag=False)] == [False] * len(X)
