"""A robot engineer's walkthrough of the Python API (hunt 35h): clips given as arrays from
the engineer's own pose tracker, no file behind them."""

from __future__ import annotations

import csv
import pickle
import re
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from casebase_store import StoreError, open_store
from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from cbr.segmentation import segment
from cbr.stored import load_classifier
from cbr.training import train
from cbr.unknown import held_out_basis, judge_of
from features.errors import DataError
from features.fluents import evaluate
from features.poses import PoseSequence, load_pose
from features.skeleton import BLAZEPOSE_33
from tests.badinput import refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
ACTIVITIES = ("deep_squat", "hurdle_step", "standing_shoulder_abduction")


# on one xdist worker: the module's arrays, in_memory, two_activities made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt35h")


@pytest.fixture(scope="module")
def arrays() -> tuple[list[PoseSequence], list[str]]:
    """Every third clip of three demo activities, as a tracker's arrays: no source, no
    metadata (what ``PoseSequence(array, names, fps)`` of a user's own numbers is)."""
    with open(DEMO / "labels.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["label"] in ACTIVITIES][::3]
    xyz = [load_pose(DEMO / r["path"]).to_canonical().positions for r in rows]
    return [PoseSequence(a, BLAZEPOSE_33, 30.0) for a in xyz], [r["label"] for r in rows]


@pytest.fixture(scope="module")
def in_memory(arrays: tuple[list[PoseSequence], list[str]]) -> CaseBaseClassifier:
    X, y = arrays
    return CaseBaseClassifier(k=3, mirror=False).fit(X, y)


def test_an_explanation_names_a_case_of_arrays_by_its_position_not_a_question_mark(
    arrays: tuple[list[PoseSequence], list[str]], in_memory: CaseBaseClassifier
) -> None:
    """Fitted from arrays, every case's source is empty: the explanation said "Nearest case
    of this label ?; of another label ?." Now a case is named by its row of ``case_base_``. A
    training clip's nearest case of its own label is itself (distance 0 but for the float32
    search's rounding): clip i is case i (no mirror images, no trimming: one case per clip,
    in order)."""
    X, y = arrays
    cb = in_memory.case_base_
    assert list(in_memory.case_origin_) == list(range(len(X)))
    for i in (0, 4, len(X) - 1):
        exp = in_memory.explain([X[i]])[0]
        assert "?" not in exp.text, exp.text
        near = re.search(r"Nearest case of this label case (\d+); of another label case (\d+)\.",
                         exp.text)  # fmt: skip
        assert near is not None, exp.text
        assert int(near.group(1)) == i
        other = int(near.group(2))
        assert str(cb.labels[other]) != y[i]
        assert exp.contrast is not None and exp.contrast.position == other
        # the neighbours say where they are in the case base, as the contrast does
        first = exp.neighbours[0]
        assert first["case_id"] == -1 and first["position"] == i and first["distance"] < 0.1
        for n in exp.neighbours:
            assert str(cb.labels[n["position"]]) == n["label"]
        assert f"\n  case {i} {y[i]}  distance " in exp.verbose


def test_a_stored_case_of_arrays_is_named_by_its_id_alone(
    arrays: tuple[list[PoseSequence], list[str]], tmp_path: Path
) -> None:
    """Stored, such a case was "#1 (?)"; now "#1": there is no file to name."""
    X, y = arrays
    db = tmp_path / "cb.sqlite"
    train(db, "default", X, y, CaseBaseClassifier(k=3, mirror=False))
    with open_store(db, create=False, readonly=True) as store:
        clf = load_classifier(store, "default").classifier
    exp = clf.explain([X[0]])[0]
    assert "?" not in exp.text, exp.text
    near = re.search(r"Nearest case of this label #(\d+); of another label #(\d+)\.", exp.text)
    assert near is not None, exp.text
    assert exp.neighbours[0]["case_id"] == int(near.group(1))
    assert exp.neighbours[0]["distance"] < 0.1


@pytest.mark.parametrize(
    ("url", "hint"),
    [
        (
            "postgres://robot@localhost:1/poses",
            "write postgresql:// (SQLAlchemy's name), not postgres://",
        ),
        (
            "postgres+psycopg://robot@localhost:1/poses",
            "write postgresql+psycopg:// (SQLAlchemy's name), not postgres+psycopg://",
        ),
        ("SQLITE:///cb.sqlite", "write the scheme in lower case, sqlite://"),
        ("Postgresql://robot@localhost:1/poses", "write the scheme in lower case, postgresql://"),
    ],
)
def test_a_database_url_sqlalchemy_has_no_dialect_for_says_what_to_write(
    url: str,
    hint: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``postgres://`` (a DATABASE_URL as Heroku and many a container write it; SQLAlchemy
    1.4 dropped the name) was "cannot use database URL (Can't load plugin:
    sqlalchemy.dialects:postgres)" and nothing more; a scheme in capitals the same. Now the
    one line says what to write, from Python and from the command alike; nothing is made."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(StoreError, match="cannot use database URL") as info:
        open_store(url)
    assert str(info.value).endswith(hint)
    assert info.value.source is not None and "://" in info.value.source
    refused(["casebase", "info", "--db", url], tmp_path, capsys, hint)
    assert list(tmp_path.iterdir()) == []


@pytest.fixture(scope="module")
def two_activities(
    arrays: tuple[list[PoseSequence], list[str]],
) -> tuple[CaseBaseClassifier, PoseSequence]:
    """A classifier of two activities (a robot's "squat" or "hurdle step") and a recording of
    four of its squats, as arrays."""
    X, y = arrays
    keep = [i for i, label in enumerate(y) if label != "standing_shoulder_abduction"]
    clf = CaseBaseClassifier(k=3).fit([X[i] for i in keep], [y[i] for i in keep])
    squats = [X[i].positions for i in keep if y[i] == "deep_squat"][:4]
    return clf, PoseSequence(np.concatenate(squats), BLAZEPOSE_33, 30.0)


def test_segmenting_with_two_activities_by_default_says_the_python_call_that_judges_it(
    two_activities: tuple[CaseBaseClassifier, PoseSequence],
) -> None:
    """``segment(clf, rec)`` and ``LiveSegmenter(clf, fps)`` of a case base of two activities
    refused it advising "use --unknown held-out", an option of a command the Python caller
    never ran. Now the same DataError says the call; made as it says, both work."""
    clf, rec = two_activities
    call = 'pass judge=cbr.unknown.judge_of(clf, "held-out")'
    for make in (lambda: segment(clf, rec), lambda: LiveSegmenter(clf, rec.fps)):
        with pytest.raises(DataError, match="fewer than three activities") as info:
            make()
        assert call in str(info.value) and "--unknown" not in str(info.value)
        assert info.value.source == "case base"
    judge = judge_of(clf, "held-out")
    done = segment(clf, rec, judge)
    assert done.segments[0].start_frame == 0 and done.segments[-1].end_frame == rec.n_frames
    live = LiveSegmenter(clf, rec.fps, judge)
    finished = [s for frame in rec.positions for s in live.push(frame)] + live.finish()
    assert finished[0].start_frame == 0 and finished[-1].end_frame == rec.n_frames


def test_live_push_says_the_frame_it_takes_and_how_a_z_up_frame_is_turned() -> None:
    """``LiveSegmenter.push`` said "one frame (33, 3)" alone: not which joints in which order,
    nor metres, nor y up. A robot engineer's z-up (ROS) frames were read as given, every
    upright torso as one tilted forward, nothing said. The docstring now says the frame, and
    the turn it gives, ``(x, y, z)`` to ``(x, z, -y)``, gives back the y-up fluents exactly."""
    doc = LiveSegmenter.push.__doc__ or ""
    for words in ("BLAZEPOSE_33", "metres", "y up", "``(x, y, z)`` to ``(x, z, -y)``"):
        assert words in " ".join(doc.split()), words
    upright = load_pose(DEMO / "m01_s01_e01.npz").to_canonical().positions
    y_up = evaluate(PoseSequence(upright, BLAZEPOSE_33, 30.0))
    x, y, z = upright[..., 0], upright[..., 1], upright[..., 2]
    z_up = np.stack([x, -z, y], axis=-1)  # ROS: the same person, gravity along -z
    as_given = evaluate(PoseSequence(z_up, BLAZEPOSE_33, 30.0))
    turned = np.stack([z_up[..., 0], z_up[..., 2], -z_up[..., 1]], axis=-1)
    assert np.allclose(turned, upright, equal_nan=True)
    column = y_up.state_names.index("torso_tilted_forward.tilted_forward")
    start = slice(0, 10)  # a deep squat starts standing
    assert np.nanmean(y_up.confidence[start, column]) < 0.1
    assert np.nanmean(as_given.confidence[start, column]) > 0.9
    again = evaluate(PoseSequence(turned, BLAZEPOSE_33, 30.0))
    assert np.allclose(again.confidence, y_up.confidence, equal_nan=True, atol=1e-9)


def _readme_block(first: str) -> str:
    """The README's ```python block holding the line ``first``, as written."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    at = text.index(first)
    start = text.rindex("```python\n", 0, at) + len("```python\n")
    return text[start : text.index("```", at)]


def test_the_readme_example_of_a_trackers_arrays_runs_as_written(
    arrays: tuple[list[PoseSequence], list[str]],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The README showed fitting from Python but not how to store a classifier fitted from
    one's own arrays, nor that the model loaded back may outlive its file. Its example, run
    as written on the demo clips' arrays, stores a case base and answers from it; moved, the
    file is not needed; pickled and in two threads, the model answers the same."""
    X, y = arrays
    monkeypatch.chdir(tmp_path)
    names: dict[str, object] = {"recordings": [s.positions for s in X], "labels": y, "fps": 30.0}
    exec(_readme_block("X = [PoseSequence(xyz, BLAZEPOSE_33, fps)"), names)
    shown = capsys.readouterr().out
    assert shown.startswith(f"['{y[0]}']") and "#" in shown and "?" not in shown
    clf = names["clf"]
    assert isinstance(clf, CaseBaseClassifier)
    (tmp_path / "robot.sqlite").rename(tmp_path / "elsewhere.sqlite")
    expected = clf.predict(X).tolist()
    assert sum(a == b for a, b in zip(expected, y, strict=True)) >= 0.8 * len(y)
    assert pickle.loads(pickle.dumps(clf)).predict(X).tolist() == expected
    halves: dict[int, list[str]] = {}

    def answer(i: int) -> None:
        halves[i] = clf.predict(X[i::2]).tolist()

    workers = [threading.Thread(target=answer, args=(i,)) for i in (0, 1)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    assert halves[0] == expected[0::2] and halves[1] == expected[1::2]


def test_the_default_judge_calibrates_on_clips_given_as_arrays_as_on_files(
    arrays: tuple[list[PoseSequence], list[str]], tmp_path: Path
) -> None:
    """Fitted from arrays (no source), every clip was taken for a stretch of one recording,
    all starting at frame 0 and so overlapping each other: holding one out left out every
    case, and the default judge refused a case base of three activities, nine clips each
    ("no activity has cases apart from each other ... (use --unknown held-out ...)"), so
    ``segment`` and ``LiveSegmenter`` refused it and ``train`` stored it without its judges.
    Now such a clip is a recording of its own: the judge is the one calibrated on the same
    clips each read from a file of its own."""
    X, y = arrays
    files = [
        PoseSequence(s.positions, BLAZEPOSE_33, s.fps, source=f"rec{i}.npz")
        for i, s in enumerate(X)
    ]
    bare = CaseBaseClassifier(k=3).fit(X, y)
    named = CaseBaseClassifier(k=3).fit(files, y)
    basis, groups = held_out_basis(bare.case_base_)
    assert basis == "recording" and len(set(groups.tolist())) == len(X)
    want = judge_of(named, "spread-margin").to_dict()  # type: ignore[attr-defined]
    assert judge_of(bare, "spread-margin").to_dict() == want  # type: ignore[attr-defined]
    recording = PoseSequence(np.concatenate([s.positions for s in X[:6]]), BLAZEPOSE_33, 30.0)
    done = segment(bare, recording)
    assert done.segments[-1].end_frame == recording.n_frames
    stored = train(tmp_path / "cb.sqlite", "default", X, y, CaseBaseClassifier(k=3))
    assert stored.judges_unknown


@pytest.mark.parametrize(
    ("code", "kind"),
    [
        ({"deep_squat": True, "hurdle_step": False, "standing_shoulder_abduction": False}, "b"),
        ({"deep_squat": 10, "hurdle_step": 2, "standing_shoulder_abduction": 9}, "i"),
        ({"deep_squat": 1.0, "hurdle_step": 2.0, "standing_shoulder_abduction": 10.0}, "f"),
    ],
)
def test_a_model_trained_on_labels_that_are_not_text_answers_with_them_once_loaded(
    arrays: tuple[list[PoseSequence], list[str]], tmp_path: Path, code: dict[str, Any], kind: str
) -> None:
    """A robot's labels are often numbers or true/false ("was the squat correct"). Trained
    with ``cbr.training.train`` the classifier was fitted on their text, and loaded back it
    answered "True" (or "10", "10.0"), not True: ``score(X, y)`` raised scikit-learn's "Mix of
    label input types (string and number)" where the classifier fitted in memory scored 1.0.
    (Whole numbers came back as numbers from ``store_fitted`` only.) Now the loaded model's
    classes are the labels as given, in their order, and it answers as the one fitted in
    memory does."""
    X, names = arrays
    y = [code[n] for n in names]
    in_memory = CaseBaseClassifier(k=3).fit(X, y)
    train(tmp_path / "cb.sqlite", "default", X, y, CaseBaseClassifier(k=3))
    with open_store(tmp_path / "cb.sqlite", create=False, readonly=True) as store:
        loaded = load_classifier(store, "default").classifier
    assert loaded.classes_.tolist() == sorted(set(y))
    assert loaded.classes_.dtype.kind == kind
    answers = loaded.predict(X)
    assert answers.tolist() == in_memory.predict(X).tolist()
    assert all(type(a) is type(y[0]) for a in answers.tolist())
    assert loaded.score(X, y) == in_memory.score(X, y) > 0.9
