"""`posecbr compare` end to end on a slice of the bundled UI-PRMD subset (real Kinect clips
with known labels), its fallbacks and its errors."""

from __future__ import annotations

import csv
import html
import json
import math
from pathlib import Path

import numpy as np
import pytest

from cbr.evaluation.stats import wilson_interval
from features.body import POSITION_JOINTS
from posecbr.cli import main

# under pytest-xdist the module's tests run on one worker: the module's compare run is done once
pytestmark = pytest.mark.xdist_group("compare-cli")

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
# Three movements: two that look alike (deep squat and sit-to-stand both bend the knees and
# hips; the case base confuses some, so there are errors to explain) and shoulder abduction.
SLICE = "deep_squat,sit_to_stand,standing_shoulder_abduction"


@pytest.fixture(scope="module")
def run_slice(compared_slice: Path) -> tuple[Path, str]:
    """One comparison on 54 clips (3 movements x 3 subjects x 6), reused by several tests
    (made once in the session, for tests/test_report_chromium.py too: tests/conftest.py)."""
    return compared_slice, ""


def _labels() -> dict[str, dict[str, str]]:
    with open(DEMO / "labels.csv", newline="") as fh:
        return {row["path"]: row for row in csv.DictReader(fh)}


def test_compare_folds_are_subjects_and_figures_follow_from_predictions(
    run_slice: tuple[Path, str],
) -> None:
    out, _ = run_slice
    res = json.loads((out / "r.json").read_text())
    truth = _labels()
    clips = res["clips"]
    assert len(clips) == 54
    assert res["cv"]["scheme"] == "loso" and res["cv"]["n_folds"] == 3
    # Every clip's fold is its subject from labels.csv: leave-one-subject-out.
    by_fold: dict[int, set[str]] = {}
    for c, f in zip(clips, res["cv"]["fold_of_clip"], strict=True):
        row = truth[c["id"]]
        assert c["label"] == row["label"] and c["target"] == row["label"]
        by_fold.setdefault(f, set()).add(row["subject"])
    assert sorted(len(s) for s in by_fold.values()) == [1, 1, 1]
    names = [m["name"] for m in res["methods"]]
    assert names == ["cbr fluents/euclidean", "cbr fluents/dtw", "dad"]
    for m in res["methods"]:
        assert m["status"] == "ok", m
        pred = np.array(m["predictions"])
        true = np.array([c["target"] for c in clips])
        k = int((pred == true).sum())
        assert m["accuracy"] == pytest.approx(k / 54)
        assert m["accuracy_ci"] == pytest.approx(list(wilson_interval(k, 54)))
        for cls, pc in m["per_class"].items():
            sel = true == cls
            assert pc["n"] == 18
            assert pc["recall"] == pytest.approx(float((pred[sel] == cls).mean()))
        assert np.asarray(m["confusion"]).sum() == 54
        assert m["fit_s"] >= 0 and m["predict_s"] > 0
    cbr = res["methods"][0]
    # 36 training clips per fold; nothing is trimmed by default, so every training clip is a
    # case (the estimator may add each clip's mirror image as a second case).
    assert cbr["training_size"] == 36 and 36 <= cbr["case_base_size"] <= 72
    # Across unseen subjects the fluent case base and the ADD rules are far above chance (1/3)
    # on real clips (measured: 83 % and 94 %).
    assert cbr["accuracy"] >= 0.7
    assert res["methods"][2]["accuracy"] >= 0.8
    best = next(m for m in res["methods"] if m["name"] == res["best"])
    assert best["accuracy"] == max(m["accuracy"] for m in res["methods"])
    assert best["mcnemar_p"] == 1.0 and best["mcnemar_b"] == best["mcnemar_c"] == 0


def test_compare_writes_csv_pictures_and_explanations(run_slice: tuple[Path, str]) -> None:
    out, _ = run_slice
    with open(out / "r.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["method"] for r in rows][:2] == ["cbr fluents/euclidean", "cbr fluents/dtw"]
    assert "recall:deep_squat" in rows[0]
    res = json.loads((out / "o" / "results.json").read_text())
    pics = res["pictures"]
    files = [pics["accuracy"], pics["prevalence"]]
    files += [c["file"] for c in pics["confusion"]] + [t["file"] for t in pics["timelines"]]
    assert [t["activity"] for t in pics["timelines"]] == sorted(SLICE.split(","))
    for f in files:
        data = (out / "o" / f).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    prev = res["prevalence"]
    assert all(18 <= n <= 36 for n in prev["cases_initial"])  # 18 clips (+ mirror images)
    # the paper's figure shows fluent states, not joint angles or positions
    axes = ("to the left", "height", "forward")
    positions = {f"{j.replace('_', ' ')} {a}" for j in POSITION_JOINTS for a in axes}
    assert prev["features"] and not any(
        w.endswith(" angle") or w in positions for w in prev["features"]
    )
    # trimming keeps half of every activity's cases
    assert prev["cases_trimmed"] == [math.ceil(n / 2) for n in prev["cases_initial"]]
    best_cbr = max(res["methods"][:2], key=lambda m: (m["accuracy"], m["macro_f1"]))
    n_wrong = sum(not ok for ok in best_cbr["correct"])
    cbr_expl = [e for e in res["explanations"] if e["method"] != "dad"]
    assert len(cbr_expl) == min(2, n_wrong) > 0
    for e in cbr_expl:
        assert e["method"] == best_cbr["name"]
        assert e["true"] != e["predicted"] and e["predicted"] in e["text"]
    dad = next(m for m in res["methods"] if m["name"] == "dad")
    dad_expl = [e for e in res["explanations"] if e["method"] == "dad"]
    assert len(dad_expl) == min(2, sum(not ok for ok in dad["correct"])) > 0
    for e in dad_expl:
        # What DAD saw for its choice and for the true activity, QMP by QMP.
        assert e["true"] != e["predicted"]
        assert e["text"].startswith("DAD chose ") and "The true activity: " in e["text"]
        assert "met: " in e["text"]


def test_target_correct_trains_one_model_per_movement(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc = main([
        "compare", str(DEMO), "--labels", "deep_squat,standing_shoulder_abduction",
        "--target", "correct", "--similarities", "euclidean", "--features", "fluents",
        "--peers", "none", "--explain", "1", "--json", str(tmp_path / "c.json"),
    ])  # fmt: skip
    assert rc == 0
    out, err = capsys.readouterr()
    assert "dad skipped" in err and "does not predict 'correct'" in err
    res = json.loads((tmp_path / "c.json").read_text())
    assert res["dataset"]["classes"] == ["correct", "incorrect"]
    assert res["settings"]["within"] == "label"
    truth = _labels()
    for c in res["clips"]:
        assert c["target"] == ("correct" if truth[c["id"]]["correct"] == "true" else "incorrect")
    m = res["methods"][0]
    assert m["status"] == "ok" and set(m["predictions"]) <= {"correct", "incorrect"}
    # A per-movement model trains on one movement's clips of the other subjects (2 x 6 = 12);
    # the two movements' case bases are summed (each clip a case, maybe with its mirror image).
    assert m["training_size"] == 24 and 24 <= m["case_base_size"] <= 48
    # accuracy per movement, from the predictions and the clips' movements
    movement = np.array([truth[c["id"]]["label"] for c in res["clips"]])
    hit = np.array(m["predictions"]) == np.array([c["target"] for c in res["clips"]])
    assert set(m["per_group"]) == {"deep_squat", "standing_shoulder_abduction"}
    for g, v in m["per_group"].items():
        assert v["n"] == 18 and v["accuracy"] == pytest.approx(hit[movement == g].mean())
        assert v["ci"] == pytest.approx(list(wilson_interval(int(hit[movement == g].sum()), 18)))
        row = next(line for line in out.splitlines() if line.startswith(g + " "))
        assert row.split()[-1] == f"{100 * v['accuracy']:.1f}"
    assert "accuracy % per label (one model each):" in out
    # the wrong clip explained reads its answer as a repetition, and one judged incorrect
    # leads with what it did outside the correct repetitions' range
    assert not all(hit)  # correct vs incorrect is hard: 36 clips are not all right
    (x,) = [e for e in res["explanations"] if e["method"] != "dad"]
    first, second = x["text"].splitlines()[:2]
    if x["predicted"] == "incorrect":
        assert first.startswith("an incorrect repetition, confidence ")
        assert second.startswith("Done differently from correct repetitions: ")
    else:
        assert first.startswith("a correct repetition, confidence ")


def test_one_subject_falls_back_to_stratified_kfold_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc = main([
        "compare", str(DEMO), "--subjects", "s01", "--labels", SLICE, "--folds", "3",
        "--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers", "none",
        "--explain", "0", "--json", str(tmp_path / "one.json"),
    ])  # fmt: skip
    assert rc == 0
    err = capsys.readouterr().err
    assert "only one subject (s01), so leave-one-subject-out is impossible" in err
    assert "falling back to stratified 3-fold" in err
    res = json.loads((tmp_path / "one.json").read_text())
    assert res["cv"]["scheme"] == "kfold" and res["cv"]["n_folds"] == 3
    folds = np.array(res["cv"]["fold_of_clip"])
    labels = np.array([c["label"] for c in res["clips"]])
    for f in range(3):  # stratified: every fold holds 2 clips of each of the 3 movements
        assert sorted(np.unique(labels[folds == f], return_counts=True)[1]) == [2, 2, 2]


def test_class_with_one_clip_is_left_out_with_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = ["path,label,subject"]
    for s in ("s01", "s02", "s03"):
        for e in ("e01", "e02"):
            rows.append(f"{DEMO / f'm01_{s}_{e}.npz'},deep_squat,{s}")
            rows.append(f"{DEMO / f'm07_{s}_{e}.npz'},standing_shoulder_abduction,{s}")
    rows.append(f"{DEMO / 'm02_s01_e01.npz'},hurdle_step,s01")
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    rc = main([
        "compare", str(tmp_path / "labels.csv"), "--similarities", "euclidean",
        "--features", "fluents", "--no-dad", "--peers", "none", "--explain", "0",
        "--json", str(tmp_path / "r.json"),
    ])  # fmt: skip
    assert rc == 0
    assert "class hurdle_step has a single clip" in capsys.readouterr().err
    res = json.loads((tmp_path / "r.json").read_text())
    assert res["dataset"]["classes"] == ["deep_squat", "standing_shoulder_abduction"]
    assert res["dataset"]["n_clips"] == 12


@pytest.mark.parametrize("what", ["missing_csv", "empty_folder", "bad_target"])
def test_bad_input_gives_one_clear_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], what: str
) -> None:
    args = ["--similarities", "euclidean", "--features", "fluents", "--peers", "none"]
    if what == "missing_csv":
        rc = main(["compare", str(tmp_path / "labels.csv"), *args])
    elif what == "empty_folder":
        (tmp_path / "empty").mkdir()
        rc = main(["compare", str(tmp_path / "empty"), *args])
    else:
        rc = main(["compare", str(DEMO), "--labels", SLICE, "--target", "colour", *args])
    assert rc == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("posecbr compare: error: ")
    if what == "missing_csv":
        assert str(tmp_path / "labels.csv") in err[0]
    elif what == "empty_folder":
        assert str(tmp_path / "empty") in err[0]
    else:
        assert "'colour'" in err[0] and "correct" in err[0]  # names what exists


def test_report_from_json_beside_the_out_folder_shows_its_pictures(
    run_slice: tuple[Path, str], tmp_path: Path
) -> None:
    """r.json lies beside the --out folder o/: it names the pictures from its own folder
    ("o/accuracy.png"), and its report shows every picture of the run."""
    out, _ = run_slice
    assert main(["report", str(out / "r.json"), "--out", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text()
    # accuracy + confusion matrices (best, DAD) + prevalence + a timeline per activity
    assert page.count('src="data:image/png;base64,') == 1 + 2 + 1 + 3
    assert json.loads((out / "r.json").read_text())["pictures"]["accuracy"] == "o/accuracy.png"
    assert "cbr fluents/euclidean" in page


def test_report_from_json_only_draws_its_pictures(tmp_path: Path) -> None:
    out = tmp_path
    rc = main([
        "compare", str(DEMO), "--labels", "deep_squat,hurdle_step", "--subjects", "s01,s02",
        "--features", "fluents", "--similarities", "euclidean", "--peers", "none",
        "--json", str(out / "r.json"),
    ])  # fmt: skip
    assert rc == 0
    assert main(["report", str(out / "r.json"), "--out", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text()
    # accuracy + confusion matrices (best, DAD), no data-dependent pictures
    assert page.count('src="data:image/png;base64,') == 1 + 2
    assert "cbr fluents/euclidean" in page


def test_report_explains_with_the_short_text_and_a_checked_counterfactual(
    run_slice: tuple[Path, str], tmp_path: Path
) -> None:
    """The report's explanations are the short default text (at most four lines and 400
    characters): the answer, why, the nearest cases and the computed counterfactual toward
    the nearest other label, as `classify` prints them; `posecbr report` shows them whole."""
    out, _ = run_slice
    res = json.loads((out / "r.json").read_text())
    cbr_expl = [e for e in res["explanations"] if e["method"] != "dad"]
    assert cbr_expl
    assert main(["report", str(out / "r.json"), "--out", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text()
    for e in cbr_expl:
        lines = e["text"].splitlines()
        assert len(lines) <= 4 and len(e["text"]) <= 400
        assert lines[0].startswith(f"{e['predicted']}, confidence ")
        assert lines[1].startswith("Why: ")
        contrast = e["explanation"]["contrast"]
        # the nearest other label of a wrong answer among three movements is one of the two
        # others, and the search was run (an answer was checked), not skipped
        assert contrast["label"] in SLICE.split(",") and contrast["label"] != e["predicted"]
        assert contrast["answer"] in SLICE.split(",")
        if contrast["valid"]:
            assert lines[-1].startswith(f"To be {contrast['label']}")
            assert contrast["answer"] == contrast["label"] and 1 <= len(contrast["changes"]) <= 6
        else:
            assert lines[-1].startswith("No change of up to ")
        for line in lines:
            assert html.escape(line) in page


def test_report_rejects_a_file_that_is_not_compare_results(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "x.json").write_text('{"hello": 1}')
    assert main(["report", str(tmp_path / "x.json")]) == 1
    err = capsys.readouterr().err
    assert "not a `posecbr compare` results file" in err and "x.json" in err


def test_unknown_case_base_parameter_is_named(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", str(DEMO), "--param", "colour=blue"]) == 1
    err = capsys.readouterr().err
    assert "--param" in err and "colour" in err
