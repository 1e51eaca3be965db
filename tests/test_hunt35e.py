"""A machine user's walk through every ``--json``: the same concept under the same key
(a stretch of frames as ``start_frame``/``end_frame``, a repetition count as ``count``),
values that are not known ``null``, checked against values worked out independently."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from features.poses import save_pose
from posecbr.cli import main
from tests.badinput import small_case_base
from tests.moves import clip
from tests.test_json_hunt import strict


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_classify_json_gives_a_piece_start_frame_and_end_frame(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that is a piece of its file (a labels CSV's start,end) was given as
    ``"frames": [start, end]``, where every other command's ``frames`` is a count: it now
    also has ``start_frame`` and ``end_frame`` (end exclusive), as reps, segment and describe
    name a stretch, in the results and in the summary's wrong clips; ``frames`` is kept. A
    whole file has none of the three."""
    rec = save_pose(clip("squat", 10.0), tmp_path / "squat.npz")  # 300 frames
    csv = tmp_path / "pieces.csv"
    # no activity of the case base is a squat: both pieces are answered wrong
    csv.write_text("path,label,start,end\nsquat.npz,squat,30,150\nsquat.npz,squat,150,291\n")
    assert main(["classify", str(csv), "--db", str(case_base), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    pieces = [(30, 150), (150, 291)]  # the rows written above
    got = [(r["start_frame"], r["end_frame"]) for r in doc["results"]]
    assert got == pieces
    assert [r["frames"] for r in doc["results"]] == [list(p) for p in pieces]  # kept
    wrong = doc["summary"]["wrong"]
    assert [(w["start_frame"], w["end_frame"], w["frames"]) for w in wrong] == [
        (a, b, [a, b]) for a, b in pieces
    ]
    assert main(["classify", str(rec), "--db", str(case_base), "--json"]) == 0
    whole = strict(capsys.readouterr().out)["results"][0]
    assert not {"frames", "start_frame", "end_frame"} & set(whole), whole


def test_casebase_list_json_gives_each_case_start_frame_and_end_frame(
    case_base: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase list --json`` gave each case's frames in its recording as ``"frames":
    [start, end]`` alone: ``start_frame`` and ``end_frame`` now, ``frames`` kept. The small
    case base holds whole clips: each case is frames 0 to its file's frame count, read here
    from the file itself."""
    assert main(["casebase", "list", "--db", str(case_base), "--json"]) == 0
    cases = strict(capsys.readouterr().out)["cases"]
    assert len(cases) == 9
    for c in cases:
        with np.load(c["source"]) as z:
            n = int(z["positions"].shape[0])
        assert (c["start_frame"], c["end_frame"], c["frames"]) == (0, n, [0, n]), c


def test_segment_json_names_each_segment_count_as_reps_does(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``reps --json`` names the repetition count ``count`` (its ``repetitions``: the list);
    a segment of ``segment --json`` had the count only as ``repetitions``. Each segment now
    has ``count`` too (``repetitions`` kept, the same number). Ten seconds of squats of
    2.5 s each, by construction (tests.moves): 4, in either command."""
    rec = save_pose(clip("squat", 10.0), tmp_path / "squat.npz")
    assert main(["segment", str(rec), "--db", str(case_base), "--json"]) == 0
    segments = strict(capsys.readouterr().out)["segments"]
    assert sum(s["count"] for s in segments) == 4, segments
    for s in segments:
        assert s["count"] == s["repetitions"] == len(s["repetition_frames"]), s
    assert main(["reps", str(rec), "--json"]) == 0
    reps = strict(capsys.readouterr().out)
    assert reps["count"] == len(reps["repetitions"]) == 4


def test_watch_lines_name_the_count_as_segment_does() -> None:
    """``watch``'s lines are ``segment``'s segments as they finish: ``count`` beside the
    ``repetitions`` kept."""
    from cbr.live import LiveSegment

    line = LiveSegment(0, 75, "squat", 0.9, 2, "two squats", 0.5).to_dict(25.0)
    assert (line["count"], line["repetitions"]) == (2, 2)
    assert (line["start_s"], line["end_s"]) == (0.0, 3.0)  # 75 frames at 25 fps


def test_reps_json_says_null_for_the_periodicity_of_no_period(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip that does not repeat (someone standing still) has no period (``period_s``
    null), so no autocorrelation at it: ``periodicity`` was 0.0, a measured "not periodic at
    all", and is null now. The squats repeat every 2.5 s (by construction), their
    periodicity a number."""
    still = save_pose(clip("still", 3.0), tmp_path / "still.npz")
    assert main(["reps", str(still), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    assert (doc["count"], doc["period_s"], doc["periodicity"]) == (0, None, None)
    squats = save_pose(clip("squat", 10.0), tmp_path / "squat.npz")
    assert main(["reps", str(squats), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    assert doc["period_s"] == pytest.approx(2.5, abs=0.1)
    assert 0.0 < doc["periodicity"] <= 1.0


def test_dad_json_gives_the_frame_count_as_the_other_commands_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``describe``, ``reps`` and ``segment`` give a clip's frame count as ``frames`` beside
    ``fps``; ``dad --json`` gave only ``duration_s``. It gives ``frames`` too: 300 for ten
    seconds at 30 fps (by construction), the same for a clip too short to judge (3 frames),
    whose document is printed with exit 1."""
    rec = save_pose(clip("squat", 10.0), tmp_path / "squat.npz")
    assert main(["dad", str(rec), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    assert (doc["fps"], doc["frames"], doc["duration_s"]) == (30.0, 300, pytest.approx(10.0))
    assert list(doc)[:7] == ["clip", "source", "status", "message", "fps", "frames",
                             "duration_s"]  # fmt: skip
    short = save_pose(clip("squat", 0.1), tmp_path / "short.npz")
    assert main(["dad", str(short), "--json"]) == 1
    doc = strict(capsys.readouterr().out)
    assert (doc["status"], doc["frames"]) == ("not enough data", 3)


def test_compare_results_give_each_piece_of_a_file_its_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare --json FILE`` named every piece of a file (a labels CSV's ``start,end``
    rows) by the file's name alone, in ``clips`` and ``explanations``: two squats cut from
    one recording could not be told apart. Each piece now has ``start_frame`` and
    ``end_frame``, as ``classify --json`` gives them (the rows written here), and ``report``
    reads the file back."""
    rows = ["path,label,subject,start,end"]
    for subject in ("s1", "s2", "s3"):
        for move in ("squat", "arm_abduction", "knee_lift"):
            name = f"{subject}_{move}.npz"
            save_pose(clip(move, 10.0), tmp_path / name)  # 300 frames
            rows += [f"{name},{move},{subject},0,150", f"{name},{move},{subject},150,300"]
    (tmp_path / "labels.csv").write_text("\n".join(rows) + "\n")
    results = tmp_path / "results.json"
    argv = ["compare", str(tmp_path / "labels.csv"), "--similarities", "euclidean",
            "--features", "fluents", "--no-dad", "--peers", "none", "--explain", "0",
            "--json", str(results)]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    doc = strict(results.read_text())
    got = {(c["clip"], c["start_frame"], c["end_frame"], c["label"]) for c in doc["clips"]}
    want = set()
    for row in rows[1:]:
        path, label, _, start, end = row.split(",")
        want.add((path, int(start), int(end), label))
    assert got == want and len(doc["clips"]) == 18
    capsys.readouterr()
    assert main(["report", str(results), "--out", str(tmp_path / "report.html")]) == 0


def test_compare_explanations_keep_the_frames_of_a_piece_when_read_back() -> None:
    """An explained piece's frames survive the results file (``posecbr report`` reads it)
    and name it for people, end inclusive, as classify names a piece; a whole file has no
    frames, as files written before."""
    from cbr.evaluation.results import ExplainedClip, Reader

    piece = ExplainedClip("a.npz", "s1", "squat", "squat", "lunge", "cbr", "why", None, (30, 90))
    d = piece.to_dict()
    assert (d["start_frame"], d["end_frame"]) == (30, 90)
    back = ExplainedClip.read(Reader("results.json"), strict(json.dumps(d)), "explanations[0]")
    assert back == piece and back.name == "a.npz frames 30-89"
    whole = ExplainedClip("a.npz", "s1", "squat", "squat", "lunge", "cbr", "why").to_dict()
    assert "start_frame" not in whole
    assert ExplainedClip.read(Reader("r.json"), whole, "e").frames is None


@pytest.mark.parametrize(("editor", "method"), [("renn", "RENN"), ("novelty-benefit", None)])
def test_casebase_trim_json_names_the_editor_as_the_option_does(
    case_base: Path, capsys: pytest.CaptureFixture[str], editor: str, method: str | None
) -> None:
    """``casebase trim --editor cnn --json`` said ``"method": "CNN"`` (``renn``: "RENN"), a
    spelling ``--editor`` refuses, and, unlike info, list and upgrade, not which store and
    case base it trimmed: ``editor`` as the option spells it, ``db`` and ``case_base`` now
    (``method`` kept)."""
    argv = ["casebase", "trim", "--db", str(case_base), "--json", "--dry-run",
            "--editor", editor]  # fmt: skip
    assert main(argv) == 0
    doc = strict(capsys.readouterr().out)
    assert (doc["db"], doc["case_base"], doc["editor"]) == (str(case_base), "default", editor)
    assert doc["method"] == (method or editor)
    assert doc["size_before"] == 9 and doc["dry_run"] is True and doc["changed"] is False


def test_casebase_export_json_says_which_case_base(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase export --json`` said where it wrote and how many cases, not which store
    and case base it read, which info, list and upgrade say: ``db`` and ``case_base`` now.
    Its ``cases``: the 9 clips the small case base was trained from (3 activities x 3)."""
    out = tmp_path / "cases.npz"
    assert main(["casebase", "export", "--db", str(case_base), "--out", str(out), "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    assert (doc["db"], doc["case_base"], doc["out"], doc["cases"]) == (
        str(case_base),
        "default",
        str(out),
        9,
    )
    with np.load(out) as z:
        assert len(z["labels"]) == 9


def test_segment_json_names_the_picture_it_drew_as_describe_and_reps_do(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``describe --json --plot`` and ``reps --json --plot`` name the picture (``plot``);
    ``segment --json --plot`` did not, and with several recordings a machine had to work out
    the name of each one's picture in the folder. Each recording's document now names it."""
    a = save_pose(clip("squat", 4.0), tmp_path / "a" / "squat.npz")
    b = save_pose(clip("squat", 4.0), tmp_path / "b" / "squat.npz")
    picture = tmp_path / "one.png"
    assert main(["segment", str(a), "--db", str(case_base), "--json", "--plot", str(picture)]) == 0
    doc = strict(capsys.readouterr().out)
    assert doc["plot"] == str(picture) and picture.is_file()
    folder = tmp_path / "pictures"
    folder.mkdir()
    argv = ["segment", str(a), str(b), "--db", str(case_base), "--json", "--plot", str(folder)]
    assert main(argv) == 0
    docs = strict(capsys.readouterr().out)
    # two recordings named alike: the second's picture numbered (plot_targets)
    assert [d["plot"] for d in docs] == [str(folder / "squat.png"), str(folder / "squat_2.png")]
    assert sorted(p.name for p in folder.iterdir()) == ["squat.png", "squat_2.png"]
    assert main(["segment", str(a), "--db", str(case_base), "--json"]) == 0
    assert "plot" not in strict(capsys.readouterr().out)


def test_segment_json_names_the_overlay_it_wrote(
    case_base: Path, shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--overlay`` likewise: the video written (the 65 frames of the squat video, counted
    by OpenCV) is named in the document."""
    import cv2

    video = shared_data / "videos" / "squat" / "tfjs_pose_squats_pexels4838220.mp4"
    out = tmp_path / "seen.mp4"
    argv = ["segment", str(video), "--db", str(case_base), "--json", "--overlay", str(out)]
    assert main(argv) == 0
    doc = strict(capsys.readouterr().out)
    assert doc["overlay"] == str(out) and "plot" not in doc
    cap = cv2.VideoCapture(str(video))
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    cap.release()
    assert doc["frames"] == n == 65
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == n
    cap.release()


def test_json_says_which_cases_are_mirror_images(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A case that is its clip's mirror image was told only by its ``source`` ending in
    " (mirrored)", which is then no file's name: ``casebase list --json`` and each of
    ``classify --json``'s neighbours and its contrast case now say ``mirrored``. Trained with
    ``--mirror augment``, each of the 9 clips is a case, and a mirror-image case unless it
    is its own mirror image (both arms alike)."""
    from tests.test_cbr_cli import _write_classes

    data = _write_classes(tmp_path / "train", 3, 5)
    db = tmp_path / "cb.sqlite"
    argv = ["train", str(data), "--db", str(db), "--mirror", "augment",
            "--feature-weights", "none", "--phases", "0"]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["casebase", "list", "--db", str(db), "--json"]) == 0
    cases = strict(capsys.readouterr().out)["cases"]
    clips = sorted(str(p) for p in data.rglob("*.npz"))
    assert len(clips) == 9 and len(cases) > 9
    assert sorted(c["source"] for c in cases if not c["mirrored"]) == clips
    images = [c["source"] for c in cases if c["mirrored"]]
    assert len(images) == len(cases) - 9
    assert all(i.endswith(" (mirrored)") and i.removesuffix(" (mirrored)") in clips for i in images)
    assert main(["classify", clips[0], "--db", str(db), "--json"]) == 0
    result = strict(capsys.readouterr().out)["results"][0]
    for case in [*result["neighbours"], result["contrast"]]:
        assert case["mirrored"] == case["source"].endswith(" (mirrored)"), case
