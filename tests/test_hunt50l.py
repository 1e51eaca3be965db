"""Hunt 50l: small library loose ends left by hunts 50f (the library API) and 50g (stores
under stress).

- ``PoseSequence`` refuses an ``fps`` given as text ("30"), as ``LiveSegmenter`` does (no pose
  file stores it so: ``save_pose`` writes a float, and ``load_pose`` refuses text);
- ``explain(target=...)`` refuses a target it does not know (a mistyped "corect" was taken
  without a word), naming ``target`` and the values it takes;
- ``LiveSegmenter.push`` says ``world``, its argument, where it said "positions";
- a fitted measure (``clf.measure_``) and a ``FeatureConfig`` print in one line: their
  reprs held every learned weight and every state's name;
- ``casebase upgrade`` that failed partway (a file size limit reached as the conversion's
  pages spilled into the file) left the file changed and its journal beside it, read by
  every reader as a killed writer's: it now undoes the failed write as a store's
  transaction does.
"""

from __future__ import annotations

import copy
import inspect
import pickle
import re
import resource
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from cbr.live import LiveSegmenter
from features.errors import InputError, ParameterError, PoseFileError
from features.poses import PoseSequence, load_pose, save_pose
from features.skeleton import BLAZEPOSE_33
from posecbr.cli import main
from tests.test_explanations import _made_shallower, squats  # noqa: F401  (a fixture)
from tests.test_hunt37l import _scripted

V1_SQL = Path(__file__).with_name("fixtures") / "store_v1.sql"


def _v1_store_of_long_sources(db: Path) -> None:
    """A case base written by posecbr 0.1 (schema version 1, tests/fixtures/store_v1.sql) with
    500 cases more, each a copy of its first case with a source of 3,000 characters: the
    upgrade's index on the sources (new in schema 2) grows the file by some 1.5 MB, past the
    store's page cache (2 MB), so pages spill into the file before the upgrade ends."""
    con = sqlite3.connect(db)
    con.executescript(V1_SQL.read_text(encoding="utf-8"))
    assert con.execute("PRAGMA journal_mode = DELETE").fetchone() == ("delete",)
    cols = [c[1] for c in con.execute("PRAGMA table_info(cases)") if c[1] not in ("id", "source")]
    row = con.execute(f"SELECT {', '.join(cols)} FROM cases WHERE id = 1").fetchone()
    marks = ", ".join("?" * (len(cols) + 1))
    con.executemany(
        f"INSERT INTO cases ({', '.join(cols)}, source) VALUES ({marks})",
        [(*row, f"{i:03000d}") for i in range(500)],
    )
    con.commit()
    con.close()


def test_an_upgrade_past_a_file_size_limit_leaves_the_file_as_it_was(
    tmp_path: Path, file_size_limit: Callable[[int], None], capsys: pytest.CaptureFixture[str]
) -> None:
    # before: the file changed, its journal left beside it; every reader then said "its last
    # change was interrupted (the process writing it was killed)", of an upgrade that had
    # said its error and ended
    db = tmp_path / "old.sqlite"
    _v1_store_of_long_sources(db)
    before = db.read_bytes()
    file_size_limit(len(before) * 5 // 4)  # the upgraded file is some 1.6 times as large
    assert main(["casebase", "upgrade", "--db", str(db)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "a size limit such as `ulimit -f`" in err[0]
    assert db.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.sqlite"]
    file_size_limit(resource.RLIM_INFINITY)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert "converted from schema version 1 to 2" in capsys.readouterr().out


@pytest.mark.parametrize("fps", ["30", np.str_("30"), b"30"])
def test_a_frame_rate_given_as_text_is_refused(fps: object, tmp_path: Path) -> None:
    # before: taken, read as 30.0 ("30") or refused as "got b'30'" only for bytes that float()
    # cannot read; LiveSegmenter(clf, "30") was refused
    still = np.zeros((3, len(BLAZEPOSE_33), 3))
    with pytest.raises(PoseFileError, match=rf"^fps must be a number, got {re.escape(repr(fps))}$"):
        PoseSequence(still, BLAZEPOSE_33, fps)  # type: ignore[arg-type]
    # a pose file stores its rate as a number, read back as numpy reads it: taken as before
    save_pose(PoseSequence(still, BLAZEPOSE_33, 25), tmp_path / "p.npz")
    with np.load(tmp_path / "p.npz") as data:
        assert data["fps"].dtype == np.float64 and data["fps"].shape == ()
        assert PoseSequence(still, BLAZEPOSE_33, data["fps"]).fps == 25.0
    assert load_pose(tmp_path / "p.npz").fps == 25.0


def test_explain_refuses_a_target_it_does_not_know(
    squats: CaseBaseClassifier,  # noqa: F811
) -> None:
    # before: any text was taken; only "correct" changes the words, so "corect" (a repetition
    # check mistyped) was explained as activities without a word
    clip = _made_shallower()
    words = "'label', 'correct' or None (target_: the column the classifier was trained"
    with pytest.raises(ParameterError, match=r"^target: must be " + re.escape(words)) as err:
        squats.explain([clip], target="corect")
    assert str(err.value).endswith("got 'corect' (did you mean 'correct'?)")
    with pytest.raises(ParameterError, match=r"^target: .* got 5$"):
        squats.explain([clip], target=5)  # type: ignore[arg-type]
    # the column a classifier was trained to predict (a loaded one's, or set after fitting)
    # is taken: the words are the labels' own, as for "label"
    by_subject = copy.copy(squats)
    by_subject.target_ = "subject"
    assert by_subject.explain([clip], target="subject")[0].text == (
        squats.explain([clip], target="label")[0].text
    )


def test_a_pushed_frame_refused_names_push_s_argument() -> None:
    # before: "positions must have shape ...", "positions are None", "positions reach ..." of
    # an argument called world
    argument = list(inspect.signature(LiveSegmenter.push).parameters)[1]
    assert argument == "world"
    live = _scripted("robot")
    far = np.full((33, 3), 20_000.0)  # past the 10 km a pose file may hold
    with pytest.raises(
        InputError, match=rf"^robot: frame 0: {argument} reaches 2e\+04: not metres"
    ):
        live.push(far)
    with pytest.raises(InputError, match=rf"^robot: frame 0: {argument} is None: push a frame"):
        live.push(None)  # type: ignore[arg-type]
    assert live.n == 0


def test_a_fitted_measure_and_a_feature_config_print_in_one_line(
    squats: CaseBaseClassifier,  # noqa: F811
) -> None:
    # before: the measure's repr held its two learned weights of each column (812 columns:
    # 22,418 characters), the configuration's every state's name (6,079)
    measure, config = squats.measure_, squats.feature_config_
    columns = squats.case_base_.problems.shape[1]
    text = repr(measure)
    assert "\n" not in text and len(text) < 300
    assert text.startswith("Euclidean(exact=False, prune_min_cases=5000, prune_dims=0, centre=(")
    assert text.count(f", ... {columns} values)") == 2  # centre and multiplier
    states = len(config.states)
    assert states > 100
    text = repr(config)
    assert "\n" not in text and len(text) < 400
    assert text.startswith("FeatureConfig(level='fluents', length=32, states=('")
    assert f", ... {states} values), min_available=0.5" in text
    # equality and pickling as they were
    assert pickle.loads(pickle.dumps(measure)) == measure
    assert pickle.loads(pickle.dumps(config)) == config
    assert repr(squats.measure_.__class__()) == (
        "Euclidean(exact=False, prune_min_cases=5000, prune_dims=0, centre=None, multiplier=None)"
    )
