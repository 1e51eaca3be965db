"""Hunt 38t: the command line's options, one idea under one name across commands, and what
each command says it did.

- ``compare -k 3`` was refused ("unrecognized arguments: -k 3") where ``train``,
  ``classify``, ``segment`` and ``casebase trim`` take ``-k``: compare now takes it too.
- worker processes are ``compare --jobs`` and ``extract --workers``: each now takes the
  other's name as well.
- the video with the stick figure drawn is ``segment --overlay`` and ``extract --overlay``,
  but ``watch --out``: watch now takes ``--overlay`` too.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from posecbr.cli import build_parser, main
from tests.badinput import refused, small_case_base

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def test_compare_takes_k_as_the_other_commands_spell_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-k 1``: the one case-base configuration retrieves 1 case, as ``--k 1`` says."""
    out = tmp_path / "results.json"
    argv = [
        "compare", str(DEMO), "--similarities", "euclidean", "--features", "fluents",
        "--no-dad", "--peers", "none", "--labels", "deep_squat,hurdle_step",
        "--explain", "0", "-k", "1", "--json", str(out),
    ]  # fmt: skip
    assert main(argv) == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["settings"]["k"] == 1


def test_extract_takes_jobs_as_compare_spells_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``extract --jobs 0`` was "unrecognized arguments" (exit 2); it is ``--workers``, checked
    as such (the video is never opened: its bytes need not be one)."""
    video = tmp_path / "squat.mp4"
    video.write_bytes(b"not decoded")
    argv = ["extract", str(video), "--out", str(tmp_path / "poses"), "--jobs", "0"]
    refused(argv, tmp_path, capsys, "--workers (--jobs) must be at least 1, got 0")
    args = build_parser().parse_args(["extract", str(video), "--out", "p", "--jobs", "3"])
    assert args.workers == 3


def test_compare_takes_workers_as_extract_spells_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    refused(["compare", str(DEMO), "--workers", "0"], tmp_path, capsys,
            "--jobs: jobs must be at least 1, got 0")  # fmt: skip
    assert build_parser().parse_args(["compare", str(DEMO), "--workers", "2"]).jobs == 2


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return small_case_base(tmp_path_factory.mktemp("cb"))


def test_watch_takes_overlay_as_segment_and_extract_name_it(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``watch --overlay V`` was "unrecognized arguments"; it is ``--out V``: refused over
    the video watched as ``--out`` is, before the video is read."""
    video = tmp_path / "squat.mp4"
    video.write_bytes(b"not decoded")
    argv = ["watch", str(video), "--db", str(case_base), "--overlay", str(video)]
    refused(argv, tmp_path, capsys, "the output video would overwrite an input")
    args = build_parser().parse_args(["watch", "0", "--db", "cb", "--overlay", "w.mp4"])
    assert args.out == Path("w.mp4")
