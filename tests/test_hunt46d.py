"""Hunt 46d: concurrency and stores. A store error partway through ``classify --feedback``
says whose feedback it stored before it (each clip's is one transaction): said alone
("database is locked"), the user ran the command again and the clips learnt before it were
learnt from twice (a case retained from a clip was moved toward that same clip again)."""

from __future__ import annotations

import asyncio
import logging
import sqlite3
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from casebase_store import StoreError, open_store
from cbr.classification import FeedbackSettings, classify_with_feedback
from cbr.stored import load_classifier
from features.errors import ConfigError
from features.poses import PoseSequence, load_pose
from posecbr.cli import main
from tests.badinput import refused
from tests.once import made_once

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/test_feedback_safety.py's case base (two subjects' clips), made once a session."""

    def make(folder: Path) -> Path:
        db = folder / "cb.sqlite"
        assert main(["train", str(LABELS), "--db", str(db), "--subjects", "s01,s02"]) == 0
        return db

    return made_once(tmp_path_factory, "feedback-safety-trained", make)


class _LockedAfterFirst(list[PoseSequence]):
    """Clips whose iteration, once the first clip's feedback is done, has another process's
    connection take the case base file's exclusive lock (as a writer holding it would)."""

    def __init__(self, clips: list[PoseSequence], db: Path) -> None:
        super().__init__(clips)
        self.db = db
        self.holder: sqlite3.Connection | None = None

    def __iter__(self) -> Iterator[PoseSequence]:
        for i, clip in enumerate(list.__iter__(self)):
            if i == 1:
                self.holder = sqlite3.connect(self.db, isolation_level=None)
                self.holder.execute("BEGIN EXCLUSIVE")
            yield clip


def test_a_store_error_midway_says_whose_feedback_is_stored(trained: Path, tmp_path: Path) -> None:
    db = tmp_path / "cb.sqlite"
    db.write_bytes(trained.read_bytes())
    paths = [DEMO / "m03_s03_e01.npz", DEMO / "m03_s03_e02.npz"]
    clips = _LockedAfterFirst([load_pose(p) for p in paths], db)
    store = open_store(db, timeout_s=0.2)
    try:
        stored = load_classifier(store, "default")
        with pytest.raises(StoreError) as caught:
            classify_with_feedback(
                store, stored, clips, "inline_lunge", FeedbackSettings()
            )  # fmt: skip
    finally:
        store.close()
        assert clips.holder is not None
        clips.holder.execute("ROLLBACK")
        clips.holder.close()
    said = str(caught.value)
    assert said.startswith(f"{db}: database is locked by another process")
    assert said.endswith(
        "before it, the feedback of 1 of the 2 clips is stored in the case base (the last: "
        "m03_s03_e01.npz); the others' is not"
    )
    # the store holds the first clip's feedback and no more: as the same feedback given to
    # the first clip alone leaves a copy of the case base
    alone = tmp_path / "alone.sqlite"
    alone.write_bytes(trained.read_bytes())
    argv = ["classify", str(paths[0]), "--db", str(alone), "--feedback", "inline_lunge"]
    assert main([*argv, "--quiet"]) == 0
    got, want = _state(db), _state(alone)
    assert got[0] == want[0] and len(got[0]) > 1  # the log's entries after the build
    np.testing.assert_array_equal(got[1], want[1])  # every case's features, bit for bit
    assert got[2] == want[2]


def _state(db: Path) -> tuple[list[tuple[str, int | None, str]], np.ndarray, list[str]]:
    """A case base's maintenance log (action, case, reason), features and labels."""
    reader = open_store(db, readonly=True)
    try:
        log = [(e.action, e.case_id, e.reason) for e in reader.maintenance_log("default")]
        cases = reader.load_cases("default")
        return log, cases.features, [str(v) for v in cases.labels]
    finally:
        reader.close()


@pytest.mark.parametrize(
    ("argv", "db"),
    [
        (["classify", str(DEMO / "m01_s01_e01.npz")], "postgresql+psycopg:/me:s3cret@dbhost/cbr"),
        (["train", str(LABELS)], "postgresql+psycopg:/me:s3cret@dbhost/cbr"),
        (["train", str(LABELS)], "postgresql:me:s3cret@dbhost"),
        (["casebase", "info"], "postgresql+psycopg//me:s3cret@dbhost/cbr"),
    ],
)
def test_a_database_url_missing_its_slashes_is_refused_without_its_password(
    argv: list[str],
    db: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Taken for a file's name, the URL was printed whole ("no such case base file", "folder
    does not exist"), password and all, or `train` made a file of that name."""
    monkeypatch.chdir(tmp_path)
    line = refused([*argv, "--db", db], tmp_path, capsys, "not a database URL", ":***@dbhost")
    assert "s3cret" not in line


def test_a_scheduler_lost_mid_run_is_said_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capfd: pytest.CaptureFixture[str]
) -> None:
    """A scheduler of the user's (``--scheduler tcp://...``) that stops while the command's
    units run: a ConfigError naming it, and nothing of Dask's on stderr. Before, the command
    died of Dask's CommClosedError ("internal error, a bug in posecbr", exit 70) under the
    client's own tracebacks of its tries to reconnect.

    And it ends: the client that gives up the lost scheduler cancels the units it holds, and
    each is sent again (as a unit whose worker died is); one sent after the client's close
    cancelled its units, before the client is closed, never finishes, and Dask's
    ``as_completed`` waited for it for good (a CI worker hung so, once in many runs). Here the
    client's close waits half a second there (its connection pool closes late), so that the
    units are sent again in that window every time."""
    dd = pytest.importorskip("dask.distributed", reason="dask is in the test extra")
    from features.cluster import connect, map_outcomes
    from tests.cluster_tasks import slow_square

    # the client tries to reconnect as long as it waits to connect (20 s) before it gives up
    monkeypatch.setattr("features.cluster.CONNECT_TIMEOUT_S", 1)
    items = list(range(40))
    done: list[int | None] = []
    ended: list[BaseException] = []
    # the user's scheduler and worker, as far as the command knows (in this process: they
    # start in a blink)
    with dd.LocalCluster(
        n_workers=1,
        processes=False,
        threads_per_worker=1,
        dashboard_address=None,
        scheduler_kwargs={"dashboard_address": ":0"},
        silence_logs=logging.CRITICAL,
    ) as theirs:
        address = str(theirs.scheduler_address)

        def run() -> None:
            try:
                with connect(address) as client:
                    _closed_late(client, 0.5)
                    for outcome in map_outcomes(
                        client, slow_square, items, [str(i) for i in items]
                    ):
                        done.append(outcome.value)
                        if len(done) == 1:
                            theirs.close()  # the scheduler and its worker stop
            except BaseException as exc:  # whatever it is, the test says it
                ended.append(exc)

        command = threading.Thread(target=run, daemon=True)
        command.start()
        command.join(timeout=30)
        assert not command.is_alive(), "the command hung once its scheduler was lost"
    assert len(ended) == 1 and isinstance(ended[0], ConfigError), ended
    assert str(ended[0]) == (
        f"scheduler: lost the Dask scheduler at {address} mid-run (it stopped, or the "
        "network to it failed): run the command again once it is back"
    )
    assert len(done) < len(items)  # it stopped before the units were done
    assert "distributed.client" not in capfd.readouterr().err


def _closed_late(client: Any, delay_s: float) -> None:
    """``client``'s first close waits ``delay_s`` after it has cancelled the futures it holds
    and before it is closed (its connection pool's close, the step between, made slow)."""
    close = client.rpc.close
    waited: list[float] = []

    async def late(*args: Any, **kwargs: Any) -> Any:
        if not waited:
            waited.append(delay_s)
            await asyncio.sleep(delay_s)
        return await close(*args, **kwargs)

    client.rpc.close = late


@pytest.mark.parametrize("scheduler", ["tcp://me:s3cret@127.0.0.1:1", "me:s3cret@127.0.0.1:1"])
def test_a_scheduler_address_with_a_password_is_refused_without_it(
    scheduler: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Dask repeats the address without its scheme ("invalid address 'me:s3cret@...'"),
    which the URL password rule missed; one given without a scheme was no URL to it."""
    pytest.importorskip("dask.distributed", reason="dask is in the test extra")
    argv = ["train", str(LABELS), "--db", str(tmp_path / "cb.sqlite"), "--scheduler", scheduler]
    line = refused(argv, tmp_path, capsys, "cannot reach the Dask scheduler at", "me:***@")
    assert "s3cret" not in line


def test_a_killed_extract_worker_is_said_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """`extract --workers 2` whose worker process dies (the kernel's out-of-memory killer,
    kill -9): one line, exit 1, no folder left (as `compare --jobs` says it). Before: the
    pool's BrokenProcessPool, "internal error, a bug in posecbr", exit 70."""
    from tests.cluster_tasks import die
    from tests.test_hunt35f import _tiny_video

    data = tmp_path / "data"
    for label in ("squat", "lunge"):
        (data / label).mkdir(parents=True)
        _tiny_video(data / label / "take.avi")
    # each worker runs the task it is sent by name: this one dies running it
    monkeypatch.setattr("posecbr.commands.extract.run_task", die)
    argv = ["extract", str(data), "--out", str(tmp_path / "poses"), "--workers", "2"]
    refused(argv, tmp_path, capsys, "--workers (--jobs): a worker process died")


@pytest.mark.parametrize("scheduler", ["lokal:2", "Local:2", "local2"])
def test_local_n_mistyped_is_refused_at_once_with_a_suggestion(
    scheduler: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Dask read it as host "lokal", port 2, and the command waited 20 s to connect, then
    said it could not reach a scheduler there."""
    argv = ["train", str(LABELS), "--db", str(tmp_path / "cb.sqlite"), "--scheduler", scheduler]
    refused(argv, tmp_path, capsys, f"--scheduler: {scheduler!r} is neither local:N nor a "
            "scheduler address (did you mean local:2?)")  # fmt: skip


def test_a_missing_postgresql_driver_other_than_psycopg_is_not_promised_by_the_extra(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--db postgresql+pg8000://...`` without pg8000 said "(pip install 'posecbr[postgres]')",
    which installs psycopg 3, not pg8000: the hint now says to install that driver or write
    the URL for psycopg, the driver the extra installs (and keeps the extra's hint where it
    is the one missing)."""
    import importlib.util

    if importlib.util.find_spec("pg8000") is not None:
        pytest.skip("pg8000 is installed here: nothing is missing to hint at")
    line = refused(
        ["casebase", "info", "--db", "postgresql+pg8000://me:PW@localhost/db"],
        tmp_path,
        capsys,
        "the database driver for postgresql+pg8000 is not installed",
        "install that driver, or write the URL as postgresql+psycopg://",
    )
    assert "PW" not in line
