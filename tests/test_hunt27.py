"""Left by the hunts of session 26 and fixed in session 27. Each test says what happened
before its fix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sqlalchemy.engine import make_url

from cbr.segmentation import BLOCK_S, _frames_of
from features.label_tracks import frame_labels
from tests.badinput import refused
from tests.test_store_postgres import pg_server as pg_server  # noqa: F401  (fixture)
from tests.test_store_postgres import pg_url as pg_url  # noqa: F401  (fixture)


@pytest.mark.parametrize("fps", [5.0, 24.0, 25.0, 29.97, 30.0, 60.0, 120.0])
def test_segment_frames_are_the_label_files_blocks(fps: float) -> None:
    """A segment's frames are those a label file gives its 0.1-s blocks (one label per
    block, label t covering [t, t + 1) x 0.1 s). Before, the segment's first frame was
    rounded half to even: at 25 fps (2.5 frames a block) block 1 began at frame 2, whose
    time, 0.08 s, is in block 0, and block 3 at frame 8 while frame 7 (0.28 s) is in it."""
    n_frames = 997
    n_blocks = int(np.ceil(n_frames / (fps * BLOCK_S) - 1e-9))
    labels = [str(i) for i in range(n_blocks)]
    block = frame_labels(labels, n_frames, fps, BLOCK_S, "labels.txt").astype(np.int64)
    for b in range(n_blocks):  # at 5 fps every other block holds no frame: [f, f)
        want = np.searchsorted(block, [b, b + 1])
        assert _frames_of(b, b + 1, fps, n_frames) == tuple(want), b
    assert _frames_of(0, n_blocks, fps, n_frames) == (0, n_frames)


def test_compare_jobs_with_a_scheduler_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare --jobs 4 --scheduler local:1`` ran the folds on the one-worker cluster and
    said nothing of ``--jobs`` (hunt 27c): the two ask for different workers; refused in one
    line before any clip is read, nothing written."""
    data = tmp_path / "data"
    data.mkdir()
    (data / "labels.csv").write_text("path,label\nmissing.npz,squat\n")  # never read
    argv = ["compare", str(data / "labels.csv"), "--jobs", "4", "--scheduler", "local:1",
            "--out", str(tmp_path / "out")]  # fmt: skip
    refused(argv, tmp_path, capsys, "--jobs", "local:1")


def test_a_postgresql_session_ended_mid_transaction_says_the_connection_was_lost(
    pg_url: str,
) -> None:
    """The server ending the session of a command in its transaction (an administrator's
    ``pg_terminate_backend``, a restart) was "database error: terminating connection due to
    administrator command" (hunt 27c): it says the connection was lost, and the store
    names the database without its password."""
    from sqlalchemy import create_engine, text

    from casebase_store import StoreError, open_store

    store = open_store(pg_url, create=True)
    other = create_engine(pg_url, isolation_level="AUTOCOMMIT")
    try:
        with pytest.raises(StoreError) as err, store.transaction() as tx:
            pid = tx.session.execute(text("SELECT pg_backend_pid()")).scalar_one()
            with other.connect() as conn:
                conn.execute(text("SELECT pg_terminate_backend(:p)"), {"p": pid})
            tx.session.execute(text("SELECT 1"))
    finally:
        other.dispose()
        store.close()
    message = str(err.value)
    assert "the connection to the database server was lost" in message, message
    password = make_url(pg_url).password
    assert not password or str(password) not in message


def test_overlay_words_beyond_ascii_are_drawn_not_question_marks() -> None:
    """``watch --out`` and the overlays wrote every label and fluent word with OpenCV's font,
    which has ASCII only: an activity named "élévation" or "Kniebeuge – tief" came out with
    question marks for its letters (hunt 27c). Drawn in DejaVu Sans it is not what OpenCV's
    font makes of it, and lies on the line an ASCII word does."""
    import cv2

    from features.pose_estimation.overlay import draw_pose

    nobody = np.full((33, 5), np.nan)
    word = "élévation – tief"

    def drawn(text: str) -> np.ndarray:
        image = np.zeros((240, 640, 3), dtype=np.uint8)
        draw_pose(image, nobody, [text])
        return image[22:]  # below the "no person" line (its baseline at row 18)

    opencv = np.zeros((240, 640, 3), dtype=np.uint8)  # what OpenCV's font draws of the word
    for colour, width in (((0, 0, 0), 4), ((255, 255, 255), 1)):  # as draw_pose outlines
        cv2.putText(opencv, word, (12, 36), cv2.FONT_HERSHEY_SIMPLEX, 0.42, colour, width,
                    cv2.LINE_AA)  # fmt: skip
    accented, plain = drawn(word), drawn("elevation")
    assert (accented != opencv[22:]).any()
    rows = np.flatnonzero(accented.any(axis=(1, 2)))
    plain_rows = np.flatnonzero(plain.any(axis=(1, 2)))
    assert rows.size and plain_rows.size
    # the same line: the baselines (the last rows of letters without descenders) agree
    assert abs(int(rows.max()) - int(plain_rows.max())) <= 4, (rows, plain_rows)
