"""What the hunt of the evaluation path (31e) found in ``posecbr compare`` and ``posecbr
report``: the files asked for not written when standard output's reader stopped reading
(``| head``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.badinput import ROOT

DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
# 24 clips, one configuration: a comparison of a few seconds
SMALL = [
    "--labels", "deep_squat,hurdle_step", "--subjects", "s01,s02", "--peers", "none",
    "--no-dad", "--features", "fluents", "--similarities", "euclidean", "--explain", "0",
]  # fmt: skip


def test_compare_piped_into_a_reader_that_stops_still_writes_its_files(tmp_path: Path) -> None:
    """``posecbr compare DATA --json r.json --out DIR | head -1``: the reader closed the pipe
    after the table's first line, the next line raised BrokenPipeError, and the command
    ended with status 0 having written neither r.json nor DIR (unbuffered output, as with
    PYTHONUNBUFFERED=1, or a table longer than the pipe's buffer). The table is what is
    printed; the files are what was asked for."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "POSECBR_NO_PROGRESS": "1"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    argv = [sys.executable, "-m", "posecbr", "compare", str(DEMO), *SMALL]
    argv += ["--json", str(tmp_path / "r.json"), "--out", str(tmp_path / "o")]
    proc = subprocess.Popen(
        argv, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader has gone before the first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=600) == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert [m["name"] for m in doc["methods"]] == ["cbr fluents/euclidean"]
    assert len(doc["clips"]) == 24  # 2 movements x 2 subjects x 6 clips
    assert json.loads((tmp_path / "o" / "results.json").read_text())["clips"] == doc["clips"]
    assert (tmp_path / "o" / "results.csv").is_file()
    assert (tmp_path / "o" / "accuracy.png").is_file()
