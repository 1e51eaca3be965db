"""posecbr train / classify / casebase from the command line, good and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from features.poses import load_pose, save_pose
from posecbr.cli import main
from tests.test_cbr_clips import ACTIVITIES, arm_dataset


def _write_classes(root: Path, n_per_class: int, seed: int) -> Path:
    X, y = arm_dataset(n_per_class, seed)
    for i, (seq, label) in enumerate(zip(X, y, strict=True)):
        save_pose(seq, root / str(label) / f"clip{i:02d}.npz")
    return root


# on one xdist worker: the module's dataset made once, not once per worker
pytestmark = pytest.mark.xdist_group("cbr_cli")


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp("cli")
    return _write_classes(base / "train", 5, 11), _write_classes(base / "test", 2, 12)


def _cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_train_classify_feedback_export_trim(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    train, test = dataset
    db = str(tmp_path / "cb.sqlite")
    code, out, err = _cli(
        capsys, "train", str(train), "--db", db, "--similarity", "dtw", "--param", "band=0.2"
    )
    assert code == 0, err
    assert "15 cases" in out and "3 activities" in out
    code, out, _ = _cli(capsys, "casebase", "info", "--db", db, "--json")
    info = json.loads(out)["case_bases"][0]
    assert info["labels"] == {a: 5 for a in ACTIVITIES}
    assert info["similarity"]["band"] == 0.2

    code, out, err = _cli(capsys, "classify", str(test), "--db", db)
    assert code == 0, err
    assert "accuracy: 100.0 % (6/6 labelled clips)" in out
    assert "\n  Why: " in out and "\n  To be " in out
    assert "6 clips: 6 classified; 0 unlike the stored cases." in out
    code, out, _ = _cli(capsys, "classify", str(test), "--db", db, "--json", "-k", "3")
    doc = json.loads(out)
    assert doc["accuracy"] == 1.0 and len(doc["results"]) == 6
    first = doc["results"][0]
    assert len(first["neighbours"]) == 3 and first["label"] in ACTIVITIES
    assert first["text"].startswith(first["label"])

    # feedback: a clip of the right-arm movement told to be the left-arm one -> revise/retain
    clip = sorted((test / ACTIVITIES[1]).glob("*.npz"))[0]
    code, out, err = _cli(capsys, "classify", str(clip), "--db", db, "--feedback", ACTIVITIES[0])
    assert code == 0, err
    assert "feedback:" in out
    store = open_store(db)
    log = store.maintenance_log("default")
    assert [e.action for e in log].count("retain") == 1
    origins = set(store.load_cases("default").origins)
    assert origins & {"retained", "revised"}

    code, out, _ = _cli(capsys, "casebase", "list", "--db", db, "--json")
    assert len(json.loads(out)["cases"]) == store.count_cases("default")

    npz = tmp_path / "cases.npz"
    code, out, _ = _cli(capsys, "casebase", "export", "--db", db, "--out", str(npz))
    with np.load(npz) as z:
        assert z["problems"].shape[0] == store.count_cases("default")
        assert z["problems"].shape[1] == 32
        assert set(z["labels"]) == set(ACTIVITIES)
        assert len(z["feature_words"]) == z["problems"].shape[2]

    before = store.count_cases("default")
    code, out, _ = _cli(capsys, "casebase", "trim", "--db", db, "--editor", "cnn", "--dry-run")
    assert code == 0 and "CNN:" in out and "dry run" in out
    assert store.count_cases("default") == before
    code, out, _ = _cli(capsys, "casebase", "trim", "--db", db, "--keep", "0.6", "--json")
    rep = json.loads(out)
    assert rep["size_before"] == before and rep["size_after"] < before
    assert store.count_cases("default") == rep["size_after"]


def test_bad_input_one_line_errors(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    train, test = dataset
    db = str(tmp_path / "cb.sqlite")
    assert _cli(capsys, "train", str(train), "--db", db, "--similarity", "euclidean")[0] == 0

    code, _, err = _cli(capsys, "train", str(train), "--db", db, "--append", "--length", "16")
    assert code == 1 and "does not take --length" in err and err.count("\n") == 1
    code, _, err = _cli(capsys, "train", str(train), "--db", db)
    assert code == 1 and "already exists" in err

    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"\x00garbage" * 500)
    code, _, err = _cli(capsys, "classify", str(test), "--db", str(junk))
    assert code == 1 and str(junk) in err and "not a readable SQLite database" in err

    code, _, err = _cli(capsys, "classify", str(test), "--db", str(tmp_path / "none.sqlite"))
    assert code == 1 and "no such case base file" in err

    empty = tmp_path / "empty"
    (empty / "squat").mkdir(parents=True)
    code, _, err = _cli(capsys, "train", str(empty), "--db", str(tmp_path / "e.sqlite"))
    assert code == 1 and err.startswith("posecbr train: error:")

    one = tmp_path / "one"
    for f in sorted((train / ACTIVITIES[2]).glob("*.npz")):
        (one / ACTIVITIES[2]).mkdir(parents=True, exist_ok=True)
        (one / ACTIVITIES[2] / f.name).write_bytes(f.read_bytes())
    code, _, err = _cli(capsys, "train", str(one), "--db", str(tmp_path / "o.sqlite"))
    assert code == 1 and err.count("\n") == 1
    # named by the data, not by the Python API's argument ("y: the training set ...")
    assert f"{one}: the training data hold only one activity ({ACTIVITIES[2]!r})" in err

    code, _, err = _cli(
        capsys,
        "train",
        str(train),
        "--db",
        str(tmp_path / "q.sqlite"),
        "--features",
        "qmp",
        "--similarity",
        "dtw",
    )
    assert code == 1 and "compares sequences" in err
    code, _, err = _cli(
        capsys, "train", str(train), "--db", str(tmp_path / "s.sqlite"), "--similarity", "cosine"
    )
    assert code == 1 and "unknown similarity 'cosine'" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--similarity", "dtw", "--phases", "3"], "--phases: goes with clip summaries"),
        (["--features", "qmp", "--phases", "3"], "--phases: goes with clip summaries"),
        (["--no-summary", "--phases", "2"], "--phases: goes with clip summaries"),
        (["--features", "qmp", "--no-positions"],
         "--no-positions: goes with fluent features, not qmp"),
        (["--features", "qmp", "--no-summary"], "--no-summary: goes with fluent features, not qmp"),
    ],
)  # fmt: skip
def test_train_refuses_options_its_features_would_ignore(
    dataset: tuple[Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    message: str,
) -> None:
    """Options of fluent features and their clip summaries given where nothing would take them
    (they were accepted, and the case base was what it would have been without them): one
    line naming the option, no case base written."""
    train, _ = dataset
    before = {p: p.read_bytes() for p in train.rglob("*") if p.is_file()}
    db = tmp_path / "cb.sqlite"
    code, out, err = _cli(capsys, "train", str(train), "--db", str(db), *argv)
    assert code == 1 and out == "" and err.count("\n") == 1
    assert message in err and not db.exists()
    assert before == {p: p.read_bytes() for p in train.rglob("*") if p.is_file()}


def test_trim_and_classify_options_that_cannot_hold_are_refused(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--keep`` with CNN (ignored before: it keeps what it needs), ``-k`` as large as the
    case base for trim or larger for classify (clamped before, and the accuracies changed):
    one line each, nothing changed."""
    import hashlib

    train, _ = dataset
    db = tmp_path / "cb.sqlite"
    assert _cli(capsys, "train", str(train), "--db", str(db))[0] == 0
    n = 5 * len(ACTIVITIES)
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    for argv, message in (
        (["--editor", "cnn", "--keep", "0.5"],
         "--keep: goes with --editor novelty-benefit; cnn decides how many cases it keeps"),
        (["-k", str(n)],
         f"-k: must be less than the {n} cases of 'default' (each is left out in turn), got {n}"),
    ):  # fmt: skip
        code, out, err = _cli(capsys, "casebase", "trim", "--db", str(db), *argv)
        assert code == 1 and out == "" and err.count("\n") == 1, err
        assert err.strip().endswith(message), err
    code, out, err = _cli(capsys, "classify", str(train), "--db", str(db), "-k", str(n + 1))
    assert code == 1 and out == "" and err.count("\n") == 1
    assert err.strip().endswith(f"-k: must be at most the {n} cases of 'default', got {n + 1}")
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before
    code, out, _ = _cli(capsys, "casebase", "trim", "--db", str(db), "-k", str(n - 1), "--dry-run")
    assert code == 0 and f"({n - 1}-NN, each of the {n} cases before left out in turn)" in out


def _demo_subset(tmp_path: Path) -> Path:
    """16 demo UI-PRMD clips with their labels.csv: deep squats and shoulder abductions of
    s01 and s02, takes 1-2, correct and incorrect."""
    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    data = tmp_path / "data"
    data.mkdir()
    takes = tuple(f"{m}_{s}_e0{e}" for m in ("m01", "m07") for s in ("s01", "s02") for e in (1, 2))
    rows = [r for r in (demo / "labels.csv").read_text().splitlines()[1:] if r.startswith(takes)]
    assert len(rows) == 16
    for r in rows:
        (data / r.split(",")[0]).write_bytes((demo / r.split(",")[0]).read_bytes())
    head = (demo / "labels.csv").read_text().splitlines()[0]
    (data / "labels.csv").write_text("\n".join([head, *rows]) + "\n")
    return data


def test_an_edited_case_base_left_with_one_subject_trains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """16 UI-PRMD clips of two subjects and two movements: CNN keeps 2 cases (a traceback
    before: the feature ranges were calibrated holding out each subject's fold, and every
    case kept was one subject's). It trains, and the case base classifies its own clips.
    (With k = 5 two cases are refused, as ``casebase trim`` refuses them: hence ``-k 1``.)"""
    data = _demo_subset(tmp_path)
    db = tmp_path / "cnn.sqlite"
    code, out, err = _cli(capsys, "train", str(data), "--db", str(db), "--editor", "cnn",
                          "-k", "1")  # fmt: skip
    assert code == 0 and "Traceback" not in err, err
    assert "CNN: 16 ->" in out
    code, out, err = _cli(capsys, "classify", str(data), "--db", str(db), "-k", "1", "-q")
    assert code == 0 and "16 clips: 16 classified" in out


def test_train_counts_the_cases_it_stored_per_activity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """With mirror-image cases (``--mirror augment``: 16 UI-PRMD clips, 16 mirror images
    added) the per-activity counts add up to the cases stored, as ``casebase info`` counts
    them (they counted the clips: 8 + 8 beside 32 cases)."""
    data = _demo_subset(tmp_path)
    db = tmp_path / "aug.sqlite"
    code, out, _ = _cli(capsys, "train", str(data), "--db", str(db), "--mirror", "augment",
                        "--json")  # fmt: skip
    assert code == 0
    doc = json.loads(out)
    assert doc["active_cases"] > 16  # mirror images were added
    assert sum(doc["labels"].values()) == doc["active_cases"]
    store = open_store(db, readonly=True)
    assert store.get_case_base("default").label_counts == doc["labels"]
    store.close()


def test_k_beyond_the_cases_is_refused_or_said(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """k counts cases, so: ``train -k`` above the clips it gets is refused, nothing written;
    ``trim`` that would leave fewer cases than the k the case base votes with is refused,
    nothing changed (it went 15 -> 3 cases under k = 5, and then reported a "5-NN"
    accuracy over 3 cases); ``trim`` whose stored k leaves no case to vote when one is
    left out is refused as an explicit -k is; a case base of fewer clips than the default k
    says so when it classifies (every case votes)."""
    import hashlib

    train, _ = dataset
    n = 5 * len(ACTIVITIES)
    db = tmp_path / "cb.sqlite"
    code, out, err = _cli(capsys, "train", str(train), "--db", str(db), "-k", str(n + 1))
    assert code == 1 and out == "" and err.count("\n") == 1
    assert err.strip().endswith(f"-k: must be at most the {n} cases, got {n + 1}")
    assert not db.exists()
    assert _cli(capsys, "train", str(train), "--db", str(db))[0] == 0  # k = 5
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    code, out, err = _cli(capsys, "casebase", "trim", "--db", str(db), "--keep", "0.2")
    assert code == 1 and out == "" and err.count("\n") == 1
    assert err.strip().endswith(
        f"trimming would leave {len(ACTIVITIES)} cases, fewer than the 5 that case base"
        " 'default' votes with (k): nothing trimmed (keep more: --keep)"
    )
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before
    every = tmp_path / "every.sqlite"
    assert _cli(capsys, "train", str(train), "--db", str(every), "-k", str(n))[0] == 0
    code, out, err = _cli(capsys, "casebase", "trim", "--db", str(every), "--dry-run")
    assert code == 1 and out == "" and err.count("\n") == 1
    assert err.strip().endswith(
        f"case base 'default' votes with k = {n}, not less than its {n} cases (each is left"
        " out in turn): give -k"
    )
    small = tmp_path / "small"
    for label in ACTIVITIES:  # one clip each: 3 cases, k = 5
        first = sorted((train / label).iterdir())[0]
        (small / label).mkdir(parents=True)
        (small / label / first.name).write_bytes(first.read_bytes())
    assert _cli(capsys, "train", str(small), "--db", str(tmp_path / "small.sqlite"))[0] == 0
    code, out, err = _cli(capsys, "classify", str(small), "--db", str(tmp_path / "small.sqlite"))
    assert code == 0 and out
    assert (
        f"note: case base 'default' holds {len(ACTIVITIES)} cases, fewer than the 5 it votes"
        " with (k): every case votes"
    ) in err


def test_casebase_history_counts_operations_and_list_marks_trimmed_cases(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two trims read "trim x2", not one entry per case dropped plus two ("trim x92"), with
    the cases dropped beside (the trims' own sizes before and after); a feedback clip not
    retained is not a retain; ``list --all`` marks the trimmed cases ("trained" for all)."""
    train, test = dataset
    db = str(tmp_path / "cb.sqlite")
    assert _cli(capsys, "train", str(train), "--db", db)[0] == 0
    retained = 0
    for clip in sorted(test.rglob("*.npz"))[:2]:
        code, out, _ = _cli(capsys, "classify", str(clip), "--db", db, "--feedback",
                            ACTIVITIES[0], "--json")  # fmt: skip
        assert code == 0
        retained += json.loads(out)["results"][0]["retention"]["retained"]
    dropped = 0
    for _ in range(2):
        code, out, _ = _cli(capsys, "casebase", "trim", "--db", db, "--keep", "0.5", "--json")
        rep = json.loads(out)
        dropped += rep["size_before"] - rep["size_after"]
    code, out, _ = _cli(capsys, "casebase", "info", "--db", db, "--json")
    info = json.loads(out)["case_bases"][0]
    assert info["maintenance"]["trim"] == 2 and info["trimmed_cases"] == dropped > 0
    assert info["maintenance"].get("retain", 0) == retained
    assert info["not_retained"] == 2 - retained
    code, out, _ = _cli(capsys, "casebase", "info", "--db", db)
    assert f"trim x2 ({dropped} cases dropped)" in out
    code, out, _ = _cli(capsys, "casebase", "list", "--db", db, "--all", "--json")
    cases = json.loads(out)["cases"]
    assert sum(not c["active"] for c in cases) == dropped
    code, out, _ = _cli(capsys, "casebase", "list", "--db", db, "--all")
    assert out.count(", trimmed\t") == dropped


DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_train_on_another_column_and_classify_against_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # one case base per movement for correct vs incorrect (the labels CSV's `correct` column)
    db = str(tmp_path / "abduction.sqlite")
    code, out, err = _cli(
        capsys, "train", str(DEMO), "--db", db, "--labels", "standing_shoulder_abduction",
        "--target", "correct", "--subjects", "s01,s02", "--json",
    )  # fmt: skip
    assert code == 0, err
    # two people x three episodes, each done correctly and incorrectly (file names: _inc)
    assert json.loads(out)["labels"] == {"correct": 6, "incorrect": 6}
    clips = sorted(str(p) for p in DEMO.glob("m07_s03_*.npz"))
    assert len(clips) == 6
    code, out, err = _cli(capsys, "classify", *clips, "--db", db, "--target", "correct", "--json")
    assert code == 0, err
    doc = json.loads(out)
    truth = {r["clip"]: "incorrect" if r["clip"].endswith("_inc.npz") else "correct"
             for r in doc["results"]}  # fmt: skip
    assert {r["true_label"] for r in doc["results"]} == {"correct", "incorrect"}
    assert all(r["true_label"] == truth[r["clip"]] for r in doc["results"])
    right = sum(r["label"] == truth[r["clip"]] for r in doc["results"])
    assert doc["accuracy"] == pytest.approx(right / 6)
    # without --target the clips are checked against what the case base predicts
    code, out, err = _cli(capsys, "classify", *clips, "--db", db, "--json")
    assert code == 0, err
    assert json.loads(out)["accuracy"] == pytest.approx(right / 6)
    # checking a verdict case base against the activity is refused, not scored 0
    code, out, err = _cli(capsys, "classify", *clips, "--db", db, "--target", "label")
    assert code == 1 and out == "" and err.count("\n") == 1
    assert "predicts 'correct'" in err and "--target label" in err


def test_train_target_column_missing_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "cb.sqlite"
    code, out, err = _cli(
        capsys, "train", str(DEMO), "--db", str(db), "--labels", "deep_squat", "--target",
        "effort",
    )  # fmt: skip
    assert code != 0 and out == ""
    assert len(err.strip().splitlines()) == 1
    assert "no value for --target 'effort'" in err and "correct" in err and ".npz" in err
    assert not db.exists() or not open_store(str(db)).list_case_bases()


def test_train_refuses_before_reading_clips(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A name the store holds (no --replace, no --append) is refused before DATA is read: a
    missing DATA folder is not even looked at (it was read, cut and described first, then
    refused). --label-block and --label-names without --frame-labels: one line naming the
    option (they were ignored, and an error about one activity followed)."""
    train, _ = dataset
    db = str(tmp_path / "cb.sqlite")
    assert _cli(capsys, "train", str(train), "--db", db)[0] == 0
    stored = Path(db).read_bytes()
    code, _, err = _cli(capsys, "train", str(tmp_path / "no-such-folder"), "--db", db)
    assert code == 1 and err.count("\n") == 1
    assert "a case base named 'default' already exists" in err and "--replace" in err
    for option, value in (("--label-block", "0.1"), ("--label-names", str(tmp_path / "n.txt"))):
        code, _, err = _cli(capsys, "train", str(train), "--db", db, "--name", "x", option, value)
        assert code == 1 and err.count("\n") == 1
        assert f"{option}: goes with --frame-labels" in err
    assert Path(db).read_bytes() == stored


def test_train_refuses_a_database_it_could_not_write_before_reading_clips(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each of these was refused only after every clip was read and the model fitted (hours on
    a large set; a name too long for the temporary file ended in a traceback): now at once, in
    one line naming the file, with DATA a folder that does not exist (so never read)."""
    train, _ = dataset
    folder = tmp_path / "a-folder"
    folder.mkdir()
    text = tmp_path / "notes.sqlite"
    text.write_text("not a database\n")
    pose = next(train.rglob("*.npz"))
    before = pose.read_bytes()
    long_name = tmp_path / ("c" * 250 + ".sqlite")  # SQLite's NAME-journal would not fit
    cases = [
        (folder, "is a folder, not a case base file"),
        (tmp_path / "missing" / "cb.sqlite", "folder does not exist"),
        (text, "not a readable SQLite database"),
        (long_name, "the file name is too long: 257 bytes, at most 247"),
    ]
    for db, message in cases:
        code, _, err = _cli(capsys, "train", str(tmp_path / "no-such-data"), "--db", str(db))
        assert code == 1 and err.count("\n") == 1 and "Traceback" not in err, err
        assert message in err, err
    code, _, err = _cli(capsys, "train", str(pose), "--db", str(pose))
    assert code == 1 and err.count("\n") == 1
    assert "the case base file would overwrite an input" in err
    assert pose.read_bytes() == before and text.read_text() == "not a database\n"
    assert not (tmp_path / "missing").exists() and list(folder.iterdir()) == []
    # a long name that leaves room for the journal is written (its temporary was too long)
    db = tmp_path / ("d" * 240 + ".sqlite")
    assert _cli(capsys, "train", str(train), "--db", str(db))[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith((".d", "d"))) == [db.name]


def test_a_clip_is_not_trained_from_twice(
    dataset: tuple[Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A labels CSV listing one file twice, and an --append of clips already in the case base:
    refused in one line naming the file (their cases would vote twice: the case base doubled
    silently), nothing written; also when the folder is named another way (through a link,
    or relative to the working folder where it was trained by its absolute path)."""
    train, _ = dataset
    clips = sorted(train.rglob("*.npz"))
    csv = tmp_path / "labels.csv"
    rows = [f"{p},{p.parent.name}" for p in [*clips, clips[3]]]
    csv.write_text("path,label\n" + "\n".join(rows) + "\n", encoding="utf-8")
    db = tmp_path / "cb.sqlite"
    code, _, err = _cli(capsys, "train", str(csv), "--db", str(db))
    assert code == 1 and err.count("\n") == 1 and not db.exists()
    # named as classify and segment name a piece: its frames, end inclusive
    last = load_pose(clips[3]).n_frames - 1
    assert f"{clips[3]} frames 0-{last} is listed twice" in err
    assert _cli(capsys, "train", str(train), "--db", str(db))[0] == 0
    stored = db.read_bytes()
    code, _, err = _cli(capsys, "train", str(clips[3].parent), "--db", str(db), "--append")
    assert code == 1 and err.count("\n") == 1
    assert "is already case " in err and "of 'default' (added before?): nothing added" in err
    assert db.read_bytes() == stored
    link = tmp_path / "link"
    link.symlink_to(clips[3].parent, target_is_directory=True)
    monkeypatch.chdir(clips[3].parent.parent)
    for again in (str(link), clips[3].parent.name):
        code, _, err = _cli(capsys, "train", again, "--db", str(db), "--append")
        assert code == 1 and err.count("\n") == 1, (again, err)
        assert "is already case " in err, err
        assert db.read_bytes() == stored
    # cut into windows: the note on the cutting came before the refusal (two lines); it is
    # said once the training is done, so a refusal is its one line
    windows = tmp_path / "windows.sqlite"
    code, _, err = _cli(capsys, "train", str(train), "--db", str(windows), "--split", "windows")
    # (the clips last under 2 s: none is cut; said so, not "cut 15 clips into 0 windows")
    assert code == 0 and "kept 15 clips whole: each shorter than a window of 2 s" in err, err
    stored = windows.read_bytes()
    code, _, err = _cli(capsys, "train", str(clips[3].parent), "--db", str(windows), "--append")
    assert code == 1 and err.count("\n") == 1 and "is already case " in err, err
    assert windows.read_bytes() == stored


def test_append_says_how_many_activities_it_added(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Appending the two test clips of one activity to the 15 cases of three: "17 cases (2
    added, of 1 activity)" (it said "from 1 activities", as if the case base held one)."""
    train, test = dataset
    db = str(tmp_path / "cb.sqlite")
    assert _cli(capsys, "train", str(train), "--db", db)[0] == 0
    one = sorted(p.name for p in test.iterdir())[0]
    code, out, err = _cli(capsys, "train", str(test / one), "--db", db, "--append")
    assert code == 0, err
    assert "17 cases (2 added, of 1 activity)" in out, out
    assert "did not hold" not in err  # an activity it holds: nothing new
    # casebase info says the calibrations are of the 15 training clips, not the 17 cases
    # (it described them as if they held for the case base as it is), and that the unknown
    # judges, dropped by the append, are calibrated as segment starts
    code, out, _ = _cli(capsys, "casebase", "info", "--db", db)
    assert code == 0
    assert "training clips (their accuracy " in out
    assert "; cases added, changed or dropped since are not taken into account)" in out
    assert "(at training: cases added, changed or dropped since are not taken into account)" in out
    assert "unknown judges: none stored (the cases changed since training" in out


def test_append_takes_the_case_base_s_target(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case base of correct/incorrect repetitions (``--target correct``): ``--append``
    without ``--target`` was refused ("predicts 'correct', not 'label'"), though it takes
    the stored kind of case (``--split``) without being told; the clips added are judged by
    their ``correct`` column. ``--target label`` given is still refused."""
    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    rows = (demo / "labels.csv").read_text(encoding="utf-8").splitlines()
    header = rows[0]
    movements = ("m01_", "m02_")

    def subset(name: str, subjects: tuple[str, ...]) -> Path:
        keep = [r for r in rows[1:] if r.startswith(movements) and r.split(",")[2] in subjects]
        path = tmp_path / name
        path.write_text("\n".join([header, *(f"{demo}/{r}" for r in keep)]) + "\n")
        return path

    train, more = subset("train.csv", ("s01", "s02")), subset("more.csv", ("s03",))
    db = str(tmp_path / "cb.sqlite")
    code, _, err = _cli(capsys, "train", str(train), "--db", db, "--target", "correct")
    assert code == 0, err
    code, out, err = _cli(capsys, "train", str(more), "--db", db, "--append")
    assert code == 0, err
    # 2 movements x 2 subjects x 3 episodes x (correct, incorrect) = 24, then 12 more
    assert "36 cases (12 added, of 2 classes)" in out, out  # correct, incorrect
    store = open_store(db, readonly=True)
    counts = store.get_case_base("default").label_counts
    store.close()
    assert counts == {"correct": 18, "incorrect": 18}
    code, _, err = _cli(capsys, "train", str(more), "--db", db, "--append", "--target", "label")
    assert code == 1 and "predicts 'correct', not 'label'" in err


def test_a_clip_shorter_than_a_movement_is_no_case_as_it_is_unclassifiable(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``classify`` calls a 1-frame clip unclassifiable (shorter than one movement can be,
    0.4 s); ``train``, ``train --append`` and ``compare`` took it as a case all the same."""
    import shutil

    from features.poses import load_pose

    train = shutil.copytree(dataset[0], tmp_path / "train")
    first = sorted(train.rglob("*.npz"))[0]
    one = save_pose(load_pose(first).slice_frames(0, 1), first.parent / "one_frame.npz")
    seconds = 1 / load_pose(one).fps
    db = str(tmp_path / "cb.sqlite")
    code, out, err = _cli(capsys, "train", str(train), "--db", db)
    assert code == 0, err
    assert (
        f"skipped 1 clip shorter than one movement can be (0.4 s): {one} (lasts {seconds:.2f} s)"
    ) in out
    assert "15 cases" in out  # the five clips of each of three activities, not the sixteenth
    stored = Path(db).read_bytes()
    code, _, err = _cli(capsys, "train", str(one), "--db", db, "--append")
    assert code == 1 and err.count("\n") == 1
    assert "every clip is shorter than one movement can be (0.4 s): nothing to add" in err
    assert Path(db).read_bytes() == stored
    code, _, err = _cli(capsys, "compare", str(train), "--no-dad", "--peers", "none",
                        "--similarities", "euclidean", "--features", "fluents")  # fmt: skip
    assert code == 0
    assert f"left out 1 clip shorter than one movement can be (0.4 s): {one}" in err


def test_append_names_the_activities_the_case_base_did_not_hold(
    dataset: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip whose label the case base lacks becomes a new activity, as it may; said, with
    the labels (before: in silence, so a pose file converted alone, labelled with its file
    name, added an activity called "13_31")."""
    train, test = dataset
    db = str(tmp_path / "cb.sqlite")
    assert _cli(capsys, "train", str(train), "--db", db)[0] == 0
    clip = sorted((test / ACTIVITIES[0]).iterdir())[0]
    csv = tmp_path / "new.csv"
    csv.write_text(f"path,label\n{clip},13_31\n", encoding="utf-8")
    code, out, err = _cli(capsys, "train", str(csv), "--db", db, "--append", "--json")
    assert code == 0, err
    assert json.loads(out)["new_labels"] == ["13_31"]
    assert "note: 1 activity the case base did not hold, added as new: 13_31" in err, err
