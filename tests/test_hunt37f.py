"""Hunt 37f: issue 14's bad input (a recording shorter than a repetition, one with no
person, a label file that does not fit, a stream that ends or stalls) and a locked, damaged
or PostgreSQL case base, tried end to end on segment, reps, watch, train and extract.

- ``watch photo.jpg`` (a still picture, which ``segment`` refuses as "a PNG or JPEG picture,
  not a clip") loaded the pose model, ran it on the one frame and ended with "the stream
  ended after 1 frame (0.04 s), before the shortest window (1 s) of it was seen", as if a
  video had been cut short. Now refused at once, as a picture, naming the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.badinput import refused


def _picture(path: Path, fmt: str = ".png") -> Path:
    import cv2

    ok, data = cv2.imencode(fmt, np.full((48, 64, 3), 120, np.uint8))
    assert ok
    path.write_bytes(data.tobytes())
    return path


@pytest.mark.parametrize("name", ["photo.jpg", "photo.PNG", "snapshot"])
def test_watch_refuses_a_still_picture_as_a_picture(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fmt = ".png" if name.lower().endswith(".png") else ".jpg"
    photo = _picture(tmp_path / name, fmt)
    db = tmp_path / "cb.sqlite"
    db.write_bytes(b"not opened: refused before")
    refused(["watch", str(photo), "--db", str(db), "--out", str(tmp_path / "w.mp4")],
            tmp_path, capsys, f"{photo}: a PNG or JPEG picture, not a video")  # fmt: skip


def test_train_split_repetitions_calls_a_clip_too_short_for_one_a_clip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A clip of 0.2 s among clips of arm movements, cut into repetitions: stderr said "1 clip
    without a repetition kept whole", then stdout "skipped 1 repetition shorter than one
    movement can be (0.4 s): short.npz (lasts 0.20 s)": it is the clip, kept whole (a clip
    shorter than one repetition can be has none), that is skipped."""
    from features.poses import load_pose
    from posecbr.cli import main
    from tests.badinput import good_pose_file
    from tests.test_cbr_cli import _write_classes

    data = _write_classes(tmp_path / "train", 3, 3)
    first = sorted(p for p in data.iterdir() if p.is_dir())[0]
    short = good_pose_file(first / "short.npz", frames=6)
    seconds = load_pose(short).n_frames / load_pose(short).fps
    assert f"{seconds:.2f}" == "0.20"
    capsys.readouterr()
    code = main(["train", str(data), "--db", str(tmp_path / "cb.sqlite"), "--split",
                 "repetitions", "--mirror", "off", "--feature-weights", "none",
                 "--phases", "0"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "1 clip without a repetition kept whole" in err
    assert f"skipped 1 clip shorter than one movement can be (0.4 s): {short} (lasts 0.20 s)" in out
    assert "repetition shorter" not in out


URL = "http://coach:s3cret@127.0.0.1:9/squats.mp4"


@pytest.mark.parametrize(
    "argv",
    [
        ["segment", URL, "--db", "cb.sqlite", "--json"],
        ["reps", URL, "--json"],
        ["reps", "rtsp://coach:s3cret@cam.local/live", "--plot", "r.png"],
        ["train", URL, "--frame-labels", "labels.txt", "--label-block", "0.1", "--db", "cb.sqlite"],
        ["describe", URL],
        ["segment", "clip.npz", "--db", "cb.sqlite", "--plot", URL + ".png"],
    ],
)
def test_a_url_given_for_a_file_is_named_as_a_url_with_its_password_hidden(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``segment http://coach:s3cret@host/squats.mp4`` (a stream, which only ``watch`` plays)
    said "http:/coach:s3cret@host/squats.mp4: no such file": the URL read as a path (its "//"
    one "/"), the password shown. Now a usage error naming the URL, the password hidden."""
    from posecbr.cli import main

    with pytest.raises(SystemExit) as stop:
        main(argv)
    captured = capsys.readouterr()
    assert stop.value.code == 2 and captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "s3cret" not in captured.err, captured.err
    assert "://coach:***@" in lines[0] and "is a URL, not a path on this machine" in lines[0]


def test_extract_names_a_url_as_a_url_with_its_password_hidden(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract https://coach:s3cret@host/x.mp4`` said "https:/coach:s3cret@host/x.mp4: no
    such file or folder"."""
    refused(["extract", "https" + URL[4:], "--out", str(tmp_path / "x.npz")], tmp_path, capsys,
            "https://coach:***@127.0.0.1:9/squats.mp4: is a URL, not a path")  # fmt: skip
    assert "s3cret" not in str(list(tmp_path.iterdir()))


def test_a_labels_csv_naming_a_url_says_so_with_its_password_hidden(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A labels CSV row ``http://coach:s3cret@host/squats.mp4,squat``: "no such file
    http://coach:***@... (looked for http:/coach:s3cret@host/squats.mp4: paths are from the
    CSV's folder)", the password shown in the path looked for."""
    from tests.badinput import good_pose_file

    good_pose_file(tmp_path / "lunge.npz")
    csv = tmp_path / "labels.csv"
    csv.write_text(f"path,label\n{URL},squat\nlunge.npz,lunge\n", encoding="utf-8")
    said = f"{csv}: line 2: http://coach:***@127.0.0.1:9/squats.mp4 is a URL, not a file"
    line = refused(["train", str(csv), "--db", str(tmp_path / "cb.sqlite")], tmp_path, capsys, said)
    assert "s3cret" not in line
