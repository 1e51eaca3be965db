"""compare's refusals from the listing (hunts 52x, 52rv) reach raw UI-PRMD, HDM05 and CMU folders:
a ``--target`` neither the file names nor the reader can give is refused before any clip is
decoded (it was refused once every clip was read, in the same words); and k-fold's refusal of
a group's class of a single clip is left to the read, which may leave that clip out (too
short): it was refused from the listing though the clips read could be cross-validated.
Folders of a few real files, linked (one cut short)."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

import features.datasets
from cbr.evaluation.data import prepare
from cbr.evaluation.folds import check_listed, make_folds
from cbr.evaluation.settings import CompareSettings
from features.datasets import dataset_entries
from posecbr.cli import main
from tests.test_hunt52o import _counted

_KINECT = ("Kinect/Positions", "positions"), ("Kinect/Angles", "angles")


def _uiprmd(shared: Path, root: Path, clips: list[tuple[str, bool]], short: str = "") -> Path:
    """A UI-PRMD folder at ``root`` of the Kinect files (positions and angles) of ``clips``
    (``m01_s01_e01``, correct or not) linked from the real data; ``short``'s files cut to
    their first 6 frames (0.2 s at 30 Hz)."""
    for stem, correct in clips:
        top = "Segmented Movements" if correct else "Incorrect Segmented Movements"
        for sub, kind in _KINECT:
            name = f"{stem}_{kind}{'' if correct else '_inc'}.txt.gz"
            real = shared / "ui-prmd" / "data" / top / sub / name
            (root / top / sub).mkdir(parents=True, exist_ok=True)
            if stem == short:
                rows = gzip.decompress(real.read_bytes()).splitlines(keepends=True)
                (root / top / sub / name).write_bytes(gzip.compress(b"".join(rows[:6])))
            else:
                (root / top / sub / name).symlink_to(real)
    return root


def _hdm05(shared: Path, root: Path) -> Path:
    """An HDM05 folder at ``root``: two takes of grabHighR (actors bd, dg) with their
    skeletons, linked from the real data."""
    (root / "3").mkdir(parents=True)
    for name in ("HDM_bd.asf", "HDM_dg.asf", "HDM_bd_grabHighR_003_120.amc",
                 "HDM_dg_grabHighR_013_120.amc"):  # fmt: skip
        (root / "3" / name).symlink_to(shared / "hdm05" / "train" / "3" / name)
    return root


def _cmu(shared: Path, root: Path) -> Path:
    """A folder of CMU takes at ``root``, one per class folder (jog: 13_29, squat: 13_30), an
    HDM05 skeleton beside each, linked from the real data: no subject is told."""
    for label, take in (("jog", "13_29"), ("squat", "13_30")):
        (root / label).mkdir(parents=True)
        (root / label / f"{take}.amc").symlink_to(shared / "cmu-mocap6" / "amc" / f"{take}.amc")
        (root / label / "HDM_bd.asf").symlink_to(shared / "hdm05" / "train" / "3" / "HDM_bd.asf")
    return root


@pytest.mark.parametrize(
    ("kind", "reader", "first", "columns", "read_only"),
    [
        # what the read of every clip named, on main's code: the file name's columns, and the
        # reader's rate (fps_source), and for HDM05 the skeleton file (asf)
        (
            "hdm05",
            "read_asf_amc",
            "HDM_bd_grabHighR_003_120.amc",
            "asf, dataset, fps_source, label, subject, take",
            ["asf", "FPS_source", "x_reflected"],
        ),
        # a CMU take's name gives no column: the reader's alone
        ("cmu", "read_asf_amc", "13_29.amc", "asf, fps_source, label, subject", ["asf"]),
        (
            "uiprmd",
            "read_uiprmd_kinect",
            "m01_s01_e01_positions.txt.gz",
            "correct, dataset, episode, fps_source, label, movement, sensor, subject",
            ["fps_source", "X_Reflected"],
        ),
    ],
)
def test_target_no_raw_clip_can_have_is_refused_before_any_clip_is_decoded(
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    kind: str,
    reader: str,
    first: str,
    columns: str,
    read_only: list[str],
) -> None:
    if kind == "hdm05":
        data = _hdm05(shared_data, tmp_path / "data")
    elif kind == "cmu":
        data = _cmu(shared_data, tmp_path / "data")
    else:
        data = _uiprmd(
            shared_data, tmp_path / "data", [("m01_s01_e01", True), ("m01_s01_e01", False)]
        )
    # the columns only the read gives (the reader's, a left-handed recording's mark), named
    # in any case, are left to it
    listed = [c for e in dataset_entries(data) for c in e.listed() or ()]
    assert len(listed) == 2  # the listing tells each clip's label and subject
    for target in read_only:
        assert check_listed(listed, CompareSettings(target=target), str(data)) is False
    decoded = _counted(monkeypatch, features.datasets, reader)
    out = tmp_path / "out"
    assert main(["compare", str(data), "--target", "nosuch", "--out", str(out)]) == 1
    assert capsys.readouterr().err == (
        f"posecbr compare: error: {data}: 2 of 2 clips have no value for target 'nosuch' (e.g."
        f" {first}); columns available: {columns}\n"
    )
    assert decoded == []
    assert not out.exists()


def test_class_of_one_clip_in_a_group_is_left_to_the_read(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # one subject: k-fold over clips, stratified by correct within each movement. Deep squat
    # correct and incorrect twice each, hurdle step correct once: a class of a single clip in
    # its group, which k-fold cannot stratify
    clips = [("m01_s01_e01", True), ("m01_s01_e02", True), ("m01_s01_e01", False),
             ("m01_s01_e02", False), ("m02_s01_e01", True)]  # fmt: skip
    settings = CompareSettings(target="correct", k=1)
    cut = _uiprmd(shared_data, tmp_path / "cut", clips, short="m02_s01_e01")
    entries = dataset_entries(cut)
    listed = [c for e in entries for c in e.listed() or ()]
    assert len(listed) == 5
    # the hurdle step cut to 0.2 s: the read leaves it out, and the deep squats' 2 x 2 clips
    # are cross-validated in 2 folds (the smallest class's clips), each class in both
    assert check_listed(listed, settings, str(cut)) is False
    data = prepare([c for e in entries for c in e.read()], settings, str(cut))
    scheme, folds, _ = make_folds(data, settings)
    assert scheme == "kfold"
    assert sorted(zip(folds.tolist(), data.y.tolist(), strict=True)) == [
        (0, "correct"), (0, "incorrect"), (1, "correct"), (1, "incorrect")]  # fmt: skip
    # read whole, it stays, and the read refuses it: one line, nothing written
    whole = _uiprmd(shared_data, tmp_path / "whole", clips)
    out = tmp_path / "out"
    args = ["compare", str(whole), "--target", "correct", "--out", str(out)]
    assert main(args) == 1
    assert capsys.readouterr().err == (
        "posecbr compare: error: --cv: a class has a single clip in some group; stratified"
        " k-fold (--cv kfold) is impossible\n"
    )
    assert not out.exists()
