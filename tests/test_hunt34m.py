"""Hunt 34m: review of the day's changes. A ``file:`` URL naming no file is refused as its
path is; ``extract --workers`` holds Ctrl-C back while its workers start, as ``compare``
does."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused, small_case_base


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_a_file_url_naming_no_file_is_refused_as_its_path_is(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch PATH`` of a file there is not says "PATH: no such video file"; ``watch
    file://PATH`` says the same line (it said "file://PATH: cannot open camera or stream",
    as of a camera)."""
    folder = tmp_path / "in"
    folder.mkdir()
    missing = folder / "no such" / "clip.mp4"
    expected = f"posecbr watch: error: {missing}: no such video file"
    for source in (str(missing), f"file://{missing}"):
        line = refused(["watch", source, "--db", str(case_base)], folder, capsys)
        assert line == expected


class _Pool:
    """A ProcessPoolExecutor that starts no process: each submit records whether Ctrl-C is
    blocked while it "starts a worker", and the first one is sent ``signum`` meanwhile."""

    def __init__(self, signum: int, submitted: list[bool], *_: object, **__: object) -> None:
        self.signum, self.submitted = signum, submitted
        self._processes: dict[int, object] = {}
        self.stopped = False

    def __enter__(self) -> _Pool:
        return self

    def __exit__(self, *_: object) -> None:
        pass

    def submit(self, fn: object, *args: object) -> object:
        import os
        import signal
        import time
        from concurrent.futures import Future

        blocked = signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])
        self.submitted.append(blocked)
        if len(self.submitted) == 1:
            os.kill(os.getpid(), self.signum)
            time.sleep(0.05)  # an unblocked signal's handler runs here
        done: Future[object] = Future()
        done.set_result(("done", Path("x"), "y"))
        return done

    def shutdown(self, wait: bool = True) -> None:
        self.stopped = True


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_extract_holds_ctrl_c_and_sigterm_back_while_its_workers_start(
    monkeypatch: pytest.MonkeyPatch, signame: str
) -> None:
    """``extract --workers``: a Ctrl-C (or SIGTERM) that comes while its worker processes
    are started is raised once all three are (KeyboardInterrupt, after the third submit),
    and Ctrl-C is blocked meanwhile (the workers inherit the block, so the terminal's Ctrl-C
    reaches the command alone), as for ``compare --jobs``. (SIGTERM was held; Ctrl-C was
    raised in the middle of starting the first worker, which printed a traceback.)"""
    import concurrent.futures
    import signal

    from features.interrupts import sigterm_as_interrupt, terminated
    from posecbr.commands import extract

    signum = getattr(signal, signame)
    submitted: list[bool] = []
    pools: list[_Pool] = []

    def pool(*args: object, **kwargs: object) -> _Pool:
        pools.append(_Pool(signum, submitted))
        return pools[-1]

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", pool)
    jobs = [extract.Job(Path(f"/no/such/v{k}.mp4"), Path(f"/no/such/v{k}.npz")) for k in range(3)]
    with sigterm_as_interrupt():
        with pytest.raises(KeyboardInterrupt):
            extract._in_processes(jobs, extract.Options(), 2)
        assert terminated() == (signame == "SIGTERM")
    assert submitted == [True, True, True]
    assert pools[0].stopped  # the workers stopped
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
