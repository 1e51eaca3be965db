"""An output asked for in a folder that cannot be written (a read-only mount) is refused in one
line before the work, not when the result is written: `compare` cross-validated every
configuration and then failed to write its results."""

from __future__ import annotations

from pathlib import Path

import pytest

from features.poses import save_pose
from tests.badinput import (
    posecbr_on_read_only_mount,
    read_only_mounts_work,
    small_case_base,
    snapshot,
    standing_clip,
)

FAST = ["--similarities", "euclidean", "--features", "fluents", "--peers", "none", "--no-dad"]

pytestmark = pytest.mark.skipif(
    not read_only_mounts_work(),
    reason="this machine cannot make a private read-only mount (unshare -rm, mount)",
)


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from tests.test_cbr_cli import _write_classes

    return _write_classes(tmp_path_factory.mktemp("data") / "train", 3, 5)


@pytest.mark.parametrize(
    ("option", "name", "what"),
    [
        ("--out", "results", "cannot write the results file"),
        ("--json", "results.json", "cannot write the JSON output"),
    ],
)
def test_compare_into_a_read_only_folder_is_refused_before_it_cross_validates(
    data: Path, tmp_path: Path, option: str, name: str, what: str
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    inputs = snapshot(data)
    done = posecbr_on_read_only_mount(
        folder, ["compare", str(data), *FAST, option, str(folder / name)]
    )
    assert snapshot(data) == inputs  # the clips and labels read are as they were
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert f"{what}: the folder {folder} is read-only" in lines[0], lines[0]
    assert lines[0].startswith("posecbr compare: error")
    assert done.stdout == ""  # no fold was run, no table printed
    assert list(folder.iterdir()) == []


def test_describe_plot_into_a_read_only_folder_is_refused(tmp_path: Path) -> None:
    clip = save_pose(standing_clip(30), tmp_path / "clip.npz")
    folder = tmp_path / "ro"
    folder.mkdir()
    before = clip.read_bytes()
    done = posecbr_on_read_only_mount(
        folder, ["describe", str(clip), "--plot", str(folder / "t.png")]
    )
    assert clip.read_bytes() == before
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert (
        len(lines) == 1
        and f"cannot write the picture: the folder {folder} is read-only" in (lines[0])
    ), done.stderr
    assert done.stdout == "" and list(folder.iterdir()) == []


def test_casebase_copy_into_a_read_only_folder_is_refused_as_train_refuses_it(
    tmp_path: Path,
) -> None:
    # before: "cannot open or write the database (unable to open database file)", SQLite's
    # words, where train names the folder that cannot be written
    source = small_case_base(tmp_path / "src")
    folder = tmp_path / "ro"
    folder.mkdir()
    before = snapshot(source.parent)
    done = posecbr_on_read_only_mount(
        folder, ["casebase", "copy", "--db", str(source), "--to", str(folder / "new.sqlite")]
    )
    assert snapshot(source.parent) == before
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"posecbr casebase copy: error: {folder / 'new.sqlite'}: cannot write the case base "
        f"file: the folder {folder} is read-only"
    ]
    assert done.stdout == "" and list(folder.iterdir()) == []
