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
