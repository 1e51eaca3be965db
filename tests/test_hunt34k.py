"""Hunt 34k: small defects. A URL's password repeated in a message; a picture given to
``reps`` called an unknown clip format; an empty class folder a stopped ``extract --workers``
left; the report's "2 classes of correct"."""

from __future__ import annotations

import socket
import sys
import time
from pathlib import Path

import pytest

from features.text import hide_passwords, shown
from tests.badinput import refused, small_case_base


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _closed_port() -> int:
    """A local port nothing listens on (bound, then let go): a connection there is refused."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


# ------------------------------------------------------------------ passwords in URLs


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("http://me:secret@host/x.mp4", "http://me:***@host/x.mp4"),
        ("rtsp://:pw@cam.local:554/live", "rtsp://:***@cam.local:554/live"),
        ("https://me:p@ss@host/x.mp4: cannot open", "https://me:***@host/x.mp4: cannot open"),
        ("postgresql+psycopg://me:s3cret@db/cases", "postgresql+psycopg://me:***@db/cases"),
        (
            "postgresql://db/cases?password=s3cret: refused",
            "postgresql://db/cases?password=***: refused",
        ),
        ("see (http://a:b@c/d) and rtsp://x:y@z", "see (http://a:***@c/d) and rtsp://x:***@z"),
        # not passwords: a port, an "@" in the path, a user without one, no URL at all
        ("http://host:8080/x@y.mp4", "http://host:8080/x@y.mp4"),
        ("http://me@host/x.mp4", "http://me@host/x.mp4"),
        ("squat é: a@b:c@d", "squat é: a@b:c@d"),
    ],
)
def test_shown_hides_the_password_of_every_url(text: str, expected: str) -> None:
    """Every message is printed through ``shown``: it hid no password, so ``watch
    http://me:secret@host/x.mp4`` repeated the password in its error line."""
    assert hide_passwords(text) == expected
    assert shown(text) == expected


def test_watch_of_a_stream_url_with_a_password_hides_it(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch`` of a URL that cannot be opened named it with its password in clear."""
    port = _closed_port()
    url = f"http://coach:s3cret@127.0.0.1:{port}/x.mp4"
    line = refused(["watch", url, "--db", str(case_base), "--speed", "0"], tmp_path, capsys,
                   f"http://coach:***@127.0.0.1:{port}/x.mp4: ")  # fmt: skip
    assert "s3cret" not in line


def test_watch_of_a_stream_url_with_a_password_parameter_hides_it(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    port = _closed_port()
    url = f"rtsp://127.0.0.1:{port}/live?user=coach&password=s3cret"
    line = refused(["watch", url, "--db", str(case_base), "--speed", "0"], tmp_path, capsys,
                   f"rtsp://127.0.0.1:{port}/live?user=coach&password=***: ")  # fmt: skip
    assert "s3cret" not in line


# ------------------------------------------------------------------ a picture given as a clip


def _picture(path: Path) -> Path:
    import cv2
    import numpy as np

    assert cv2.imwrite(str(path), np.full((16, 16, 3), 128, np.uint8))
    return path


@pytest.mark.parametrize("name", ["picture.png", "photo.jpg"])
@pytest.mark.parametrize("command", ["reps", "describe"])
def test_a_picture_given_as_a_clip_is_said_to_be_one(
    command: str, name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``reps picture.png`` said "unknown clip format", as of a file of no known kind; it
    is a picture, as ``--db picture.png`` already says."""
    picture = _picture(tmp_path / name)
    said = f"{picture}: a PNG or JPEG picture, not a clip (expected .npz pose file"
    line = refused([command, str(picture)], tmp_path, capsys, said)
    assert "unknown clip format" not in line


def test_a_file_of_no_known_kind_is_still_an_unknown_clip_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = tmp_path / "notes.png"  # a picture's name, not its bytes
    other.write_text("not a picture\n")
    refused(["reps", str(other)], tmp_path, capsys, f"{other}: unknown clip format (expected")


# ------------------------------------------------------------------ extract stopped


@pytest.mark.skipif(sys.platform != "linux", reason="signals and /proc: Linux")
def test_a_stopped_extract_with_workers_removes_the_class_folders_it_made_empty(
    shared_data: Path, tmp_path: Path
) -> None:
    """``extract VIDEOS --out poses --workers 2`` sent SIGTERM once a worker is writing a
    pose file: the worker unwinds its clip, and the class folder it had made for it
    (``poses/edge/``) was left empty. Now each folder the run made and left empty goes; an
    empty folder that was there before (a class's, and one of the user's) stays."""
    from tests.test_hunt34i import _children, _command, _ended, _gone_soon, _hidden

    out = tmp_path / "poses"
    before = [out / "squat", out / "mine"]  # empty, made by the user before the run
    for folder in before:
        folder.mkdir(parents=True)
    argv = ["extract", str(shared_data / "videos"), "--out", str(out), "--workers", "2"]
    proc = _command(argv, tmp_path)
    while not _hidden(out) and proc.poll() is None:
        time.sleep(0.02)
    begun = _hidden(out)
    assert begun, "no file was begun"
    workers = _children(proc.pid)
    proc.terminate()
    got = _ended(proc, tmp_path)
    assert _gone_soon(workers) == []
    assert got == (143, "posecbr extract: terminated (SIGTERM)\n", "")
    left = sorted(p.relative_to(out).as_posix() for p in out.rglob("*"))
    # a clip another worker finished before the stop keeps its pose file (under load the first
    # file begun can be missed by the polling, and the stop comes a clip or two later)
    assert not [p for p in left if any(part.startswith(".") for part in p.split("/"))], left
    assert all(p.endswith(".npz") for p in left if "/" in p), left
    empty = [p for p in left if (out / p).is_dir() and not any((out / p).iterdir())]
    assert empty == ["mine", "squat"], (begun, left)


# ------------------------------------------------------------------ the report's first line

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_the_report_of_a_correctness_comparison_names_its_two_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare --target correct`` then ``report``: the page began "24 clips, 2 classes of
    correct"; the two values of the column (true and false in labels.csv) are correct and
    incorrect repetitions, and it says so."""
    import json

    from posecbr.cli import main

    run = tmp_path / "run.json"
    argv = ["compare", str(DEMO), "--labels", "deep_squat,hurdle_step", "--subjects", "s01,s02",
            "--target", "correct", "--peers", "none", "--no-dad", "--features", "fluents",
            "--similarities", "euclidean", "--explain", "0", "--json", str(run)]  # fmt: skip
    assert main(argv) == 0
    assert sorted(json.loads(run.read_text())["dataset"]["classes"]) == ["correct", "incorrect"]
    page = tmp_path / "r.html"
    assert main(["report", str(run), "--out", str(page)]) == 0
    capsys.readouterr()
    text = page.read_text()
    # 2 movements x 2 subjects x 6 clips (3 correct, 3 incorrect each)
    assert "<p>24 clips, correct and incorrect repetitions (one model per label), " in text
    assert "classes of" not in text


@pytest.mark.parametrize(
    ("classes", "target", "expected"),
    [
        (["correct", "incorrect"], "correct", "correct and incorrect repetitions"),
        (["false", "true"], "correct", "correct and incorrect repetitions"),
        (["kinect", "vicon"], "sensor", "<b>sensor</b>: kinect or vicon"),
        (["no", "yes"], "fallen", "<b>fallen</b>: no or yes"),  # no repetitions to judge
        (["a", "b", "c"], "grade", "3 classes of <b>grade</b>"),
        (["squat", "lunge", "plank"], "label", "3 activities"),
        (["squat", "lunge"], None, "2 activities"),
    ],
)
def test_what_the_report_says_the_clips_were_told_apart_by(
    classes: list[str], target: str | None, expected: str
) -> None:
    from cbr.evaluation.report import _classes_words

    assert _classes_words(classes, target) == expected
