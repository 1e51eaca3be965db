"""The case base never loses or corrupts a case under feedback, concurrency and kills
(issue 15, "Data loss or damage" 1-4 and 8): real processes, real SQLite files (and PostgreSQL
where CI starts one)."""

from __future__ import annotations

import hashlib
import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.stored import load_classifier
from features.poses import PoseSequence, load_pose, save_pose
from posecbr.cli import main
from tests.badinput import posecbr_on_read_only_mount, read_only_mounts_work
from tests.once import made_once
from tests.postgres import postgres_copy_of
from tests.processes import posecbr_process as _posecbr

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A case base of two subjects' clips (fluents, euclidean), to copy per test (made once
    in the session, not once in each worker)."""

    def make(folder: Path) -> Path:
        db = folder / "cb.sqlite"
        assert main(["train", str(LABELS), "--db", str(db), "--subjects", "s01,s02"]) == 0
        return db

    return made_once(tmp_path_factory, "feedback-safety-trained", make)


def _copy(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes())
    return dst


@pytest.fixture(params=["sqlite", "postgresql"])
def db_url(request: pytest.FixtureRequest, trained: Path, tmp_path: Path) -> str:
    if request.param == "sqlite":
        return str(_copy(trained, tmp_path / "cb.sqlite"))
    return postgres_copy_of(trained)


def test_two_writers_revising_one_case_all_take_effect(db_url: str) -> None:
    """Two processes each revise the same case six times with the same observation q: the
    LVQ step p <- p + 0.25 (q - p) applied 12 times gives q + 0.75^12 (p0 - q), whatever the
    interleaving; a lost update would leave a power of 0.75 below 12."""
    clip = str(DEMO / "m01_s03_e01.npz")
    store = open_store(db_url, readonly=True)
    stored = load_classifier(store, "default")
    solved = stored.classifier.solve([load_pose(clip)])[0]
    q = solved.problem.values
    case_id = int(solved.retrieval.case_ids[0])
    assert solved.retrieval.labels[0] == "deep_squat"  # the nearest case has the true label
    p0 = store.load_cases("default", ids=[case_id]).features[0]
    n_before = store.count_cases("default")
    store.close()
    argv = [
        "classify",
        clip,
        clip,
        clip,
        clip,
        clip,
        clip,
        "--db",
        db_url,
        "--feedback",
        "deep_squat",
        "--novelty",
        "1e9",
    ]  # fmt: skip  (never novel enough to retain: always revise)
    procs = [_posecbr(*argv) for _ in range(2)]
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
    store = open_store(db_url, readonly=True)
    got = store.load_cases("default", ids=[case_id]).features[0]
    np.testing.assert_allclose(got, q + 0.75**12 * (p0 - q), rtol=1e-9, atol=1e-12)
    assert store.count_cases("default") == n_before  # nothing retained, nothing lost
    revisions = [e for e in store.maintenance_log("default") if e.action == "revise"]
    assert len(revisions) == 12 and all(e.case_id == case_id for e in revisions)
    store.close()
    if not db_url.startswith("postgresql"):
        con = sqlite3.connect(db_url)
        assert con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
        con.close()


def test_two_writers_retaining_lose_and_duplicate_nothing(db_url: str) -> None:
    clips = sorted(str(p) for p in DEMO.glob("m07_s03_e0?.npz"))  # three abduction clips
    store = open_store(db_url, readonly=True)
    n_before = store.count_cases("default")
    store.close()
    argv = [
        "classify",
        *clips,
        "--db",
        db_url,
        "--feedback",
        "standing_shoulder_abduction",
        "--novelty",
        "0",
        "--benefit",
        "0",
    ]  # fmt: skip  (every clip is retained, once: the other writer finds its case stored)
    procs = [_posecbr(*argv) for _ in range(2)]
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
    store = open_store(db_url, readonly=True)
    cases = store.load_cases("default")
    assert len(cases.ids) == n_before + 3 and len(set(cases.ids.tolist())) == len(cases.ids)
    log = [e for e in store.maintenance_log("default") if e.action == "retain"]
    assert len(log) == 6  # every decision logged, the three not retained without a case
    source = dict(zip(cases.ids.tolist(), cases.sources, strict=True))
    # a retained case the other writer then revised toward its clip is "revised"
    assert sorted(source[e.case_id] for e in log if e.case_id is not None) == clips
    store.close()


def test_replacing_the_case_base_during_feedback_writes_nothing_into_the_new_one(
    trained: Path, tmp_path: Path
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    clips = sorted(str(p) for p in DEMO.glob("m01_s03_*.npz"))
    gate = tmp_path / "go"
    feedback = _posecbr("classify", *clips, "--db", str(db), "--feedback", "deep_squat", gate=gate)
    assert feedback.stdout is not None and feedback.stdout.readline().strip() == "PAUSED"
    # the first clip's feedback is committed; the case base is replaced before the second
    assert main(["train", str(LABELS), "--db", str(db), "--subjects", "s03", "--replace"]) == 0
    store = open_store(db, readonly=True)
    new = store.load_case_base("default")
    store.close()
    gate.touch()
    out, err = feedback.communicate(timeout=300)
    assert feedback.returncode == 1 and "Traceback" not in err
    assert err.strip().endswith("was replaced by another process since it was read; nothing was "
                                "written (run the command again)")  # fmt: skip
    assert err.count("\n") == 1
    store = open_store(db, readonly=True)
    info, cases = store.load_case_base("default")
    assert info.uid == new[0].uid and info.version == new[0].version
    np.testing.assert_array_equal(cases.features, new[1].features)
    assert [e.action for e in store.maintenance_log("default")] == ["build"]
    store.close()
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    con.close()
    assert main(["classify", clips[0], "--db", str(db)]) == 0  # loadable, consistent


def test_a_feedback_run_sees_the_replacement_and_stops_with_one_line(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The in-memory classifier was read before the case base was replaced: the next
    feedback transaction refuses to write into the new one."""
    db = _copy(trained, tmp_path / "cb.sqlite")
    from cbr.classification import FeedbackSettings, classify_with_feedback

    store = open_store(db)
    stored = load_classifier(store, "default")
    assert main(["train", str(LABELS), "--db", str(db), "--subjects", "s03", "--replace"]) == 0
    capsys.readouterr()
    before = _sha(db)
    with pytest.raises(Exception, match="replaced by another process"):
        classify_with_feedback(
            store, stored, [load_pose(DEMO / "m01_s03_e01.npz")], "deep_squat",
            FeedbackSettings(),
        )  # fmt: skip
    store.close()
    assert _sha(db) == before
    # and new ids never reuse old ones: the replacement's cases come after the old ones
    store = open_store(db, readonly=True)
    assert min(store.load_cases("default").ids) > max(stored.classifier.case_base_.ids)
    store.close()


@pytest.mark.parametrize(
    ("label", "message"),
    [
        ("deep_sqaut", "did you mean 'deep_squat'?"),
        ("", "the feedback label is empty"),
        ("   ", "the feedback label is empty"),
    ],
)
def test_a_mistyped_or_empty_feedback_label_changes_nothing(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    label: str,
    message: str,
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    before = _sha(db)
    clip = str(DEMO / "m01_s03_e01.npz")
    code = main(["classify", clip, "--db", str(db), "--feedback", label])
    out, err = capsys.readouterr()
    assert code == 1 and out == "" and err.count("\n") == 1 and message in err
    assert "Traceback" not in err
    assert _sha(db) == before


def test_a_new_label_needs_new_label_and_then_makes_one_case(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    clip = str(DEMO / "m01_s03_e01.npz")
    argv = ["classify", clip, "--db", str(db), "--feedback", "deep squat, heels up", "--new-label"]
    assert main(argv) == 0
    capsys.readouterr()
    store = open_store(db, readonly=True)
    counts = store.get_case_base("default").label_counts
    assert counts["deep squat, heels up"] == 1
    assert sum(counts.values()) == 121  # 120 trained + the new one; no case relabelled
    assert counts["deep_squat"] == 12
    store.close()


def test_answers_are_judged_against_the_label_the_user_gives(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A deep squat clip (its file says deep_squat) told to be sit_to_stand: it is stored as
    sit_to_stand, so the answer is judged against sit_to_stand too, not against its file's
    label (it said "correct", accuracy 1.0, while storing the other label)."""
    db = _copy(trained, tmp_path / "cb.sqlite")
    clip = DEMO / "m01_s03_e01.npz"
    assert load_pose(clip).label == "deep_squat"
    argv = ["classify", str(clip), "--db", str(db), "--feedback", "sit_to_stand", "--json"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    (result,) = doc["results"]
    assert result["true_label"] == "sit_to_stand"
    assert result["correct"] == (result["label"] == "sit_to_stand")
    assert doc["accuracy"] == (1.0 if result["correct"] else 0.0)


def _no_person(like: Path, out: Path) -> Path:
    seq = load_pose(like)
    blank = PoseSequence(
        np.full_like(seq.positions, np.nan), seq.joint_names, seq.fps, source=str(out),
        metadata={"label": "deep_squat", "subject": "s09"},
    )  # fmt: skip
    save_pose(blank, out)
    return out


def test_a_clip_with_no_person_is_unclassifiable_and_never_stored(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    blank = _no_person(DEMO / "m01_s03_e01.npz", tmp_path / "blank.npz")
    code = main(["classify", str(blank), "--db", str(db), "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    # nothing asked for could be done: exit 1 (it was 0), the JSON still says why
    assert code == 1
    assert err == (
        "posecbr classify: error: no clip could be classified (1 clip, each unclassifiable: "
        "see above)\n"
    )
    assert doc["results"][0]["label"] is None
    assert "no person" in doc["results"][0]["unclassifiable"]
    # not judged: "correct": false before, while the summary counted no labelled clip
    assert doc["results"][0]["correct"] is None and doc["summary"]["labelled"] == 0
    store = open_store(db, readonly=True)
    n, log = store.count_cases("default"), len(store.maintenance_log("default"))
    store.close()
    argv = ["classify", str(blank), "--db", str(db), "--feedback", "deep_squat", "--novelty", "0",
            "--benefit", "0"]  # fmt: skip
    assert main(argv) == 1
    out = capsys.readouterr().out
    assert "unclassifiable" in out
    store = open_store(db, readonly=True)
    assert store.count_cases("default") == n and len(store.maintenance_log("default")) == log
    store.close()


def test_a_clip_shorter_than_a_movement_is_unclassifiable_and_never_stored(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One frame of a deep squat (0.03 s) was answered "standing_shoulder_abduction,
    confidence 0.86" and could be retained by feedback. 12 frames at 30 fps (0.4 s, the
    shortest repetition) are classified; 11 are not."""
    import numpy as np

    db = _copy(trained, tmp_path / "cb.sqlite")
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    clip = dict(np.load(DEMO / "m01_s03_e01.npz"))
    for n, usable in ((1, False), (11, False), (12, True)):
        path = tmp_path / f"first{n}.npz"
        np.savez(path, **{**clip, "positions": clip["positions"][:n]})  # type: ignore[arg-type]
        code = main(["classify", str(path), "--db", str(db), "--feedback", "deep_squat"])
        out, err = capsys.readouterr()
        if usable:
            assert code == 0 and "unclassifiable" not in out
            continue
        frames = f"{n} frame{'s' if n > 1 else ''}"
        assert code == 1 and err == (
            "posecbr classify: error: no clip could be classified (1 clip, each "
            "unclassifiable: see above)\n"
        )
        assert f"unclassifiable (lasts {n / 30:.2f} s ({frames}), shorter than one movement" in out
        assert hashlib.sha256(db.read_bytes()).hexdigest() == before


def test_train_skips_clips_with_no_person_and_names_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    for f in sorted(DEMO.glob("m0[17]_s01_*.npz")):
        label = "deep_squat" if f.name.startswith("m01") else "abduction"
        (data / label).mkdir(parents=True, exist_ok=True)
        (data / label / f.name).write_bytes(f.read_bytes())
    _no_person(DEMO / "m01_s03_e01.npz", data / "deep_squat" / "black.npz")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [Path(s).name for s in doc["skipped"]] == ["black.npz"]
    assert doc["cases"] == 12


def test_read_only_commands_create_and_change_nothing(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    db = _copy(trained, folder / "cb.sqlite")
    before = _sha(db)
    clip = str(DEMO / "m01_s03_e01.npz")
    for argv in (
        ["classify", clip, "--db", str(db)],
        ["casebase", "info", "--db", str(db)],
        ["casebase", "list", "--db", str(db)],
        ["casebase", "trim", "--db", str(db), "--dry-run"],
    ):
        assert main(argv) == 0, capsys.readouterr().err
    assert _sha(db) == before and sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]
    for missing in (str(tmp_path / "none.sqlite"), f"sqlite:///{tmp_path / 'none2.sqlite'}"):
        assert main(["classify", clip, "--db", missing]) == 1
        assert "no such case base file" in capsys.readouterr().err
    assert not (tmp_path / "none.sqlite").exists() and not (tmp_path / "none2.sqlite").exists()


@pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)
@pytest.mark.parametrize("journal", ["delete", "wal"])  # wal: a file written by posecbr 0.1
def test_a_case_base_in_a_read_only_folder_can_be_read(
    trained: Path, tmp_path: Path, journal: str
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    db = _copy(trained, folder / "cb.sqlite")
    if journal == "wal":
        con = sqlite3.connect(db)
        assert con.execute("PRAGMA journal_mode = WAL").fetchone() == ("wal",)
        con.close()
    before = _sha(db)
    clip = DEMO / "m01_s03_e01.npz"
    done = posecbr_on_read_only_mount(folder, ["classify", str(clip), "--db", str(db), "--json"])
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["results"][0]["label"] == "deep_squat"
    assert _sha(db) == before and sorted(p.name for p in folder.iterdir()) == ["cb.sqlite"]


def test_a_failed_or_killed_train_leaves_no_case_base_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    one = tmp_path / "one" / "squat"
    one.mkdir(parents=True)
    for f in sorted(DEMO.glob("m01_s01_*.npz")):
        (one / f.name).write_bytes(f.read_bytes())
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(one.parent), "--db", str(db)]) == 1
    assert "only one activity" in capsys.readouterr().err
    assert not db.exists()
    # killed inside its one transaction, after every case was written
    proc = _posecbr("train", str(LABELS), "--db", str(db), "--subjects", "s01",
                    pause_after="build")  # fmt: skip
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    proc.kill()
    proc.wait(timeout=30)
    assert not db.exists()
    assert main(["train", str(LABELS), "--db", str(db), "--subjects", "s01"]) == 0
    store = open_store(db, readonly=True)
    assert store.count_cases("default") == 60
    store.close()


def test_a_killed_train_into_an_existing_file_leaves_it_as_it_was(
    trained: Path, tmp_path: Path
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    proc = _posecbr("train", str(LABELS), "--db", str(db), "--subjects", "s03", "--replace",
                    pause_after="build")  # fmt: skip
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    proc.kill()
    proc.wait(timeout=30)
    store = open_store(db)  # a writer: rolls the hot journal back
    info = store.get_case_base("default")
    assert info.n_cases == 120 and set(store.load_cases("default").subjects) == {"s01", "s02"}
    store.close()


def _state(db: Path) -> tuple[object, ...]:
    """Everything a case base file holds that a command may change (read-only)."""
    store = open_store(db, create=False)  # a writer first: rolls a hot journal back
    store.close()
    store = open_store(db, readonly=True)
    try:
        info, cases = store.load_case_base("default", include_inactive=True)
        active = store.load_cases("default").ids.tolist()
        log = [(e.action, e.case_id, e.reason) for e in store.maintenance_log("default")]
        return (info.version, info.model, cases.ids.tolist(), active, cases.labels.tolist(),
                _sha_array(cases.features), log)  # fmt: skip
    finally:
        store.close()


def _sha_array(a: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


@pytest.mark.parametrize(
    ("argv", "pause"),
    [
        (["casebase", "trim", "--keep", "0.5"], "trim"),
        (
            [
                "classify",
                str(DEMO / "m01_s03_e01.npz"),
                "--feedback",
                "deep_squat",
                "--novelty",
                "0",
                "--benefit",
                "0",
            ],
            "retain",
        ),  # fmt: skip
        (
            [
                "classify",
                str(DEMO / "m01_s03_e01.npz"),
                "--feedback",
                "deep_squat",
                "--novelty",
                "1e9",
            ],
            "revise",
        ),  # fmt: skip
    ],
    ids=["trim", "retain", "revise"],
)
def test_killed_inside_its_transaction_a_command_changes_nothing(
    trained: Path, tmp_path: Path, argv: list[str], pause: str
) -> None:
    db = _copy(trained, tmp_path / "cb.sqlite")
    before = _state(db)
    proc = _posecbr(*argv, "--db", str(db), pause_after=pause)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "PAUSED"
    assert (tmp_path / "cb.sqlite-journal").exists()  # the transaction has written
    proc.kill()
    proc.wait(timeout=30)
    assert _state(db) == before
    con = sqlite3.connect(db)
    assert con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    con.close()
