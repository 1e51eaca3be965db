"""Hunt 38o: a researcher comparing methods (``posecbr compare``) on the data README shows and
on long recordings.

``compare --labels deep_squat --subjects s99`` (a subject the data do not have) said
"--labels: no clip labelled 'deep_squat' ... passes the other filters", blaming the label
that is there for the subject that is not; ``train`` named the subject. Now a value the
data have nowhere is named first, whichever flag gave it, with the values the data have.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def test_compare_names_a_subject_the_data_lack_not_the_label(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo holds subjects s01, s02 and s03 (its labels.csv): s99 is none of them."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat", "--subjects", "s99", "--json",
            str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert line.endswith(
        f"--subjects: no clip of subject 's99' in {DEMO}: its subjects are s01, s02 and s03"
    )


def test_compare_names_a_label_the_data_lack_though_a_subject_is_also_wrong(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Both flags name a value the data lack: the labels are checked first, as before."""
    argv = ["compare", str(DEMO), "--labels", "deep_squat,nope", "--subjects", "s01,s99",
            "--json", str(tmp_path / "r.json")]  # fmt: skip
    line = refused(argv, tmp_path, capsys)
    assert f"--labels: no clip labelled 'nope' in {DEMO}: its labels are deep_squat," in line
