"""Hunt 34c: a guess for a swapped pair of letters in a three-letter value (`--similarity
dwt`), and ``watch`` of a browser's WebM or a raw H.264 stream served over HTTP, played as
the same file on this machine is."""

from __future__ import annotations

from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import refused
from tests.test_cbr_cli import _write_classes


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic arm movements (tests.test_cbr_cli's: three activities, two clips each)."""
    return _write_classes(tmp_path_factory.mktemp("clips"), 2, 5)


SIMILARITIES = ["dtw", "euclidean", "signature"]


@pytest.mark.parametrize(
    ("typed", "known", "guess"),
    [
        # two neighbouring letters swapped: every letter kept, difflib's ratio 0.67
        ("dwt", SIMILARITIES, "dtw"),
        ("tdw", SIMILARITIES, "dtw"),
        ("ncn", ["novelty-benefit", "cnn", "renn", "icf"], "cnn"),
        ("lal", ["angles", "instantaneous", "all"], "all"),
        # longer words: one edit was guessed before and still is
        ("margni", ["spread-margin", "activity-margin", "margin", "margin-distance"], "margin"),
        ("anlges", ["angles", "instantaneous", "all"], "angles"),
        ("eucldean", SIMILARITIES, "euclidean"),
    ],
)
def test_a_typo_gets_its_guess(typed: str, known: list[str], guess: str) -> None:
    from features.text import did_you_mean

    assert did_you_mean(typed, known) == f" (did you mean {guess!r}?)"


@pytest.mark.parametrize(
    ("typed", "known"),
    [
        ("xyz", SIMILARITIES),
        ("abc", SIMILARITIES),
        ("wtd", SIMILARITIES),  # dtw backwards: two swaps, not one
        ("twd", SIMILARITIES),  # a letter moved two places
        ("dtx", SIMILARITIES),  # a wrong letter: two of three kept, as cnm for cnn
        ("cnm", ["cnn"]),
        ("mxi", ["max", "min"]),
    ],
)
def test_a_non_typo_gets_no_guess(typed: str, known: list[str]) -> None:
    from features.text import did_you_mean

    assert did_you_mean(typed, known) == ""


def test_one_swap_alike_for_two_names_is_no_guess() -> None:
    """``bac`` is one swap from both ``abc`` and ``bca``: no guess rather than the first;
    a name close by difflib comes before one a swap away."""
    from features.text import did_you_mean

    assert did_you_mean("bac", ["abc", "bca"]) == ""
    assert did_you_mean("bac", ["abc"]) == " (did you mean 'abc'?)"
    assert did_you_mean("ba", ["ab", "ba2"]) == " (did you mean 'ba2'?)"  # ratio 0.8


def test_train_guesses_a_swapped_similarity(
    clips: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`train --similarity dwt` listed the known measures alone; now "(did you mean 'dtw'?)".
    `--similarity xyz` still gets none."""
    argv = ["train", str(clips), "--db", str(tmp_path / "cb.db"), "--similarity", "dwt"]
    line = refused(argv, tmp_path, capsys, "--similarity", "'dwt'")
    assert line.endswith("(did you mean 'dtw'?)"), line
    argv[-1] = "xyz"
    assert "did you mean" not in refused(argv, tmp_path, capsys, "--similarity", "'xyz'")


def test_a_swapped_choice_gets_a_guess(capsys: pytest.CaptureFixture[str]) -> None:
    """argparse's choices share the guess: `train --editor ncn`."""
    with pytest.raises(SystemExit) as exit_:
        main(["train", "data", "--db", "cb.sqlite", "--editor", "ncn"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "invalid choice: 'ncn'" in err, err
    assert "(did you mean 'cnn'?); see posecbr train --help" in err, err
