"""A refusal the arguments and the dataset's listing show comes before the modules only the
work needs are imported: ``posecbr compare`` refusing one class imports neither
scikit-learn (the peers', seconds of CPU) nor the case-base store (SQLAlchemy), nor SciPy's
image filters (DTW's envelopes). Run in a new process, whose ``sys.modules`` holds only what
the command imported."""

from __future__ import annotations

import subprocess
import sys

from tests import ROOT

#: runs posecbr's entry point with the arguments given, then prints its exit status, the
#: modules asked about that it imported, and what it said on stderr
RUN = """
import contextlib, io, sys
from posecbr.cli import main
said = io.StringIO()
with contextlib.redirect_stderr(said):
    status = main(sys.argv[1:])
asked = ("sklearn", "casebase_store", "scipy.ndimage")
print(status, [m for m in asked if m in sys.modules])
print(said.getvalue().strip())
"""


def test_compare_refuses_one_class_before_the_runs_imports() -> None:
    demo = ROOT / "posecbr" / "demo_data" / "uiprmd"
    argv = ["compare", str(demo), "--labels", "deep_squat"]
    done = subprocess.run([sys.executable, "-c", RUN, *argv], cwd=ROOT, capture_output=True,
                          text=True, timeout=60, check=False)  # fmt: skip
    status, said = done.stdout.splitlines()[:2]
    assert status == "1 []", done.stdout + done.stderr
    assert said == (
        f"posecbr compare: error: {demo}: need at least two classes of 'label' with two or"
        " more clips each; found {'deep_squat': 18}"
    )
