"""Hunt 51c: a Dask scheduler address where a program listens that is no Dask scheduler.
Dask's client waits for the greeting of what it connected to without a deadline: a port
that takes the connection and says nothing (the scheduler's dashboard, 8787, for its 8786:
an HTTP server waits for a request line) hung the command for good."""

from __future__ import annotations

import logging
import socket
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from features.errors import ConfigError
from tests import two_activities
from tests.badinput import refused

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def test_a_port_that_takes_the_connection_and_says_nothing_is_refused_in_time(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("dask.distributed", reason="dask is in the test extra")
    monkeypatch.setattr("features.cluster.CONNECT_TIMEOUT_S", 0.5)
    monkeypatch.setattr("features.cluster.ANSWER_TIMEOUT_S", 0.5, raising=False)  # new
    said: list[str] = []
    failed: list[BaseException] = []
    # a listening socket never accepted from: the kernel takes the connection, nobody answers
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(1)
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        two_activities(tmp_path / "data")
        argv = ["train", str(tmp_path / "data"), "--db", str(tmp_path / "cb.sqlite")]

        def run() -> None:
            try:
                said.append(refused([*argv, "--scheduler", address], tmp_path, capsys))
            except BaseException as exc:  # said by the test below
                failed.append(exc)

        command = threading.Thread(target=run, daemon=True)
        command.start()
        command.join(timeout=20)
        assert not command.is_alive(), "the command hung on a port that never answered"
    assert failed == []
    assert said == [
        f"posecbr train: error: --scheduler: {address} took the connection but did not answer "
        "as a Dask scheduler (another program's port? Dask's scheduler listens on 8786, its "
        "dashboard on 8787)"
    ]


@pytest.fixture
def no_workers(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    """A scheduler of the user's with no worker (in this process: it starts in a blink), the
    client's wait for one cut to 0.3 s."""
    dd = pytest.importorskip("dask.distributed", reason="dask is in the test extra")
    monkeypatch.setattr("features.cluster.CONNECT_TIMEOUT_S", 0.3)
    with dd.LocalCluster(
        n_workers=0,
        processes=False,
        dashboard_address=None,
        scheduler_kwargs={"dashboard_address": ":0"},
        silence_logs=logging.CRITICAL,
    ) as cluster:
        yield cluster


NO_WORKER = (
    "the Dask cluster has no worker to run the work on (none joined its scheduler in time, or "
    "every one stopped mid-run): start workers and run the command again"
)


def test_a_cluster_without_workers_is_said_in_one_line(
    no_workers: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Dask's scheduler waits the client's timeout for a worker to send the shared arguments
    to, then raised TimeoutError("No valid workers found"): "internal error, a bug in
    posecbr", exit 70."""
    two_activities(tmp_path / "data")
    argv = ["train", str(tmp_path / "data"), "--db", str(tmp_path / "cb.sqlite")]
    address = no_workers.scheduler_address
    refused([*argv, "--scheduler", address], tmp_path, capsys, f"--scheduler: {NO_WORKER}")


def test_the_last_worker_stopping_mid_run_is_said(no_workers: Any) -> None:
    """The last worker gone (killed with its nanny, stopped) takes the shared arguments along;
    its units are sent again with them scattered anew, to no worker."""
    from features.cluster import connect, map_outcomes
    from tests.cluster_tasks import slow_add

    no_workers.scale(1)
    items = list(range(10))
    done: list[int | None] = []
    with pytest.raises(ConfigError) as caught, connect(no_workers.scheduler_address) as client:
        client.wait_for_workers(1, timeout=30)
        for outcome in map_outcomes(client, slow_add, items, [str(i) for i in items], 1000):
            done.append(outcome.value)
            if len(done) == 1:
                no_workers.scale(0)  # the last worker stops
    assert str(caught.value) == f"scheduler: {NO_WORKER}"
    assert len(done) < len(items)


@pytest.mark.parametrize(
    ("scheduler", "port"),
    [("tcp://127.0.0.1:99999", "99999"), ("127.0.0.1:0", "0"), ("tcp://me:pw@head:abc", "abc")],
)
def test_a_port_no_program_can_listen_on_is_refused_before_any_work(
    scheduler: str, port: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Dask tried to connect to port 0 or 99999 for 20 s, once the command had listed its
    clips, then said "Timed out trying to connect"; a port that is not a number was "cannot
    reach ... (invalid literal for int() with base 10: 'abc')"."""
    argv = ["train", str(DEMO / "labels.csv"), "--db", str(tmp_path / "cb.sqlite")]
    shown = scheduler.replace(":pw@", ":***@")
    line = refused([*argv, "--scheduler", scheduler], tmp_path, capsys)
    assert line == (
        f"posecbr train: error: --scheduler: the scheduler address {shown} has the port "
        f"'{port}': a port is a number from 1 to 65535 (Dask's scheduler listens on 8786)"
    )
