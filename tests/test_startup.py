"""Fast start: the command line loads a heavy library only where a command uses it.

Each probe runs in a fresh interpreter (this test process has everything loaded already) and
reports which of the heavy libraries are in ``sys.modules`` afterwards. Behaviour, not timing:
``python -m benchmarks.startup`` measures the times.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.version import __version__

ROOT = Path(__file__).resolve().parents[1]
CLIP = ROOT / "posecbr" / "demo_data" / "uiprmd" / "m01_s01_e01.npz"
# numpy too: the parser needs none of them (about 0.1 s of the 0.3 s aimed at for --help)
HEAVY = (
    "sklearn", "scipy", "numba", "sqlalchemy", "matplotlib", "cv2", "onnxruntime", "numpy",
    "pandas",
)  # fmt: skip
MARK = "loaded-modules:"
# The names of the registered commands, from the parser itself (argparse keeps them in the
# subparsers action's choices).
COMMANDS = (
    "import argparse\n"
    "from posecbr.cli import build_parser\n"
    "parser = build_parser()\n"
    "sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))\n"
    "names = sorted(sub.choices)"
)


def _run(code: str, tmp_path: Path, heavy: tuple[str, ...] = HEAVY) -> tuple[str, set[str]]:
    """Run ``code`` in a new interpreter; its output and which of the ``heavy`` libraries
    (or modules) it loaded."""
    probe = (
        "import sys\n"
        f"{code}\n"
        f"heavy = sorted(m for m in {heavy!r} if m in sys.modules)\n"
        f"print({MARK!r} + ','.join(heavy))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    out, _, loaded = proc.stdout.rpartition(MARK)
    return out, {m for m in loaded.strip().split(",") if m}


def test_version_loads_no_heavy_library(tmp_path: Path) -> None:
    out, loaded = _run(
        "from posecbr.cli import main\ntry:\n    main(['--version'])\nexcept SystemExit:\n    pass",
        tmp_path,
    )
    assert out.strip() == f"posecbr {__version__}"
    assert loaded == set()


def test_building_the_parser_loads_no_heavy_library(tmp_path: Path) -> None:
    # nor importlib.metadata: train's help names the plugins' measures (entry points) only
    # when it is shown (every installed package's metadata read: 0.016 s of CPU a process)
    out, loaded = _run(
        f"import json\n{COMMANDS}\nprint(json.dumps(names))",
        tmp_path,
        (*HEAVY, "importlib.metadata"),
    )
    # every command registered (so nothing was left out to look fast)
    commands = {p.stem for p in (ROOT / "posecbr" / "commands").glob("*.py")} - {"__init__"}
    assert set(json.loads(out)) == commands
    assert loaded == set()


def test_help_of_every_command_loads_no_heavy_library(tmp_path: Path) -> None:
    out, loaded = _run(
        f"import contextlib, io\n{COMMANDS}\n"
        "for name in names:\n"
        "    with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "        build_parser().parse_args([name, '--help'])\n"
        "print(len(names))",
        tmp_path,
    )
    assert int(out.strip()) >= 11
    assert loaded == set()


def test_train_help_names_the_measures_when_shown(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """train --help names every similarity measure as it is shown, not as the parser is
    built: one registered after that (as a plugin's is, by its entry point) is named."""
    from cbr.similarity import registry
    from posecbr.cli import build_parser

    parser = build_parser()
    monkeypatch.setitem(registry._REGISTRY, "plugin-measure", object)
    with pytest.raises(SystemExit):
        parser.parse_args(["train", "--help"])
    said = " ".join(capsys.readouterr().out.split())
    assert (
        "similarity measure: dtw, euclidean, plugin-measure, signature (default euclidean)" in said
    )


def _describe(clip: Path, tmp_path: Path) -> tuple[dict[str, Any], set[str]]:
    out, loaded = _run(
        f"from posecbr.cli import main\nassert main(['describe', {str(clip)!r}, '--json']) == 0",
        tmp_path,
    )
    doc: dict[str, Any] = json.loads(out)
    return doc, loaded


def test_describe_of_a_short_clip_loads_only_numpy(tmp_path: Path) -> None:
    doc, loaded = _describe(CLIP, tmp_path)
    assert doc["frames"] == 73 and doc["runs"]
    # one short clip: the numpy reference (numba would take longer to load its kernels than
    # they save); the spans are cleaned by a running majority in numpy; no scipy, case base,
    # estimator, plot or video
    assert loaded == {"numpy"}


def test_describe_of_a_long_clip_uses_the_compiled_kernels(tmp_path: Path) -> None:
    from features.datasets import load_clip
    from features.fluents import evaluate
    from features.poses import PoseSequence, save_pose
    from features.timeline import runs_to_json, state_runs

    squat = load_clip(CLIP)
    reps = 5000 // squat.n_frames + 1  # the deep squat 69 times over: 5037 frames
    seq = PoseSequence(np.concatenate([squat.positions] * reps), squat.joint_names, squat.fps)
    save_pose(seq, tmp_path / "long.npz")
    doc, loaded = _describe(tmp_path / "long.npz", tmp_path)
    assert doc["frames"] == 73 * reps
    assert "numba" in loaded and loaded <= {"numpy", "scipy", "numba"}
    # the same spans as the numpy reference gives
    reference = evaluate(seq, backend="numpy")
    assert doc["runs"] == runs_to_json(state_runs(reference, 0.8, 5, False), seq.fps)


def test_reps_of_a_short_clip_loads_no_compiled_kernel(tmp_path: Path) -> None:
    """reps of one short clip: its joint angles by the numpy reference, as describe's; the
    same repetitions as counted with numba's kernels (the library's default) here."""
    from features.datasets import load_clip
    from features.repetitions import count_repetitions

    out, loaded = _run(
        f"from posecbr.cli import main\nassert main(['reps', {str(CLIP)!r}, '--json']) == 0",
        tmp_path,
    )
    doc = json.loads(out)
    # the deep squat goes down once: frames 11-66, deepest at 45 (30 fps)
    assert doc["count"] == 1
    assert [(r["start_frame"], r["end_frame"], r["peak_frame"]) for r in doc["repetitions"]] == [
        (11, 67, 45)
    ]
    expected = count_repetitions(load_clip(CLIP).to_canonical()).to_dict()
    assert {k: doc[k] for k in expected} == json.loads(json.dumps(expected))
    # scipy's filters count; no numba, case base, estimator, plot or video
    assert loaded == {"numpy", "scipy"}


def test_dad_loads_no_estimator(tmp_path: Path) -> None:
    """dad of a clip runs the detector; DAD's scikit-learn face (DADClassifier) is not loaded."""
    from cbr.dad import detect
    from features.datasets import load_clip
    from features.qmp.add import load_add

    argv = ["dad", str(CLIP), "--json"]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    doc = json.loads(out)
    assert doc["status"] == "ok"
    expected = json.loads(json.dumps(detect(load_clip(CLIP), load_add()).to_dict()))
    assert {k: v for k, v in doc.items() if k not in ("window_s", "step_s")} == expected
    # one short clip: its state signals by the numpy reference (as describe's), the same
    # document as with numba's kernels (the library's default, above); SciPy fits the QMPs
    assert loaded == {"numpy", "scipy"}


def test_dad_of_a_long_clip_uses_the_compiled_kernels(tmp_path: Path) -> None:
    from features.datasets import load_clip
    from features.poses import PoseSequence, save_pose

    squat = load_clip(CLIP)
    reps = 5000 // squat.n_frames + 1  # 5037 frames
    seq = PoseSequence(np.concatenate([squat.positions] * reps), squat.joint_names, squat.fps)
    save_pose(seq, tmp_path / "long.npz")
    argv = ["dad", str(tmp_path / "long.npz"), "--json"]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert json.loads(out)["status"] == "ok"
    assert loaded == {"numpy", "scipy", "numba"}


@pytest.mark.parametrize("name", ["m01_s01_e01", "m05_s03_e02", "m10_s01_e01_inc"])
def test_dad_gives_the_same_document_by_either_backend(name: str) -> None:
    """The numpy reference's state signals give DAD the same document as numba's (checked on
    all 180 bundled clips once; three here)."""
    from cbr.dad import detect
    from features.datasets import load_clip
    from features.qmp.add import load_add

    seq, add = load_clip(CLIP.parent / f"{name}.npz"), load_add()
    assert detect(seq, add, backend="numpy").to_dict() == detect(seq, add).to_dict()


def test_dad_classifier_is_still_importable_from_the_package() -> None:
    from cbr.dad import DADClassifier
    from cbr.dad.classifier import DADClassifier as defined

    assert DADClassifier is defined


# on one xdist worker: the module's small_db made once, not once per worker
pytestmark = pytest.mark.xdist_group("startup")


@pytest.fixture(scope="module")
def small_db(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from posecbr.cli import main

    db = tmp_path_factory.mktemp("cb") / "cb.sqlite"
    labels = CLIP.parent / "labels.csv"
    argv = ["train", str(labels), "--db", str(db), "--subjects", "s01",
            "--labels", "deep_squat,standing_shoulder_abduction"]  # fmt: skip
    assert main(argv) == 0
    return db


@pytest.mark.parametrize("json_output", [False, True])
def test_casebase_list_loads_no_scipy_or_estimator(
    small_db: Path, tmp_path: Path, json_output: bool
) -> None:
    """Listing a store needs the store (SQLAlchemy, numpy), not the classifier's modules."""
    argv = ["casebase", "list", "--db", str(small_db), *(["--json"] if json_output else [])]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    # s01's 6 clips (3 correct, 3 incorrect) of each of the two activities
    if json_output:
        cases = json.loads(out)["cases"]
        labels = sorted(c["label"] for c in cases)
        assert labels == ["deep_squat"] * 6 + ["standing_shoulder_abduction"] * 6
        assert [c["case_id"] for c in cases] == list(range(1, 13))
    else:
        lines = out.splitlines()
        assert [line.split("\t")[0] for line in lines] == [f"#{i}" for i in range(1, 13)]
        assert lines[0].split("\t")[1:4] == ["deep_squat", "trained", "s01"]
    assert loaded == {"numpy", "sqlalchemy"}


@pytest.mark.parametrize("json_output", [False, True])
def test_casebase_info_loads_no_scipy_or_estimator(
    small_db: Path, tmp_path: Path, json_output: bool
) -> None:
    """info reads the stored model document; it does not load the classifier or SciPy to say
    what it holds."""
    argv = ["casebase", "info", "--db", str(small_db), *(["--json"] if json_output else [])]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert "deep_squat" in out
    # the stored novelty calibration is described without SciPy (cbr.novelty -> cbr.problem
    # imports the QMP fit and the repetition counter, which load SciPy only when they run)
    assert loaded == {"numpy", "sqlalchemy"}


def test_casebase_export_loads_no_scipy_or_estimator(small_db: Path, tmp_path: Path) -> None:
    """export checks the case base's width with the store's own check, not the classifier's
    module."""
    out_file = tmp_path / "cases.npz"
    argv = ["casebase", "export", "--db", str(small_db), "--out", str(out_file), "--json"]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert json.loads(out)["cases"] == 12
    with np.load(out_file) as z:
        assert sorted(z["labels"]) == ["deep_squat"] * 6 + ["standing_shoulder_abduction"] * 6
        assert list(z["case_ids"]) == list(range(1, 13))
    assert loaded == {"numpy", "sqlalchemy"}


def test_check_width_is_still_importable_from_cbr_stored() -> None:
    from casebase_store import check_width
    from cbr.stored import check_width as before

    assert before is check_width


def _subcommand(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found: argparse.ArgumentParser = sub.choices[name]
    return found


def test_editor_choices_written_out_are_the_maintenance_editors() -> None:
    from cbr.maintenance import EDITORS
    from posecbr.cli import build_parser

    parser = build_parser()
    trim = _subcommand(_subcommand(parser, "casebase"), "trim")
    train = _subcommand(parser, "train")
    for p in (trim, train):
        (editor,) = [a for a in p._actions if "--editor" in a.option_strings]
        assert editor.choices is not None and sorted(editor.choices) == sorted(EDITORS)


def test_unknown_choices_written_out_are_the_judges() -> None:
    """segment and watch offer the judges (from cbr.judges: building the parser loads no
    numpy); the default is the first, as in cbr.unknown."""
    from cbr.unknown import JUDGES
    from posecbr.cli import build_parser

    parser = build_parser()
    for name in ("segment", "watch"):
        (unknown,) = [
            a for a in _subcommand(parser, name)._actions if "--unknown" in a.option_strings
        ]
        assert unknown.choices is not None and tuple(unknown.choices) == JUDGES
        assert unknown.default == JUDGES[0]


# scikit-learn's algorithms (and the pandas and SciPy statistics it imports) serve `compare`
# alone: the classifiers follow its estimator protocol without importing it
# (cbr.estimator_protocol), so the commands that train or classify do not load it
NOT_FOR_CLASSIFYING = {"sklearn", "pandas"}


def test_train_loads_no_scikit_learn(tmp_path: Path) -> None:
    from casebase_store import open_store
    from cbr.stored import load_classifier

    db = tmp_path / "trained.sqlite"
    argv = ["train", str(CLIP.parent / "labels.csv"), "--db", str(db), "--subjects", "s01",
            "--labels", "deep_squat,standing_shoulder_abduction"]  # fmt: skip
    _, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert loaded.isdisjoint(NOT_FOR_CLASSIFYING), loaded
    store = open_store(db, readonly=True)
    try:
        clf = load_classifier(store, "default").classifier
    finally:
        store.close()
    # s01's 6 clips (3 correct, 3 incorrect) of each of the two activities
    assert sorted(clf.case_base_.labels) == ["deep_squat"] * 6 + ["standing_shoulder_abduction"] * 6


def test_classify_loads_no_scikit_learn(small_db: Path, tmp_path: Path) -> None:
    argv = ["classify", str(CLIP), "--db", str(small_db), "--json"]
    # nor SciPy's statistics and sparse graphs, which the case base editors use
    # (cbr.maintenance): classify edits no case base
    editors = {"scipy.stats", "scipy.sparse"}
    out, loaded = _run(
        f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path, (*HEAVY, *editors)
    )
    assert loaded.isdisjoint(NOT_FOR_CLASSIFYING | editors), loaded
    (result,) = json.loads(out)["results"]
    # the deep squat is one of the case base's own clips: its nearest case is itself
    assert result["label"] == "deep_squat"
    assert result["neighbours"][0]["distance"] == 0.0


def test_segment_loads_no_scikit_learn(small_db: Path, tmp_path: Path) -> None:
    # two activities are too few to calibrate the default judge on: the held-out one
    argv = ["segment", str(CLIP), "--db", str(small_db), "--unknown", "held-out", "--json"]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert loaded.isdisjoint(NOT_FOR_CLASSIFYING), loaded
    doc = json.loads(out)
    segments = doc["segments"]
    assert doc["frames"] == 73 and segments[0]["start_frame"] == 0
    assert segments[-1]["end_frame"] == 73
    # the deep squat goes down once (frames 11-66)
    assert sum(s["repetitions"] for s in segments) == 1


def test_watch_loads_no_scikit_learn(small_db: Path, shared_data: Path, tmp_path: Path) -> None:
    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    argv = ["watch", str(video), "--db", str(small_db), "--unknown", "held-out", "--speed", "0"]
    out, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert loaded.isdisjoint(NOT_FOR_CLASSIFYING), loaded
    lines = [json.loads(line) for line in out.splitlines()]
    assert lines[0]["start_frame"] == 0 and lines[-1]["end_frame"] == 65
    # three squats by hand (tests/fixtures/repetition_counts.json)
    assert sum(line["repetitions"] for line in lines) == 3


@pytest.mark.parametrize("given", ["folder", "json"])
def test_report_loads_no_scikit_learn(compared_three: Path, tmp_path: Path, given: str) -> None:
    """report draws its page from compare's results (a --json file's missing pictures too,
    by matplotlib); it loaded scikit-learn, pandas and SciPy all the same (the pictures module
    imported the comparison's, its methods among them, for a type)."""
    results = compared_three if given == "folder" else compared_three / "results.json"
    page = tmp_path / "report.html"
    argv = ["report", str(results), "--out", str(page)]
    _, loaded = _run(f"from posecbr.cli import main\nassert main({argv!r}) == 0", tmp_path)
    assert loaded.isdisjoint(NOT_FOR_CLASSIFYING | {"scipy"}), loaded
    text = page.read_text(encoding="utf-8")
    assert "cbr fluents/euclidean" in text  # THREE's one method
    # compare --out drew the accuracy and the confusion matrix; the pictures of a --json file
    # are drawn again from the results
    assert text.count('<img src="data:image/png;base64,') >= 2


def test_a_video_is_opened_without_pillow(shared_data: Path, tmp_path: Path) -> None:
    """extract and watch read a still picture's EXIF orientation with Pillow; a file that
    starts as a video does (MP4, AVI) is no picture, said without importing Pillow (which
    loads every format it reads to open one); a picture still goes through Pillow."""
    videos = [
        shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4",  # ftyp
        shared_data / "media" / "vtest.avi",  # RIFF ... AVI
    ]
    code = (
        "from features.pose_estimation.containers import picture_orientation\n"
        f"print([picture_orientation(p) for p in {[str(v) for v in videos]!r}])"
    )
    out, loaded = _run(code, tmp_path, ("PIL",))
    assert out.strip() == "[1, 1]" and loaded == set()
    picture = str(shared_data / "media" / "messi5.jpg")
    code = "from features.pose_estimation.containers import picture_orientation\n"
    out, loaded = _run(f"{code}print(picture_orientation({picture!r}))", tmp_path, ("PIL",))
    assert out.strip() == "1" and loaded == {"PIL"}
