"""Command-line consistency (hunt 33k): a guess for a mistyped value that posecbr checks itself
(not argparse), and compare's --json / --csv saying where they were written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_cbr_cli import _write_classes


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic arm movements (tests.test_cbr_cli's: three activities, two clips each)."""
    return _write_classes(tmp_path_factory.mktemp("clips"), 2, 5)


def test_did_you_mean() -> None:
    from features.text import did_you_mean  # new: imported here so the rest runs on old code

    assert did_you_mean("eucldean", ["dtw", "euclidean"]) == " (did you mean 'euclidean'?)"
    assert did_you_mean("zzz", ["dtw", "euclidean"]) == ""
    assert did_you_mean("cnm", ["cnn"]) == ""  # 2 of 3 letters: ratio 0.67, not close


@pytest.mark.parametrize(
    ("options", "guess"),
    [
        (["--states", "angels"], "angles"),
        (["--similarity", "eucldean"], "euclidean"),
        (["--similarity", "signture"], "signature"),
    ],
)
def test_train_guesses_a_mistyped_value(
    clips: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    options: list[str],
    guess: str,
) -> None:
    """`train --states angels` was refused with the states allowed but no guess, unlike a
    mistyped argparse choice (`--editor cnm`); now it ends "(did you mean 'angles'?)"."""
    argv = ["train", str(clips), "--db", str(tmp_path / "cb.db"), *options]
    line = refused(argv, tmp_path, capsys, options[0], f"(did you mean '{guess}'?)")
    assert line.endswith(f"(did you mean '{guess}'?)"), line


def test_train_no_guess_when_nothing_is_close(
    clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["train", str(clips), "--db", str(tmp_path / "cb.db"), "--states", "zzz"]
    assert "did you mean" not in refused(argv, tmp_path, capsys, "--states", "'zzz'")


@pytest.mark.parametrize(
    ("options", "guess"),
    [
        (["--similarities", "eucldean"], "euclidean"),
        (["--peers", "dtw-knm"], "dtw-knn"),
        (["--param", "feature_weights=fishr"], "fisher"),
        (["--param", "feature_weight=fisher"], "feature_weights"),
        (["--param", "mirror=canonicl"], "canonical"),
        (["--param", "states=angels"], "angles"),
        (["--param", "editor=cnnn"], "cnn"),
    ],
)
def test_compare_guesses_a_mistyped_value(
    clips: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    options: list[str],
    guess: str,
) -> None:
    """compare's --similarities, --peers and --param values are checked by posecbr, not
    argparse: they were refused without a guess."""
    argv = ["compare", str(clips), "--no-dad", "--csv", str(tmp_path / "r.csv"), *options]
    refused(argv, tmp_path, capsys, options[0], f"(did you mean '{guess}'?)")


def test_compare_says_where_json_and_csv_went(
    clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`compare --json FILE --csv FILE` (no --out) wrote both without a word, where every
    other command says "written to ..." on stderr; now it says so, on stderr."""
    results, table = tmp_path / "results.json", tmp_path / "results.csv"
    argv = ["compare", str(clips), "--similarities", "euclidean", "--features", "fluents",
            "--no-dad", "--peers", "none", "--k", "1",
            "--json", str(results), "--csv", str(table)]  # fmt: skip
    capsys.readouterr()
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert isinstance(json.loads(results.read_text()), dict)
    assert table.read_text().startswith("method")
    lines = err.splitlines()
    assert f"results written to {results}" in lines, err
    assert f"results table written to {table}" in lines, err
    assert "written to" not in out
