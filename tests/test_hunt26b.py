"""``convert``, ``extract``, ``describe``, ``compare`` and ``demo`` used as a newcomer would
(hunt 26b): mocap skeletons with odd but parseable units, output names in capitals, and the
other mistakes and edge cases a first user makes. Each test says what happened before its
fix.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import refused
from tests.test_readers_asfamc import ASF, _write


@pytest.mark.parametrize("scale", ["0", "-0.5", "0.0e0"])
def test_an_asf_length_unit_that_is_not_positive_is_refused(
    scale: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``:units length 0`` made the metres per unit a division by zero: a ZeroDivisionError
    traceback; ``length -0.5`` was taken, every position negated (the person upside down
    and mirrored, left side on the right)."""
    assert "  length 0.5\n" in ASF  # the hand-made skeleton's unit, replaced
    data = tmp_path / "data"
    data.mkdir()
    skel, amc = _write(data, asf=ASF.replace("  length 0.5\n", f"  length {scale}\n"))
    out = tmp_path / "out"
    refused(
        ["convert", str(amc), "--asf", str(skel), "--out", str(out)],
        tmp_path, capsys, str(skel), "length", "positive",
    )  # fmt: skip
