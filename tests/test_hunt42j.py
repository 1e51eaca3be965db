"""Hunt 42j: ``watch``'s handlers for Ctrl-C and SIGTERM
(:func:`posecbr.commands.watch.stop_on_interrupt`) set and put back as one: a SIGTERM that came
between setting the two left SIGINT's handler the watch's for an in-process caller (its first
Ctrl-C after only set an event nobody read), and a signal between putting them back left one
of them unrestored or was lost. A file that is no SQLite database is said with the option
it was given to (``casebase copy --to``), or none (``open_store``), not always ``--db``. A
case base, pose file or picture given where a text file goes (``report``, ``segment
--truth``, a labels CSV, the labels.csv in ``convert``'s folder) is said as what it is, not in
the codec's words."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from features.interrupts import raise_interrupt, sigterm_as_interrupt, terminated
from posecbr.commands.watch import stop_on_interrupt
from tests.test_hunt42g import _sigterm_first


@pytest.fixture(autouse=True)
def _handlers_put_back() -> Iterator[None]:
    """SIGINT's and SIGTERM's handlers as they were after each test, whatever the code under
    test left."""
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    for signum, handler in handlers.items():
        signal.signal(signum, handler)


def _the_watchs(handler: Any) -> bool:
    return getattr(handler, "__qualname__", "").startswith("stop_on_interrupt.")


def test_sigterm_as_the_handlers_are_set_stops_the_watch(monkeypatch: pytest.MonkeyPatch) -> None:
    """SIGTERM just before the watch's SIGTERM handler is set (SIGINT's already is): taken
    once both are set, as the watch's stop (said as SIGTERM); both handlers back after. It
    raised KeyboardInterrupt before the block, and SIGINT's handler stayed the watch's."""
    sigint_before = signal.getsignal(signal.SIGINT)
    with sigterm_as_interrupt():
        with monkeypatch.context() as patched:
            patched.setattr(
                signal,
                "signal",
                _sigterm_first(signal.signal, lambda s, h: s == signal.SIGTERM and _the_watchs(h)),
            )
            try:
                with stop_on_interrupt() as stop:
                    assert _the_watchs(signal.getsignal(signal.SIGINT))
                    assert stop.is_set() and stop.signum == signal.SIGTERM
            except KeyboardInterrupt:
                pytest.fail("the SIGTERM raised KeyboardInterrupt as the watch began")
        assert signal.getsignal(signal.SIGTERM) is raise_interrupt
    assert signal.getsignal(signal.SIGINT) is sigint_before


def test_sigterm_as_the_handlers_are_put_back_reaches_the_caller(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """SIGTERM just before SIGINT's handler is put back (the watch over): raised once both are
    back, to the caller's SIGTERM handler. It went to the watch's handler, which took it as a
    stop nobody would read: lost."""
    sigint_before = signal.getsignal(signal.SIGINT)
    with sigterm_as_interrupt():
        with monkeypatch.context() as patched:
            patched.setattr(
                signal,
                "signal",
                _sigterm_first(
                    signal.signal, lambda s, h: s == signal.SIGINT and h is sigint_before
                ),
            )
            with pytest.raises(KeyboardInterrupt), stop_on_interrupt() as stop:
                pass
        assert terminated() and not stop.is_set()
        assert signal.getsignal(signal.SIGTERM) is raise_interrupt
    assert signal.getsignal(signal.SIGINT) is sigint_before


def _ctrl_c_after(real: Callable[..., Any], when: Callable[..., bool]) -> Callable[..., Any]:
    """``real``, this thread sent SIGINT just after it has done its work when ``when(*args)``
    (a Ctrl-C that came at the next bytecode boundary)."""

    def ctrl_c_after(*args: Any) -> Any:
        done = real(*args)
        if when(*args):
            signal.raise_signal(signal.SIGINT)
        return done

    return ctrl_c_after


def test_ctrl_c_as_the_handlers_are_put_back_leaves_sigterms_back(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Ctrl-C just after SIGINT's handler is put back (the caller's: it raises
    KeyboardInterrupt): SIGTERM's handler is put back too. It was put back after SIGINT's,
    so never, and stayed the watch's."""
    sigint_before = signal.getsignal(signal.SIGINT)
    with sigterm_as_interrupt():
        with monkeypatch.context() as patched:
            patched.setattr(
                signal,
                "signal",
                _ctrl_c_after(
                    signal.signal, lambda s, h: s == signal.SIGINT and h is sigint_before
                ),
            )
            with pytest.raises(KeyboardInterrupt), stop_on_interrupt():
                pass
        assert not terminated()
        assert signal.getsignal(signal.SIGTERM) is raise_interrupt
    assert signal.getsignal(signal.SIGINT) is sigint_before


def test_a_pose_file_given_to_copy_to_is_said_as_given_to_to(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase copy --to clip.npz`` (a pose file where the copy goes): the line names
    ``--to`` as the option that takes the case base file; it named ``--db``, which was given
    the right file."""
    from tests.badinput import good_pose_file, refused, small_case_base

    db = small_case_base(tmp_path)
    clip = good_pose_file(tmp_path / "victim.npz")
    capsys.readouterr()  # what train said
    line = refused(["casebase", "copy", "--db", str(db), "--to", str(clip)], tmp_path, capsys,
                   "victim.npz: not a readable SQLite database (a NumPy file, such as a pose"
                   " file: --to takes the case base file)")  # fmt: skip
    assert "--db" not in line


def test_open_store_of_a_pose_file_names_no_option(tmp_path: Path) -> None:
    """``casebase_store.open_store`` given a pose file (a Python caller: no command line)
    says what the file is and nothing of ``--db``."""
    from casebase_store import StoreError, open_store
    from tests.badinput import good_pose_file

    clip = good_pose_file(tmp_path / "clip.npz")
    with pytest.raises(StoreError) as caught:
        open_store(clip)
    assert str(caught.value) == (
        f"{clip}: not a readable SQLite database (a NumPy file, such as a pose file)"
    )


def _sqlite_file(path: Path) -> Path:
    """A real SQLite database at ``path`` (a table, a row): what a case base file is."""
    import sqlite3

    con = sqlite3.connect(path)
    with con:
        con.execute("CREATE TABLE cases (x)")
        con.execute("INSERT INTO cases VALUES (1)")
    con.close()
    return path


def _png(path: Path) -> Path:
    """A real PNG picture at ``path`` (4 x 4, drawn by matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.imsave(path, np.zeros((4, 4)))
    return path


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ("cb.sqlite", "a SQLite database, such as a case base"),
        ("clip.npz", "a NumPy file, such as a pose file"),
        ("plot.png", "a PNG or JPEG picture"),
    ],
)
def test_report_given_a_binary_file_says_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], given: str, said: str
) -> None:
    """``report cb.sqlite`` (a case base where compare's results go): one line saying what
    the file is and what report takes. It printed the codec's "'utf-8' codec can't decode
    byte ..."."""
    from tests.badinput import good_pose_file, refused

    path = tmp_path / given
    {"cb.sqlite": _sqlite_file, "clip.npz": good_pose_file, "plot.png": _png}[given](path)
    line = refused(["report", str(path), "--out", str(tmp_path / "report.html")], tmp_path,
                   capsys, f"{given}: is {said}, not a results file (report takes a compare"
                   " --out folder or its results JSON file)")  # fmt: skip
    assert "codec" not in line


def test_report_given_other_non_text_says_where_it_stops_being_text(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A results file with a byte that is no UTF-8 (0xff, never in UTF-8) at byte 2: said by
    its byte, not in the codec's words."""
    from tests.badinput import refused

    path = tmp_path / "results.json"
    path.write_bytes(b'{"\xff": 1}')
    line = refused(["report", str(path), "--out", str(tmp_path / "report.html")], tmp_path,
                   capsys, "results.json: not a JSON results file (not UTF-8 text: invalid"
                   " start byte at byte 2)")  # fmt: skip
    assert "codec" not in line


def test_segment_truth_given_a_case_base_says_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``segment rec.npz --db cb.sqlite --truth cb.sqlite``: the case base is no label file,
    said so; it was "not UTF-8 text (...): save it as UTF-8", which it cannot be."""
    from tests.badinput import good_pose_file, refused, small_case_base

    db = small_case_base(tmp_path / "cb")
    capsys.readouterr()
    rec = good_pose_file(tmp_path / "rec.npz", frames=12)
    line = refused(["segment", str(rec), "--db", str(db), "--truth", str(db)], tmp_path,
                   capsys, "cb.sqlite: is a SQLite database, such as a case base, not a label"
                   " file")  # fmt: skip
    assert "save it as UTF-8" not in line


def test_compare_given_a_case_base_as_its_labels_csv_says_what_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare labels.csv`` where labels.csv is a SQLite database (a case base saved under
    the wrong name): said as one, not as "not UTF-8 text (invalid continuation byte ...)"."""
    from tests.badinput import refused

    labels = _sqlite_file(tmp_path / "labels.csv")
    refused(["compare", str(labels), "--out", str(tmp_path / "out")], tmp_path, capsys,
            "labels.csv: is a SQLite database, such as a case base, not a labels CSV")  # fmt: skip


def test_convert_into_a_folder_whose_labels_csv_is_a_case_base_says_so(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``convert ... --out DIR`` where DIR/labels.csv is a SQLite database: one line saying
    what it is; it printed the codec's "'utf-8' codec can't decode byte ...". The folder as it
    was."""
    from tests.badinput import refused

    asf = shared_data / "hdm05" / "train" / "3" / "HDM_bd.asf"
    amc = shared_data / "cmu-mocap6" / "amc" / "13_30.amc"
    out = tmp_path / "out"
    out.mkdir()
    _sqlite_file(out / "labels.csv")
    line = refused(["convert", str(amc), "--asf", str(asf), "--out", str(out)], out, capsys,
                   "labels.csv: cannot read the labels file already there (it is a SQLite"
                   " database, such as a case base)")  # fmt: skip
    assert "codec" not in line
