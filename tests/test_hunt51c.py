"""Hunt 51c: a Dask scheduler address where a program listens that is no Dask scheduler.
Dask's client waits for the greeting of what it connected to without a deadline: a port
that takes the connection and says nothing (the scheduler's dashboard, 8787, for its 8786:
an HTTP server waits for a request line) hung the command for good."""

from __future__ import annotations

import shutil
import socket
import threading
from pathlib import Path

import pytest

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
        (tmp_path / "data" / "deep_squat").mkdir(parents=True)  # one clip: the command is quick
        shutil.copy(DEMO / "m01_s01_e01.npz", tmp_path / "data" / "deep_squat")
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
