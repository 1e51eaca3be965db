from __future__ import annotations

import os
import resource
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.once import made_once

if TYPE_CHECKING:
    from cbr.estimator import CaseBaseClassifier
    from features.poses import PoseSequence

# The suite runs one process per core (pytest-xdist), and the commands and workers the tests
# start are more processes. A BLAS or OpenMP pool of every core in each of them oversubscribes
# the machine: OpenBLAS's threads spin while they wait, and tests/test_similarity_fast.py took
# 62 s on 2 workers against 18 s with one thread each (2 cores). Set before any worker starts,
# so every process the suite starts inherits it.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))


def _write_bytecode() -> None:
    """Python's compiled modules (``__pycache__/*.pyc``, beside numba's cache there) written
    and read by this process and every process it starts, though PYTHONDONTWRITEBYTECODE is
    set: without them every xdist worker compiled the ~300 test modules it collects (12.4 s
    of CPU instead of 5.2) and every command a test starts compiled the project's modules
    (0.3-0.4 s of each ``python -m posecbr``). ``.gitignore`` leaves ``__pycache__`` out."""
    import sys

    if os.environ.pop("PYTHONDONTWRITEBYTECODE", None) is not None:
        sys.dont_write_bytecode = False


def _ctrl_c_as_in_a_terminal() -> None:
    """Ctrl-C (SIGINT) raises KeyboardInterrupt in this process, and is not ignored by the
    processes it starts (xdist's workers, the commands the tests run), as for a job in the
    foreground of a terminal, which the tests that send it rely on. A shell without job
    control (a script, ``bash -c``) starts a background job (``pytest ... &``) with SIGINT
    ignored, and an ignored signal stays ignored in Python and in every process started from
    it: there a SIGINT did nothing, and such a test failed (``describe`` sent SIGINT exited 0,
    not 130)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_configure(config: pytest.Config) -> None:
    """Before the xdist workers start, :func:`_ctrl_c_as_in_a_terminal`,
    :func:`_write_bytecode`, and numba's kernels are compiled once, in two processes at a
    time (``tests/_kernels.py``): otherwise every worker, every Dask worker and every command
    a test starts before a cache is written compiles them again (about 50 s of CPU each,
    cold). Not in a worker, nor without workers (``-n 0``: the one process compiles)."""
    _ctrl_c_as_in_a_terminal()
    _write_bytecode()
    if os.environ.get("PYTEST_XDIST_WORKER") or not config.getoption("numprocesses", None):
        return
    import subprocess
    import sys

    procs = [
        subprocess.Popen([sys.executable, "-m", "tests._kernels", part], cwd=ROOT)
        for part in ("fluents", "search")
    ]
    for proc in procs:
        proc.wait()  # a failure shows in the tests themselves


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The read-only real datasets beside the project (``../shared/data``)."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data folder {SHARED_DATA} is not on this machine")
    return SHARED_DATA


@pytest.fixture(scope="module")
def arm_k3() -> tuple[CaseBaseClassifier, PoseSequence, list[str]]:
    """A classifier of k = 3 fitted on three arm clips of each of the synthetic arm
    movements (``tests.test_cbr_clips.arm_dataset``, seed 3), those clips one after the other
    as one recording, and their labels."""
    import numpy as np

    from cbr.estimator import CaseBaseClassifier
    from features.poses import PoseSequence
    from tests.test_cbr_clips import arm_dataset

    X, y = arm_dataset(3, seed=3)
    rec = PoseSequence(np.concatenate([x.positions for x in X]), X[0].joint_names, 30.0)
    return CaseBaseClassifier(k=3).fit(X, y), rec, [str(v) for v in y]


@pytest.fixture(scope="session")
def bundled_poses(
    shared_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> Callable[[str], PoseSequence]:
    """``bundled_poses("squat/tfjs_pose_squats_pexels4838220.mp4")``: the poses of that video
    of ``../shared/data/videos`` as ``extract`` finds them (``estimate_video``, defaults),
    estimated once in the whole session (each estimate is 1-4 s of the pose model's CPU
    time, and several files read the same videos). A fresh copy at each call."""

    def poses(name: str) -> PoseSequence:
        def make(root: Path) -> PoseSequence:
            from features.pose_estimation import estimate_video

            return estimate_video(shared_data / "videos" / name, progress_bar=False).sequence

        return made_once(tmp_path_factory, "poses-" + name.replace("/", "-"), make)

    return poses


@pytest.fixture(scope="session")
def lunge_poses(bundled_poses: Callable[[str], PoseSequence]) -> PoseSequence:
    """The bundled reverse-lunge video's poses (250 frames at 25 fps, as ``extract`` finds
    them), estimated once in the session: about a minute of the pose model's CPU time.
    Read by tests/test_leg_swaps.py and tests/test_repetitions_unseen.py."""
    return bundled_poses("lunge/fit_reverse_lunge_pexels8233047.mp4")


@pytest.fixture(scope="session")
def side_plank_reps(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[str, str]:
    """What ``reps`` of the bundled side-plank video prints, without and with ``--json``
    (standard output), each run once in the session: tests/test_repetitions.py and
    tests/test_hunt36i.py read them (each run is the pose model on its 215 frames)."""

    def make(root: Path) -> tuple[str, str]:
        import contextlib
        import io

        from posecbr.cli import main

        plank = shared_data / "videos" / "side_plank" / "fit_side_plank_pexels6023266.mp4"
        printed = []
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("POSECBR_NO_PROGRESS", "1")
            for extra in ([], ["--json"]):
                out = io.StringIO()
                with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
                    assert main(["reps", str(plank), *extra]) == 0
                printed.append(out.getvalue())
        return printed[0], printed[1]

    return made_once(tmp_path_factory, "side-plank-reps", make)


def _seen(factory: pytest.TempPathFactory, split: str) -> Path:
    """``train --split SPLIT`` on three movements of the demo's subjects s01 and s02 (deep
    squat, standing shoulder abduction, side lunge), made once in the session."""

    def make(root: Path) -> Path:
        from posecbr.cli import main

        db = root / "cb.sqlite"
        labels = ROOT / "posecbr" / "demo_data" / "uiprmd" / "labels.csv"
        seen = "deep_squat,standing_shoulder_abduction,side_lunge"
        argv = ["train", str(labels), "--db", str(db), "--subjects", "s01,s02", "--labels", seen,
                "--split", split]  # fmt: skip
        assert main(argv) == 0
        return db

    return made_once(factory, f"seen-{split}", make)


@pytest.fixture(scope="session")
def seen_windows(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """:func:`_seen`'s case base of windows: tests/test_stored_judges.py and
    tests/test_spread_default.py read or copy it."""
    return _seen(tmp_path_factory, "windows")


@pytest.fixture(scope="session")
def seen_clips(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """:func:`_seen`'s case base of whole clips (train's default for clips):
    tests/test_stored_judges.py and tests/test_hunt38d.py read or copy it."""
    return _seen(tmp_path_factory, "clips")


@pytest.fixture(scope="session")
def swapped_compare(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, str]]:
    """One ``compare --out`` on ten demo clips with their labels swapped
    (``tests/test_compare_bad_input.py``): the labels file, the results folder, and the
    snapshot of the data folder taken before the run. Read, or copied, by the tests."""

    def make(root: Path) -> tuple[Path, Path, dict[str, str]]:
        from posecbr.cli import main
        from tests.test_compare_bad_input import FAST, _swapped_data, snapshot

        labels = _swapped_data(root / "data")
        before = snapshot(root / "data")
        assert main(["compare", str(labels), *FAST, "--out", str(root / "out")]) == 0
        return labels, root / "out", before

    return made_once(tmp_path_factory, "swapped-compare", make)


@pytest.fixture(scope="session")
def compared_slice(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One ``compare`` on 54 real clips of the demo subset (3 movements x 3 subjects x 6,
    ``tests/test_compare_cli.py``'s SLICE), fluents by euclidean and dtw, DAD, two
    explanations: the folder holding ``r.json``, ``r.csv`` and the ``--out`` folder ``o``.
    Read (or copied) by tests/test_compare_cli.py and tests/test_report_chromium.py."""

    def make(root: Path) -> Path:
        from posecbr.cli import main
        from tests.test_compare_cli import DEMO, SLICE

        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("POSECBR_NO_PROGRESS", "1")
            rc = main([
                "compare", str(DEMO), "--labels", SLICE, "--similarities", "euclidean,dtw",
                # The tslearn peer is left out: tests/test_compare_peers.py checks it, here
                # its DTW 1-NN would only add to the suite's time.
                "--features", "fluents", "--peers", "none", "--explain", "2",
                "--json", str(root / "r.json"), "--csv", str(root / "r.csv"),
                "--out", str(root / "o"),
            ])  # fmt: skip
        assert rc == 0
        return root

    return made_once(tmp_path_factory, "compare-slice", make)


@pytest.fixture(scope="session")
def compared_three(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The ``--out`` folder of one ``compare`` of three activities of the demo's subject s01
    (``tests/test_hunt40j.py``'s THREE: three folds, fluents by euclidean, no DAD, peers or
    explanations; six pictures), made once in the session. tests/test_hunt39e.py and
    tests/test_hunt40j.py copy it as the earlier run their own comparison writes over (compare
    names no folder in its files: a copy is that run)."""

    def make(root: Path) -> Path:
        from posecbr.cli import main
        from tests.test_hunt40j import THREE

        assert main([*THREE, "--out", str(root / "o")]) == 0
        return root / "o"

    return made_once(tmp_path_factory, "compare-three", make)


@pytest.fixture(scope="session")
def compared_small(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """One ``compare`` of 24 demo clips (tests/test_hunt31e.py's SMALL: two movements of two
    subjects, fluents by euclidean alone, no DAD, peers or explanations) with ``--json
    run.json --out run``, made once in the session: the folder holding both, and what the
    command printed. tests/test_hunt31e.py copies the folder (a results file beside its
    pictures' folder), tests/test_hunt32c.py reads the results and the printed table."""

    def make(root: Path) -> tuple[Path, str]:
        import contextlib
        import io

        from posecbr.cli import main
        from tests.test_hunt31e import DEMO, SMALL

        printed = io.StringIO()
        argv = ["compare", str(DEMO), *SMALL, "--json", str(root / "run.json")]
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("POSECBR_NO_PROGRESS", "1")
            with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(io.StringIO()):
                assert main([*argv, "--out", str(root / "run")]) == 0
        return root, printed.getvalue()

    return made_once(tmp_path_factory, "compare-small", make)


@pytest.fixture(autouse=True)
def _no_progress_bars(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")


@pytest.fixture
def file_size_limit() -> Iterator[Callable[[int], None]]:
    """Call it with a byte count: from then on, until the test ends, writing a file past that
    size fails as a full disk does (``OSError`` EFBIG from the kernel, RLIMIT_FSIZE).
    Python's compiled modules are not written meanwhile: a module the command imports under
    the limit had its ``.pyc`` cut at it (Python 3.11 takes the short write(2) for the
    whole), and every later import of it in any process failed ("marshal data too short")."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    # Without this the kernel kills the process (SIGXFSZ) instead of failing the write.
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    bytecode = sys.dont_write_bytecode

    def limit(n_bytes: int) -> None:
        sys.dont_write_bytecode = True
        resource.setrlimit(resource.RLIMIT_FSIZE, (n_bytes, hard))

    try:
        yield limit
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)
        sys.dont_write_bytecode = bytecode


@pytest.fixture
def silent_server() -> Iterator[str]:
    """A URL on this machine whose server accepts connections and never sends a byte."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                held.append(server.accept()[0])
            except OSError:  # closed: the test is over
                return

    threading.Thread(target=accept, daemon=True).start()
    yield f"http://127.0.0.1:{server.getsockname()[1]}/live.mp4"
    server.close()
    for conn in held:
        conn.close()
