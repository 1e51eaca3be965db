"""Hunt 46f: small defects a previous session found and left.

1. ``watch VIDEO --max-frames N`` of a video of exactly N frames with nobody in view was taken
   as stopped by the limit (exit 0, a note that the frames after them were not watched),
   though the whole video was watched: it is refused as the same video is without
   ``--max-frames`` (README, watch).
2. ``train DATA --append --target corect`` gave no "did you mean 'correct'?" where ``train``,
   ``classify`` and ``compare`` without ``--append`` do.
3. ``train --append`` of a byte-identical copy of a stored clip's pose file under another
   file name stored it twice (the same clip was recognised by its file name, frames and
   features only): a clip whose frames and features are a stored case's is refused whatever
   either file is called, naming the case, nothing added.
4. ``cases_from`` read every case (no index on the cases' sources): stores get one; one made
   before is read as it is and ``casebase upgrade`` adds it.
5. ``extract DIR --out P --overlay O`` replaced a file of the user's at an overlay's place
   ``O/<class>/<video>.mp4`` in silence when the video's pose file was in P (a rerun with
   ``--force`` or other options): overlays now carry a mark (an MP4 ``uuid`` box), and a
   file there without the mark of that video is refused before any work.
6. A pose file's relative ``source_video`` was looked up from the current folder: ``extract``
   run in another folder whose video of that relative path is another video replaced the
   pose file in silence. Pose files record a digest of the video's resolved path now.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.test_hunt45v import _grey_video
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows


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


@pytest.fixture(scope="module")
def small_cases(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/badinput.py's small case base (three activities of synthetic arm movements,
    three clips each, in ``train/<activity>/clipNN.npz`` beside it); tests copy it."""
    from tests.badinput import small_case_base

    return small_case_base(tmp_path_factory.mktemp("small"))


def _case_of(db: Path, source: Path) -> tuple[int, int]:
    """The id and end frame of the case stored of ``source`` (read with sqlite3)."""
    import contextlib
    import sqlite3

    with contextlib.closing(sqlite3.connect(db)) as con:
        ((case_id, end),) = con.execute(
            "SELECT id, frame_end FROM cases WHERE source = ?", (str(source),)
        ).fetchall()
    return int(case_id), int(end)


def test_train_append_of_a_copy_under_another_name_is_refused_naming_the_case(
    small_cases: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One stored clip's pose file copied byte for byte as ``copy/<activity>/renamed.npz``:
    its append is refused in one line naming the case it repeats, the case base unchanged
    (before: added, 9 cases to 10, voting twice), told by its poses (since hunt 49d: by its
    features before); the same with the stored case's frames removed (told by its poses
    alone); a copy with one joint moved 5 cm in every frame is another clip, added."""
    import contextlib
    import dataclasses
    import shutil
    import sqlite3

    from features.poses import load_pose, save_pose
    from posecbr.cli import main
    from tests.badinput import refused

    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    original = sorted((small_cases.parent / "train").rglob("*.npz"))[0]
    copy = tmp_path / "copy" / original.parent.name / "renamed.npz"
    copy.parent.mkdir(parents=True)
    shutil.copyfile(original, copy)
    case_id, end = _case_of(db, original)
    argv = ["train", str(tmp_path / "copy"), "--db", str(db), "--append"]
    line = refused(argv, tmp_path, capsys)
    assert line == (
        f"posecbr train: error: {db}: {copy} frames 0-{end - 1} is already case {case_id} of "
        f"'default', stored as {original} frames 0-{end - 1} (the same frames and poses "
        "under another file name: a copy of its file?): nothing added"
    )
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute("UPDATE cases SET frame_start = NULL, frame_end = NULL")
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"is already case {case_id} of 'default', stored as {original} (the same poses "
        "under another file name: a copy of its file?): nothing added"
    )
    seq = load_pose(copy)
    moved = seq.positions.copy()
    moved[:, 0, 0] += 0.05
    save_pose(dataclasses.replace(seq, positions=moved), copy)
    assert main(argv) == 0
    with contextlib.closing(sqlite3.connect(db)) as con:
        assert con.execute("SELECT COUNT(*) FROM cases").fetchone() == (10,)


def test_store_finds_the_cases_of_given_frames_whatever_their_source(tmp_path: Path) -> None:
    """``cases_framed``: the active cases of the frames asked for, or stored without frames,
    whatever their source, by id, their features as stored (a missing value missing), 500 a
    list; a trimmed case and cases of other frames are not."""
    from casebase_store import NewCase, open_store

    rows = [("x.npz", 0, 9), ("conv1/y.npz", 0, 9), ("y.npz", 0, 20), ("z.npz", None, None),
            ("w.npz", 5, 9), ("old/x.npz", 0, 9)]  # fmt: skip
    many = [(f"m{i}.npz", 100, 200) for i in range(501)]
    store = open_store(tmp_path / "cb.sqlite", create=True)
    try:
        with store.transaction() as tx:
            info = tx.create_case_base(
                "default", {"f": 1}, ["a", "b"], ["a", "b"], {"name": "euclidean"}
            )
            new = [NewCase("l", np.array([i, np.nan]), s, a, b) for i, (s, a, b) in enumerate(rows)]
            new += [NewCase("l", np.array([i, -i]), s, a, b) for i, (s, a, b) in enumerate(many)]
            ids = tx.add_cases(info, new)
            tx.deactivate_cases(info, [ids[5]])
        with store.transaction() as tx:
            info = tx.case_base("default")
            found = list(tx.cases_framed(info, [(0, 9), (1, 9)]))
            chunks = list(tx.cases_framed(info, [(100, 200)]))
    finally:
        store.close()
    assert len(found) == 1
    assert [(c.id, c.source, c.frame_start, c.frame_end) for c in found[0]] == [
        (ids[0], "x.npz", 0, 9),
        (ids[1], "conv1/y.npz", 0, 9),
        (ids[3], "z.npz", None, None),
    ]
    np.testing.assert_array_equal(found[0][2].features, [3.0, np.nan])
    assert [len(c) for c in chunks] == [500, 2]  # 501 of those frames and z.npz's
    cases = [c for chunk in chunks for c in chunk]
    assert [c.id for c in cases] == sorted([ids[3], *ids[6:]])
    expected = [[3.0, np.nan]] + [[i, -i] for i in range(501)]
    np.testing.assert_array_equal(np.stack([c.features for c in cases]), expected)


def test_extract_overlay_folder_refuses_a_file_it_did_not_draw_and_redraws_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 12-frame grey video extracted into ``poses`` (no overlay); then, with a video of
    the user's at its overlay's place in ``ov``, ``--overlay ov --force`` is refused in one
    line, the file as it was (before: replaced in silence). Moved away, the overlay is
    drawn: it holds the mark (an MP4 ``uuid`` box: "extract " and the first 16 hex digits of
    the SHA-256 of the video's resolved path, read here from the file's last box), still
    reads as 12 frames, and a rerun with ``--force`` replaces it."""
    import hashlib
    import struct

    import cv2

    from posecbr.cli import main
    from tests.badinput import refused

    for folder in ("in", "ov"):
        (tmp_path / folder / "squat").mkdir(parents=True)
    video = _grey_video(tmp_path / "in" / "squat" / "clip.mp4", 12)
    theirs = _grey_video(tmp_path / "ov" / "squat" / "clip.mp4", 15)
    poses, ov = tmp_path / "poses", tmp_path / "ov"
    assert main(["extract", str(tmp_path / "in"), "--out", str(poses)]) == 0
    argv = ["extract", str(tmp_path / "in"), "--out", str(poses), "--overlay", str(ov)]
    capsys.readouterr()
    line = refused([*argv, "--force"], tmp_path, capsys)
    assert line == (
        f"posecbr extract: error: {theirs}: is already there, not an overlay posecbr extract "
        f"made of clip.mp4: extracting into {ov} would replace it; move it away, or choose "
        "another --overlay"
    )
    theirs.unlink()
    assert main([*argv, "--force"]) == 0
    digest = hashlib.sha256(str(video.resolve()).encode()).hexdigest()[:16]
    mark = b"extract " + digest.encode()
    box = struct.pack(">I4s", 8 + 16 + len(mark), b"uuid")
    marked = box + bytes.fromhex("cab5aa21f4394e688342e23fd7fa5c39") + mark
    assert theirs.read_bytes().endswith(marked)
    cap = cv2.VideoCapture(str(theirs))
    assert cap.get(cv2.CAP_PROP_FRAME_COUNT) == 12
    cap.release()
    assert main([*argv, "--force"]) == 0


def test_extract_from_another_folder_does_not_take_a_pose_file_of_its_video_for_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``extract videos --out ../poses`` run in d1, then in d2, whose ``videos/squat/clip.mp4``
    is another video (14 frames, not 12): the pose file's ``source_video`` (relative to d1)
    named d2's video when looked up from d2, so d1's pose file was replaced in silence.
    Refused now: the pose file records which file it was made of (a digest of its resolved
    path). A pose file made before that was recorded (the key removed) is still its own
    video's from the folder it was made in: up to date."""
    import dataclasses

    from features.poses import load_pose, save_pose
    from posecbr.cli import main
    from tests.badinput import refused

    for folder, frames in (("d1", 12), ("d2", 14)):
        (tmp_path / folder / "videos" / "squat").mkdir(parents=True)
        _grey_video(tmp_path / folder / "videos" / "squat" / "clip.mp4", frames)
    argv = ["extract", "videos", "--out", "../poses"]
    monkeypatch.chdir(tmp_path / "d1")
    assert main(argv) == 0
    monkeypatch.chdir(tmp_path / "d2")
    capsys.readouterr()
    line = refused(argv, tmp_path, capsys)
    assert line == (
        "posecbr extract: error: ../poses/squat/clip.npz: is already there, not a pose file "
        "posecbr extract made of clip.mp4: extracting into ../poses would replace it; move it "
        "away, or choose another --out"
    )
    pose = tmp_path / "poses" / "squat" / "clip.npz"
    seq = load_pose(pose)
    older = {k: v for k, v in seq.metadata.items() if k != "source_video_digest"}
    assert len(older) == len(seq.metadata) - 1
    save_pose(dataclasses.replace(seq, metadata=older), pose)
    monkeypatch.chdir(tmp_path / "d1")
    assert main(argv) == 0
    assert "0 extracted, 1 up to date" in capsys.readouterr().out


def test_casebase_upgrade_adds_the_index_on_sources_to_a_store_made_before(
    small_cases: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A store made today holds the index on its cases' sources; one made before (the index
    dropped) is read as it is (``casebase info`` writes nothing), and ``casebase upgrade``
    adds it, saying so, no case changed; run again, nothing to do. ``cases_from`` (read by
    the index, its rows sorted by id here) finds each clip's case, as sqlite3 reads them."""
    import contextlib
    import shutil
    import sqlite3

    from casebase_store import open_store
    from posecbr.cli import main

    def indexes(db: Path) -> set[str]:
        with contextlib.closing(sqlite3.connect(db)) as con:
            rows = con.execute("SELECT name FROM sqlite_master WHERE type = 'index'").fetchall()
        return {name for (name,) in rows}

    index = "ix_cases_case_base_id_source"
    assert index in indexes(small_cases)
    db = Path(shutil.copy(small_cases, tmp_path / "cb.sqlite"))
    with contextlib.closing(sqlite3.connect(db)) as con, con:
        con.execute(f"DROP INDEX {index}")
        cases = con.execute("SELECT id, source, frame_start, frame_end FROM cases").fetchall()
    before = db.read_bytes()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    assert db.read_bytes() == before
    capsys.readouterr()
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert capsys.readouterr().out == (
        f"{db}: added the index {index} of a newer schema (no case changed)\n"
    )
    assert index in indexes(db)
    assert main(["casebase", "upgrade", "--db", str(db)]) == 0
    assert capsys.readouterr().out == f"{db}: already schema version 2, nothing to do\n"
    store = open_store(db)
    try:
        with store.transaction() as tx:
            found = tx.cases_from(tx.case_base("default"), [s for _, s, _, _ in cases])
    finally:
        store.close()
    assert found == {(s, a, b): i for i, s, a, b in cases}
