"""README walk-through (hunt 32c): what the commands print, against what the README shows."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cbr.evaluation.results import CompareResults
from cbr.evaluation.tables import format_table
from posecbr.cli import main
from tests.badinput import small_case_base
from tests.test_hunt31e import DEMO


@pytest.fixture(scope="module")
def one_configuration(compared_small: tuple[Path, str]) -> tuple[dict[str, object], str]:
    """`posecbr demo --quick`'s comparison, smaller: fluents/euclidean alone, which is then
    the best interpretable method and marked " *" (tests/conftest.py compared_small, made
    once in the session)."""
    folder, printed = compared_small
    return json.loads((folder / "run.json").read_text()), printed


def test_compare_table_keeps_a_marked_long_name_in_its_column(
    one_configuration: tuple[dict[str, object], str],
) -> None:
    """`posecbr demo --quick` printed "cbr fluents/euclidean *  89.4 [84.1,  93.1] ...": the
    name and its best-interpretable mark (23 characters) overflowed the 22-character method
    column and pushed the row one character right of the header."""
    doc, printed = one_configuration
    table = format_table(CompareResults.from_dict(doc))
    head, rule, row = table.splitlines()[:3]
    figures = re.compile(r"^ *\d+\.\d \[ *\d+\.\d, +\d+\.\d\] *$")
    # every column starts where its header does: the name column 23 wide, then a space
    assert row[:24] == "cbr fluents/euclidean * "
    assert head.index("accuracy % [95 % CI]") == 24
    assert figures.match(row[24:46]) and row[46] == " "
    assert head.index("macro-F1 % [95 % CI]") == 47
    assert figures.match(row[47:69]) and row[69] == " "
    assert len(rule) == len(head)
    assert row.endswith("best") and len(row) == len(head)
    assert table in printed  # what compare printed


def test_segment_says_where_its_picture_went(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The README's workout, `segment ... --plot timeline.png --overlay seen.mp4`, said
    "overlay written to seen.mp4" and nothing of the picture, where `describe --plot` says
    "timeline written to ..." and `reps --plot` "picture written to ...". It is said on
    stderr, beside the overlay's line, so `--json` stays one document on stdout."""
    db = small_case_base(tmp_path)
    clip = sorted((tmp_path / "train").rglob("*.npz"))[0]
    plot = tmp_path / "timeline.png"
    capsys.readouterr()
    assert main(["segment", str(clip), "--db", str(db), "--json", "--plot", str(plot)]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["recording"] == str(clip)
    # then the note of its case base of whole clips (hunt 39m)
    assert err.splitlines()[0] == f"timeline written to {plot}"
    assert [line.split(":")[0] for line in err.splitlines()[1:]] == ["note"]
    assert plot.stat().st_size > 0


def test_casebase_trim_help_says_what_editor_does(capsys: pytest.CaptureFixture[str]) -> None:
    """`posecbr casebase trim --help` listed `--editor {novelty-benefit,cnn,renn,icf}` with no
    words and no default, where every other option of it had both (README: "`--keep` is
    novelty-benefit's share of each activity and refused with the others")."""
    with pytest.raises(SystemExit):
        main(["casebase", "trim", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "novelty-benefit (default; keeps --keep of each activity)" in text


def test_a_repetition_check_with_no_deciding_feature_reads_as_english(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """`posecbr compare ../shared/data/ui-prmd --target correct` (README, "Comparing
    configurations") explained a clip "Why: nearest to the a correct repetition cases
    overall; no one feature sets it apart.": the answer's words with their article inside
    "the ... cases". Here every clip's deciding features are taken away, as they were for
    that clip, so the line is the one said when none decides."""
    import cbr.explain

    db = tmp_path / "squat.sqlite"
    argv = ["train", str(DEMO / "labels.csv"), "--labels", "deep_squat", "--subjects",
            "s01,s02", "--target", "correct", "--db", str(db)]  # fmt: skip
    assert main(argv) == 0
    monkeypatch.setattr(cbr.explain, "_reasons", lambda *a, **k: ([], []))
    capsys.readouterr()
    clips = [str(DEMO / "m01_s03_e01.npz"), str(DEMO / "m01_s03_e01_inc.npz")]
    assert main(["classify", *clips, "--db", str(db)]) == 0
    why = [ln.strip() for ln in capsys.readouterr().out.splitlines() if "Why:" in ln]
    assert len(why) == 2
    for line in why:
        assert re.fullmatch(
            r"Why: nearest to the (correct|incorrect) repetition cases overall; "
            r"no one feature sets it apart\.",
            line,
        ), line
