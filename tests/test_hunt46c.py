"""Hunt 46c: commands used as a new user would (casebase, report, describe, dad, thresholds,
convert, the library API), each defect's test failing on the code before its fix."""

from __future__ import annotations

import json
import math
import re
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from features.qmp.add import Condition, _failure_text
from posecbr.cli import main
from tests.badinput import refused
from tests.test_classify_output import data_and_stores  # noqa: F401 (a fixture, made once)

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_a_failed_condition_reads_failed_however_near_its_bound() -> None:
    # The squat depth's bound, 2.0 rad = 114.59°, and a knee at 114.8° (2.0036 rad): at three
    # digits both read "115°", "at most 115° (observed 115°)", a condition met by its words.
    knee = Condition("right_knee", "mean", max=2.0)
    assert math.degrees(2.0036) == pytest.approx(114.80, abs=0.005)
    text = _failure_text(knee, [np.array([2.0036])], 0)
    assert text == "right knee mean at most 114.6° (observed 114.8°)"
    # far from it, the usual three digits
    assert (
        _failure_text(knee, [np.array([2.5])], 0) == "right knee mean at most 115° (observed 143°)"
    )
    low = Condition("torso_sagittal", "min", min=0.7)  # 40.107°
    assert _failure_text(low, [np.array([0.6995])], 0) == (
        "torso sagittal min at least 40.11° (observed 40.08°)"
    )


def test_dad_never_shows_a_failed_bound_and_its_value_alike(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # The bundled s02 sit-to-stand: its right armpit's mean, just past the 2.0-rad bound of
    # "arms kept within about 115 degrees of the torso", read "at most 115° (observed 115°)".
    assert main(["dad", str(DEMO / "m05_s02_e01_inc.npz"), "--top", "0"]) == 0
    needs = re.findall(
        r"needs .* (?:at most|at least) (\S+) \(observed (\S+)\)", capsys.readouterr().out
    )
    assert len(needs) > 20
    assert all(bound != seen for bound, seen in needs), [n for n in needs if n[0] == n[1]]


def test_convert_names_the_movements_when_one_asked_is_not_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # "m1" for m01: refused as a subject no clip has is, naming the movements there; it was
    # "no clips matched (check the filters)", and "m01,m7" converted m01 alone in silence.
    held = "its movements are m01, m02, m03, m04, m05, m06, m07, m08, m09 and m10"
    out = tmp_path / "out"
    refused(["convert", str(DEMO), "--out", str(out), "--movements", "m1"], tmp_path, capsys,
            "--movements: no clip of movement 'm1' in", held)  # fmt: skip
    argv = ["convert", str(DEMO / "labels.csv"), "--out", str(out), "--subjects", "s01"]
    refused([*argv, "--movements", "m01,m7"], tmp_path, capsys, "movement 'm7'", held)
    assert main([*argv, "--movements", "m01,m07"]) == 0  # both there: 12 clips, 6 of each
    rows = (out / "labels.csv").read_text().splitlines()[1:]
    assert sorted({r.split(",")[5] for r in rows}) == ["m01", "m07"] and len(rows) == 12


def test_convert_uiprmd_movement_typo_named(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["convert", str(shared_data / "ui-prmd"), "--out", str(tmp_path / "o")]
    refused([*argv, "--movements", "m11", "--subjects", "s01"], tmp_path, capsys,
            "no clip of movement 'm11'", "m09 and m10")  # fmt: skip


def test_casebase_info_gives_the_phase_means_fit_chose(
    data_and_stores: tuple[tuple[Path, Path], dict[str, str]],  # noqa: F811
    capsys: pytest.CaptureFixture[str],
) -> None:
    # Trained with --phases auto (the default): info --json gave the parameter, "auto", beside
    # the side handling and feature weights fit chose; the classifier uses a number.
    from casebase_store import open_store
    from cbr.stored import load_classifier

    db = data_and_stores[1]["label"]
    with open_store(db, readonly=True) as store:
        clf = load_classifier(store, "default").classifier
    assert clf.get_params()["phases"] == "auto" and isinstance(clf.phases_, int)
    assert main(["casebase", "info", "--db", db, "--json"]) == 0
    model = json.loads(capsys.readouterr().out)["case_bases"][0]["model"]
    assert model["phases"] == clf.phases_
    assert (model["side"], model["feature_weights"]) == (clf.side_, clf.weighting_)


def test_a_bad_similarity_parameter_value_is_named_as_the_parameter_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # band=-1 came from --param (similarity_params) but was blamed on --similarity (on
    # "similarity dtw" in Python), the option (parameter) the user had right.
    from cbr.estimator import CaseBaseClassifier
    from features.errors import ParameterError
    from features.poses import load_pose

    argv = ["train", str(DEMO / "labels.csv"), "--db", str(tmp_path / "cb.sqlite")]
    refused([*argv, "--similarity", "dtw", "--param", "band=-1"], tmp_path, capsys,
            "error: --param: band must be in [0, 1], got -1")  # fmt: skip
    refused([*argv, "--similarity", "dwt", "--param", "band=0.2"], tmp_path, capsys,
            "error: --similarity: unknown similarity 'dwt'")  # fmt: skip
    clips = [load_pose(DEMO / f"m0{m}_s01_e01.npz") for m in (1, 5)]
    with pytest.raises(ParameterError) as raised:
        CaseBaseClassifier(similarity="dtw", similarity_params={"band": -1}).fit(clips, ["a", "b"])
    assert str(raised.value) == "similarity_params: band must be in [0, 1], got -1"
    with pytest.raises(ParameterError, match=r"^similarity_params: similarity 'euclidean' has no"):
        CaseBaseClassifier(similarity_params={"band": 0.2}).fit(clips, ["a", "b"])


def test_report_and_compare_refuse_to_write_over_a_pose_file_or_a_case_base(
    compared_three: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # `report cmp --out poses/squat.npz` (a slip for report.html) replaced the recording by
    # an HTML page, exit 0, and `compare --json`/`--csv` one by the results once the run was
    # done; casebase export refuses such a file, and so do they now, before any work.
    pose = tmp_path / "m01_s01_e01.npz"
    pose.write_bytes((DEMO / "m01_s01_e01.npz").read_bytes())
    refused(["report", str(compared_three), "--out", str(pose)], tmp_path, capsys,
            f"{pose}: is a pose file: the report would replace that recording")  # fmt: skip
    for flag in ("--json", "--csv"):
        refused(["compare", str(DEMO), "--labels", "deep_squat,sit_to_stand", flag, str(pose)],
                tmp_path, capsys, f"{pose}: is a pose file: the ")  # fmt: skip
    store = tmp_path / "cb.sqlite"  # any SQLite database: a case base file, as likely
    with sqlite3.connect(store) as con:
        con.execute("CREATE TABLE case_bases (id INTEGER)")
    refused(["report", str(compared_three), "--out", str(store)], tmp_path, capsys,
            f"{store}: is a SQLite database (a case base file?): the report would")  # fmt: skip
    refused(["compare", str(DEMO), "--json", str(store)], tmp_path, capsys, "is a SQLite database")
    # no pose file there: refused as any name but an HTML page's is (hunt 47c)
    refused(["report", str(compared_three), "--out", str(tmp_path / "r.npz")], tmp_path, capsys,
            "r.npz: the report is an HTML page: name it .html or .htm (got '.npz')")  # fmt: skip


def test_a_mistyped_fluent_in_a_thresholds_file_gets_a_guess(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # "unknown fluent 'leg_bnt'" alone, where --similarity dwt and the rest get a guess
    t = tmp_path / "t.json"
    t.write_text('{"fluents": {"leg_bnt": {"lower": {"tau": 2.0}}}}')
    refused(["thresholds", "--from", str(t)], tmp_path, capsys,
            f"{t}: unknown fluent 'leg_bnt' (did you mean 'leg_bent'?)")  # fmt: skip


def test_casebase_info_says_the_vote_is_balanced_by_class(
    data_and_stores: tuple[tuple[Path, Path], dict[str, str]],  # noqa: F811
    capsys: pytest.CaptureFixture[str],
) -> None:
    # train --target correct votes each case divided by its class's share of the cases
    # (class_weight="balanced"); info said "k = 5, distance vote" alone, as of a plain vote.
    from casebase_store import open_store
    from cbr.stored import load_classifier

    for target, weight in (("correct", "balanced"), ("label", "none")):
        db = data_and_stores[1][target]
        with open_store(db, readonly=True) as store:
            assert load_classifier(store, "default").classifier.class_weight == weight
        assert main(["casebase", "info", "--db", db, "--json"]) == 0
        assert (
            json.loads(capsys.readouterr().out)["case_bases"][0]["model"]["class_weight"] == weight
        )
        assert main(["casebase", "info", "--db", db]) == 0
        vote = "distance vote, balanced by class;" if weight == "balanced" else "distance vote;"
        assert f"k = 5, {vote} side handling" in capsys.readouterr().out


@pytest.mark.parametrize(("name", "why"), [("", "the case base name is empty"),
                                           ("x\x00y", "contains a NUL character")])  # fmt: skip
def test_train_in_python_names_its_name_argument(tmp_path: Path, name: str, why: str) -> None:
    # cbr.training.train(db, "", ...) raised ConfigError("--name: ..."): the command's option,
    # not the argument, and no ValueError, unlike its other arguments' InputError
    from cbr.estimator import CaseBaseClassifier
    from cbr.training import train
    from features.errors import InputError

    with pytest.raises(InputError, match=f"^name: .*{why}"):
        train(tmp_path / "cb.sqlite", name, [], [], CaseBaseClassifier())
    assert list(tmp_path.iterdir()) == []
