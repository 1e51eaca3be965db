"""Hunt 42g: a SIGTERM that comes as :func:`features.interrupts.interrupts_held` or
:func:`features.interrupts.interrupts_ignored_by_children` puts things back is raised only once
every one is back (it was raised in the middle: SIGINT left blocked, or ignored, or the
sentinel process left running, in a caller of ``posecbr.main()`` that goes on)."""

from __future__ import annotations

import signal
import subprocess
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from features import interrupts
from features.interrupts import (
    interrupts_held,
    interrupts_ignored_by_children,
    sigterm_as_interrupt,
    terminated,
)


@pytest.fixture(autouse=True)
def _signals_put_back() -> Iterator[None]:
    """This process's signal mask and SIGINT handler as they were after each test, whatever
    the code under test left (a failing test leaves no blocked Ctrl-C to the next ones)."""
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    handler = signal.getsignal(signal.SIGINT)
    yield
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    signal.signal(signal.SIGINT, handler)


def _sigterm_first(real: Callable[..., Any], when: Callable[..., bool]) -> Callable[..., Any]:
    """``real``, sent SIGTERM by this thread just before it does its work when
    ``when(*args)``: the handler there is runs before ``real`` is called (the Python code of
    a SIGTERM that came at that bytecode boundary)."""

    def sent_sigterm_first(*args: Any) -> Any:
        if when(*args):
            signal.raise_signal(signal.SIGTERM)
        return real(*args)

    return sent_sigterm_first


def test_sigterm_as_the_mask_is_put_back_leaves_ctrl_c_unblocked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """SIGTERM as ``interrupts_held`` sets the signal mask back (the command's handler
    raising KeyboardInterrupt): raised after the mask and the SIGINT handler are back. It was
    raised before the mask was set back (SIGTERM's handler put back first), and SIGINT stayed
    blocked."""
    before = signal.getsignal(signal.SIGINT)
    setmask = _sigterm_first(signal.pthread_sigmask, lambda how, _: how == signal.SIG_SETMASK)
    monkeypatch.setattr(signal, "pthread_sigmask", setmask)
    steps: list[str] = []
    with sigterm_as_interrupt():
        with pytest.raises(KeyboardInterrupt), interrupts_held():
            steps.append("workers started")
        assert terminated()
    monkeypatch.undo()
    assert steps == ["workers started"]
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    assert signal.getsignal(signal.SIGINT) is before


def test_sigterm_as_ctrl_c_is_taken_again_leaves_it_not_ignored(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """SIGTERM as ``interrupts_ignored_by_children`` sets SIGINT's handler back: raised after
    it is back, and the sentinel process ended. It was raised before, and SIGINT stayed
    ignored (Ctrl-C did nothing to the caller after)."""
    before = signal.getsignal(signal.SIGINT)
    real_signal = signal.signal
    handler_back = _sigterm_first(
        real_signal, lambda signum, handler: signum == signal.SIGINT and handler != signal.SIG_IGN
    )
    monkeypatch.setattr(signal, "signal", handler_back)
    with sigterm_as_interrupt():
        with pytest.raises(KeyboardInterrupt), interrupts_ignored_by_children():
            assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
        assert terminated()
    monkeypatch.undo()
    assert signal.getsignal(signal.SIGINT) is before


def test_sigterm_as_the_sentinel_is_ended_ends_it(monkeypatch: pytest.MonkeyPatch) -> None:
    """SIGTERM as ``interrupts_ignored_by_children`` ends its sentinel process: raised once it
    is ended and waited for. It was raised before it was killed, which left it running (a
    ``sleep`` of a day)."""
    sentinels: list[subprocess.Popen[bytes]] = []
    real_sentinel = interrupts._sentinel

    def sentinel() -> subprocess.Popen[bytes] | None:
        proc = real_sentinel()
        assert proc is not None
        sentinels.append(proc)
        real_kill = proc.kill
        monkeypatch.setattr(proc, "kill", _sigterm_first(real_kill, lambda: True))
        return proc

    monkeypatch.setattr(interrupts, "_sentinel", sentinel)
    try:
        with sigterm_as_interrupt():
            with pytest.raises(KeyboardInterrupt), interrupts_ignored_by_children():
                pass
            assert terminated()
        assert len(sentinels) == 1
        assert sentinels[0].poll() is not None  # ended (and waited for: its status known)
    finally:
        monkeypatch.undo()  # each sentinel's own kill again
        for proc in sentinels:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
