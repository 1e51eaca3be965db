"""Fast start: the command line loads a heavy library only where a command uses it.

Each probe runs in a fresh interpreter (this test process has everything loaded already) and
reports which of the heavy libraries are in ``sys.modules`` afterwards. Behaviour, not timing:
``python -m benchmarks.startup`` measures the times.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from features.version import __version__

ROOT = Path(__file__).resolve().parents[1]
CLIP = ROOT / "posecbr" / "demo_data" / "uiprmd" / "m01_s01_e01.npz"
# numpy too: the parser needs none of them (about 0.1 s of the 0.3 s aimed at for --help)
HEAVY = ("sklearn", "scipy", "numba", "sqlalchemy", "matplotlib", "cv2", "onnxruntime", "numpy")
MARK = "loaded-modules:"
# The names of the registered commands, from the parser itself (argparse keeps them in the
# subparsers action's choices).
COMMANDS = (
    "import argparse\n"
    "from posecbr.cli import build_parser\n"
    "parser = build_parser()\n"
    "sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))\n"
    "names = sorted(sub.choices)"
)


def _run(code: str, tmp_path: Path) -> tuple[str, set[str]]:
    """Run ``code`` in a new interpreter; its output and the heavy libraries it loaded."""
    probe = (
        "import sys\n"
        f"{code}\n"
        f"heavy = sorted(m for m in {HEAVY!r} if m in sys.modules)\n"
        f"print({MARK!r} + ','.join(heavy))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    out, _, loaded = proc.stdout.rpartition(MARK)
    return out, {m for m in loaded.strip().split(",") if m}


def test_version_loads_no_heavy_library(tmp_path: Path) -> None:
    out, loaded = _run(
        "from posecbr.cli import main\ntry:\n    main(['--version'])\nexcept SystemExit:\n    pass",
        tmp_path,
    )
    assert out.strip() == f"posecbr {__version__}"
    assert loaded == set()


def test_building_the_parser_loads_no_heavy_library(tmp_path: Path) -> None:
    out, loaded = _run(
        f"import json\n{COMMANDS}\nprint(json.dumps(names))",
        tmp_path,
    )
    # every command registered (so nothing was left out to look fast)
    commands = {p.stem for p in (ROOT / "posecbr" / "commands").glob("*.py")} - {"__init__"}
    assert set(json.loads(out)) == commands
    assert loaded == set()


def test_help_of_every_command_loads_no_heavy_library(tmp_path: Path) -> None:
    out, loaded = _run(
        f"import contextlib, io\n{COMMANDS}\n"
        "for name in names:\n"
        "    with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "        build_parser().parse_args([name, '--help'])\n"
        "print(len(names))",
        tmp_path,
    )
    assert int(out.strip()) >= 11
    assert loaded == set()


def test_describe_loads_only_what_it_uses(tmp_path: Path) -> None:
    out, loaded = _run(
        f"from posecbr.cli import main\nassert main(['describe', {str(CLIP)!r}, '--json']) == 0",
        tmp_path,
    )
    doc = json.loads(out)
    assert doc["frames"] > 0 and doc["runs"]
    # fluents are compiled kernels (numba) and the spans are median-cleaned (scipy); no case
    # base, no estimator, no plot, no video
    assert loaded <= {"numba", "scipy", "numpy"}
    assert "numba" in loaded


def _subcommand(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found: argparse.ArgumentParser = sub.choices[name]
    return found


def test_editor_choices_written_out_are_the_maintenance_editors() -> None:
    from cbr.maintenance import EDITORS
    from posecbr.cli import build_parser

    parser = build_parser()
    trim = _subcommand(_subcommand(parser, "casebase"), "trim")
    train = _subcommand(parser, "train")
    for p in (trim, train):
        (editor,) = [a for a in p._actions if "--editor" in a.option_strings]
        assert editor.choices is not None and sorted(editor.choices) == sorted(EDITORS)
