"""Corpus work on Dask (issue 16): ``--scheduler`` for extract, train and compare on a real
LocalCluster of two worker processes, started once for the module (``local:2`` through
:func:`features.cluster.connect`; the commands reach it by its scheduler address). Results
equal those of a run in one process; failed units are named and the others finish; a worker
that dies has its task run again."""

from __future__ import annotations

import builtins
import hashlib
import io
import json
import logging
import os
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import features.pose_estimation  # noqa: F401  (silences FFmpeg before any video opens)
from casebase_store import open_store
from features.cluster import connect, gather, map_outcomes
from features.poses import load_pose, load_pose_arrays
from posecbr.cli import main
from tests import two_activities
from tests.badinput import refused
from tests.cluster_tasks import bookkeeping, fail_on_even, square_or_die_once
from tests.test_pose_extract import SQUAT, _cut

# under pytest-xdist the module's tests run on one worker: one LocalCluster for the module
pytestmark = pytest.mark.xdist_group("cluster")

pytest.importorskip("dask.distributed", reason="dask is in the test extra: pip install -e .[test]")

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
TWO = "deep_squat,standing_shoulder_abduction"


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    with connect("local:2") as c:
        c.wait_for_workers(2, timeout=120)
        yield c


@pytest.fixture(scope="module")
def address(client: Any) -> str:
    return str(client.scheduler.address)


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _cases(db: Path) -> tuple[Any, Any]:
    store = open_store(db, readonly=True)
    try:
        info, cases = store.load_case_base("default")
        return info, cases
    finally:
        store.close()


def test_train_on_the_cluster_stores_the_same_case_base_as_one_process(
    address: str, tmp_path: Path
) -> None:
    argv = ["train", str(LABELS), "--subjects", "s01,s02", "--labels", TWO, "--json"]
    assert main([*argv, "--db", str(tmp_path / "one.sqlite")]) == 0
    assert main([*argv, "--db", str(tmp_path / "dask.sqlite"), "--scheduler", address]) == 0
    info_1, one = _cases(tmp_path / "one.sqlite")
    info_d, dask = _cases(tmp_path / "dask.sqlite")
    assert len(one.ids) == 24
    np.testing.assert_array_equal(dask.features, one.features)  # bit for bit
    assert list(dask.labels) == list(one.labels) and list(dask.sources) == list(one.sources)
    assert list(dask.subjects) == list(one.subjects)
    assert info_d.model == info_1.model and info_d.feature_names == info_1.feature_names


def test_append_on_the_cluster_adds_the_same_cases(address: str, tmp_path: Path) -> None:
    base = ["train", str(LABELS), "--subjects", "s01,s02", "--labels", TWO]
    for name in ("one", "dask"):
        assert main([*base, "--db", str(tmp_path / f"{name}.sqlite")]) == 0
    more = ["train", str(LABELS), "--subjects", "s03", "--labels", TWO, "--append"]
    assert main([*more, "--db", str(tmp_path / "one.sqlite")]) == 0
    assert main([*more, "--db", str(tmp_path / "dask.sqlite"), "--scheduler", address]) == 0
    _, one = _cases(tmp_path / "one.sqlite")
    _, dask = _cases(tmp_path / "dask.sqlite")
    assert len(one.ids) == 36
    np.testing.assert_array_equal(dask.features, one.features)
    assert list(dask.sources) == list(one.sources)


def _with_bad_clips(tmp_path: Path) -> Path:
    """A labels CSV of six good clips and two broken pose files, the broken ones in the
    middle: a run that stopped at the first would not name the second."""
    good = sorted(DEMO.glob("m01_s01_*.npz"))[:3] + sorted(DEMO.glob("m07_s01_*.npz"))[:3]
    (tmp_path / "broken_a.npz").write_bytes(b"not a pose file")
    (tmp_path / "broken_b.npz").write_bytes(b"PK\x03\x04 cut short")
    rows = [f"{p},deep_squat,s01" for p in good[:3]]
    rows += [f"{tmp_path / 'broken_a.npz'},deep_squat,s01", f"{tmp_path / 'broken_b.npz'},x,s01"]
    rows += [f"{p},abduction,s01" for p in good[3:]]
    csv = tmp_path / "labels.csv"
    csv.write_text("path,label,subject\n" + "\n".join(rows) + "\n")
    return csv


def test_failed_clips_are_named_the_rest_finish_and_nothing_is_written(
    address: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    csv = _with_bad_clips(tmp_path)
    db = tmp_path / "cb.sqlite"
    before = {p.name: _sha(p) for p in tmp_path.iterdir()}
    assert main(["train", str(csv), "--db", str(db), "--scheduler", address]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert "Traceback" not in "\n".join(err)
    assert [ln for ln in err if "broken_a.npz" in ln] and [ln for ln in err if "broken_b.npz" in ln]
    assert err[-1] == ("posecbr train: error: 2 clips failed (listed above); nothing was written")
    assert len(err) == 3
    assert not db.exists()
    assert {p.name: _sha(p) for p in tmp_path.iterdir()} == before


def test_a_unit_that_fails_is_reported_by_name_and_the_others_finish(client: Any) -> None:
    items = [1, 2, 3, 4, 5]
    values, failed = gather(
        map_outcomes(client, fail_on_even, items, [f"item {i}" for i in items]), len(items)
    )
    assert values == [1, None, 3, None, 5]
    assert [(o.name, o.error) for o in failed] == [
        ("item 2", "ValueError: 2 is even"),
        ("item 4", "ValueError: 4 is even"),
    ]


def test_local_workers_keep_only_the_bookkeeping_a_batch_job_needs(client: Any) -> None:
    # Dask's defaults: a stack sample of the running task every 10 ms (the profiler), an
    # event-loop check every 20 ms, a host monitor every 500 ms, a memory check every 100 ms;
    # local:N turns the first off and runs the others every 1 s, 5 s and 500 ms
    periods = list(client.run(bookkeeping).values())
    assert len(periods) == 2
    for p in periods:
        assert "profile" not in p and "profile-cycle" not in p
        assert p["tick"] == 1000.0 and p["monitor"] == 5000.0
        assert p["memory_monitor"] == 500.0 and "heartbeat" in p


def test_a_worker_that_dies_has_its_task_run_again(client: Any, tmp_path: Path) -> None:
    items = list(range(6))
    values, failed = gather(
        map_outcomes(client, square_or_die_once, items, [str(i) for i in items], str(tmp_path)),
        len(items),
    )
    assert (tmp_path / "died").exists()  # a worker really died running item 3
    assert [(o.name, o.error) for o in failed] == [] and values == [0, 1, 4, 9, 16, 25]
    client.wait_for_workers(2, timeout=300)  # the nanny restarted it (slow on a loaded machine)


def test_a_worker_that_dies_with_the_only_copy_of_the_shared_input_is_survived(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # one worker: the scattered argument lives only there, so its death loses it and Dask
    # cancels the calls that needed it; they must be sent again, not reported as failed
    # what Dask's log prints (its scheduler's: in this process), to the stream its default
    # configuration gives the "distributed" logger outside pytest (stderr)
    said = io.StringIO()
    monkeypatch.setattr(logging.getLogger("distributed"), "handlers", [logging.StreamHandler(said)])
    with connect("local:1") as one:
        one.wait_for_workers(1, timeout=120)
        items = list(range(6))
        values, failed = gather(
            map_outcomes(one, square_or_die_once, items, [str(i) for i in items], str(tmp_path)),
            len(items),
        )
    assert (tmp_path / "died").exists()
    assert [(o.name, o.error) for o in failed] == [] and values == [0, 1, 4, 9, 16, 25]
    # and the run that survived it says nothing of it: Dask's scheduler, here in this
    # process, logged "lose scattered data" and "Couldn't gather keys" as ERRORs (hunt 46d)
    assert said.getvalue() == ""


def test_a_second_local_cluster_takes_a_free_port_without_a_warning(client: Any) -> None:
    # the module's cluster is up; another (a second command, a notebook's) starts beside it
    # without Dask's "Port 8787 is already in use" on the user's terminal
    assert client.submit(int, 1).result(timeout=60) == 1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with connect("local:1") as one:
            assert one.submit(int, 2).result(timeout=120) == 2
    said = [str(w.message) for w in caught if "already in use" in str(w.message)]
    assert said == []


def test_compare_on_the_cluster_predicts_as_one_process(address: str, tmp_path: Path) -> None:
    argv = ["compare", str(DEMO), "--labels", TWO,
            "--subjects", "s01,s02,s03", "--similarities", "euclidean", "--features",
            "fluents", "--peers", "none", "--no-dad", "--explain", "0"]  # fmt: skip
    assert main([*argv, "--json", str(tmp_path / "one.json")]) == 0
    assert main([*argv, "--json", str(tmp_path / "dask.json"), "--scheduler", address]) == 0
    one = json.loads((tmp_path / "one.json").read_text())
    dask = json.loads((tmp_path / "dask.json").read_text())
    assert len(one["clips"]) == 36
    assert dask["clips"] == one["clips"]
    for a, b in zip(dask["methods"], one["methods"], strict=True):
        assert a["name"] == b["name"] and a["predictions"] == b["predictions"]
        assert a["accuracy"] == b["accuracy"]


@pytest.fixture(scope="module")
def videos(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A class folder of two short real clips (6 and 8 frames of the squat video)."""
    data = tmp_path_factory.mktemp("videos") / "data"
    (data / "squat").mkdir(parents=True)
    _cut(shared_data / SQUAT, data / "squat" / "a.mp4", 8)
    _cut(shared_data / SQUAT, data / "squat" / "b.mp4", 6, start=20)
    return data


def test_extract_on_the_cluster_matches_one_process_and_resumes(
    address: str, videos: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    (data / "squat").mkdir(parents=True)
    for v in (videos / "squat").iterdir():
        os.symlink(v, data / "squat" / v.name)
    (data / "squat" / "c_bad.mp4").write_bytes(b"not a video")
    capfd.readouterr()
    assert main(["extract", str(data), "--out", str(tmp_path / "one")]) == 1
    assert main(["extract", str(data), "--out", str(tmp_path / "dask"), "--scheduler",
                 address]) == 1  # fmt: skip
    err = capfd.readouterr().err
    assert err.count("posecbr extract: error:") == 2 and err.count("c_bad.mp4") == 2
    for name, frames in (("a", 8), ("b", 6)):
        one = load_pose(tmp_path / "one" / "squat" / f"{name}.npz")
        dask = load_pose(tmp_path / "dask" / "squat" / f"{name}.npz")
        assert one.n_frames == frames and np.isfinite(one.positions).any()
        np.testing.assert_array_equal(dask.positions, one.positions)
        np.testing.assert_array_equal(dask.confidence, one.confidence)
        assert dask.metadata["label"] == "squat"
        images = [load_pose_arrays(tmp_path / d / "squat" / f"{name}.npz")["image_landmarks"]
                  for d in ("one", "dask")]  # fmt: skip
        np.testing.assert_array_equal(images[0], images[1])
    # a second run finds both outputs up to date and reads no video again
    stamps = {p: p.stat().st_mtime_ns for p in (tmp_path / "dask" / "squat").iterdir()}
    assert main(["extract", str(data), "--out", str(tmp_path / "dask"), "--scheduler",
                 address]) == 1  # fmt: skip
    out = capfd.readouterr()
    assert "0 extracted, 2 up to date, 1 failed" in out.err
    assert {p: p.stat().st_mtime_ns for p in (tmp_path / "dask" / "squat").iterdir()} == stamps


def test_a_workers_or_nannys_address_is_named_for_what_it_is(
    client: Any, address: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--scheduler`` given a worker's address (or its nanny's), as `dask worker` prints
    them: said so, with the worker's scheduler. Dask said "cannot reach the Dask scheduler
    at ... (Worker.identity() got an unexpected keyword argument 'n_workers')" under two
    warnings of its own ("Closing dangling stream")."""
    worker, info = next(iter(client.scheduler_info()["workers"].items()))
    two_activities(tmp_path / "data")
    argv = ["train", str(tmp_path / "data"), "--db", str(tmp_path / "cb.sqlite"), "--scheduler"]
    said = f"--scheduler: {worker} is a Dask worker's address, not the scheduler's"
    refused([*argv, worker], tmp_path, capsys, f"{said} (its scheduler: {address})")
    nanny = info["nanny"]
    said = f"--scheduler: {nanny} is a Dask nanny's address (the process that starts a worker)"
    refused([*argv, nanny], tmp_path, capsys, f"{said}, not the scheduler's")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("local:0", "local:N needs a whole number of workers >= 1, got 'local:0'"),
        ("local:two", "local:N needs a whole number of workers >= 1, got 'local:two'"),
    ],
)
def test_a_bad_scheduler_is_one_line_before_any_work(
    spec: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "cb.sqlite"
    for argv in (
        ["train", str(LABELS), "--db", str(db), "--scheduler", spec],
        ["extract", str(DEMO), "--out", str(tmp_path / "out"), "--scheduler", spec],
        ["compare", str(DEMO), "--scheduler", spec],
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_without_dask_the_scheduler_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    real_import = builtins.__import__

    def no_dask(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "dask" or name.startswith("dask."):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(LABELS), "--db", str(db), "--scheduler", "local:2"]) == 1
    err = capsys.readouterr().err
    assert err == (
        "posecbr train: error: --scheduler: needs dask.distributed, which is not installed "
        "(pip install 'posecbr[cluster]')\n"
    )
    assert not db.exists()
