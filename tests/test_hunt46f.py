"""Hunt 46f: small defects a previous session found and left.

1. ``watch VIDEO --max-frames N`` of a video of exactly N frames with nobody in view was taken
   as stopped by the limit (exit 0, a note that the frames after them were not watched),
   though the whole video was watched: it is refused as the same video is without
   ``--max-frames`` (README, watch).
2. ``train DATA --append --target corect`` gave no "did you mean 'correct'?" where ``train``,
   ``classify`` and ``compare`` without ``--append`` do.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


def _grey_video(path: Path, frames: int) -> Path:
    """A lossless video of ``frames`` plain grey frames at 10 fps: nobody in view."""
    from tests.test_video_vfr import _write

    grey = [np.full((48, 64, 3), 90, np.uint8) for _ in range(frames)]
    return _write(path, [100 * k for k in range(frames)], grey, rate=10)


def test_watch_max_frames_of_exactly_the_videos_length_refuses_nobody_in_view(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """25 grey frames (2.5 s): ``--max-frames 25``
    watches the whole video, refused as without the limit (before: exit 0, "--max-frames 25
    stopped the watch"); ``--max-frames 24`` leaves a frame unwatched: exit 0 and the note, as
    before."""
    from posecbr.cli import main
    from tests.badinput import assert_unchanged, snapshot

    video = _grey_video(tmp_path / "empty.mp4", 25)
    db = str(case_base)
    before = snapshot(tmp_path)
    argv = ["watch", str(video), "--db", db, "--speed", "0", "--out", str(tmp_path / "o.mp4")]
    capsys.readouterr()
    assert main([*argv, "--max-frames", "25"]) == 1
    captured = capsys.readouterr()
    assert captured.err == (
        f"posecbr watch: error: {video}: the stream ended after 25 frames (2.50 s) with nobody"
        " in view in any of them: no activity to label\n"
    )
    segments = [json.loads(line) for line in captured.out.splitlines()]
    assert [(s["start_frame"], s["end_frame"], s["unknown"]) for s in segments] == [
        (0, 25, "nobody in view")
    ]
    assert_unchanged(tmp_path, before)  # no video, no temporary
    assert main(["watch", str(video), "--db", db, "--speed", "0", "--max-frames", "24"]) == 0
    err = capsys.readouterr().err
    assert (
        f"note: {video}: nobody in view in the 24 frames (2.40 s) watched (--max-frames 24"
        " stopped the watch: the video's frames after them, if any, were not watched)"
    ) in err


def test_train_append_guesses_a_mistyped_target_from_the_datas_columns(
    case_base: Path,  # noqa: F811 - the fixture imported above
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A labels CSV with a ``correct`` column appended with ``--target corect`` to a case base
    of labels: refused, now with the guess ``train`` without ``--append`` gives (before:
    none); ``--target lable``: the case base's own target guessed."""
    import shutil

    from features.poses import save_pose
    from tests.badinput import refused
    from tests.moves import clip

    db = shutil.copy(case_base, tmp_path / "cb.sqlite")
    save_pose(clip("squat", 2.0, 30.0), tmp_path / "data" / "s.npz")
    labels = tmp_path / "data" / "train.csv"
    labels.write_text("path,label,correct\ns.npz,Squat,yes\n")
    argv = ["train", str(labels), "--db", str(db), "--append", "--target"]
    line = refused([*argv, "corect"], tmp_path, capsys)
    assert line == (
        "posecbr train: error: --target: case base 'default' predicts 'label', not 'corect': "
        "its cases cannot take --target corect (did you mean 'correct'?)"
    )
    line = refused([*argv, "lable"], tmp_path, capsys)
    assert line.endswith("cannot take --target lable (did you mean 'label'?)")
