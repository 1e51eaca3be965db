"""README audit (hunt 29c): what the commands print, against what the README says."""

from __future__ import annotations

from posecbr.commands.train import _skipped


def test_train_names_one_clip_with_no_person_in_the_singular() -> None:
    """`train` skips clips with no person, naming them (README, "Case bases"). One such clip
    read "skipped 1 clip that show no person"; the verb agrees with the count now."""
    assert _skipped(["empty.npz"], [], "clips") == "skipped 1 clip that shows no person: empty.npz"
    two = _skipped(["a.npz", "b.npz"], [], "clips")
    assert two == "skipped 2 clips that show no person: a.npz, b.npz"
    # one recording cut into windows, three of them empty: counted as windows, plural
    assert _skipped(["r.npz"] * 3, [], "windows") == (
        "skipped 3 windows that show no person: r.npz (3)"
    )
