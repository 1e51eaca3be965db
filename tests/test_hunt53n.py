"""Session 53, task N: leftovers of compare's and train's refusals (hunts 53e, 53j). ``compare
--cv loso`` asked for by name is refused when the clips the read leaves out (too short, no
person) leave one subject (it fell back to k-fold with a note, as without --cv); ``--within``
groups each inside one subject under it are refused from the listing, before any clip is
decoded (they were refused once every clip was read); ``train --json`` says why each clip
skipped was (``skipped_reasons``). Folders of a few real files, linked (one cut short)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

import features.datasets
from cbr.evaluation.data import prepare
from cbr.evaluation.settings import CompareSettings
from features.datasets import dataset_entries, load_clip
from features.errors import ConfigError
from features.poses import save_pose
from posecbr.cli import main
from tests.test_hunt52o import _counted
from tests.test_hunt53e import _uiprmd
from tests.test_hunt53j import BELOW_THE_WAIST, DEMO

#: one subject's deep squats and hurdle steps, twice each, and one deep squat of another
CLIPS = [("m01_s01_e01", True), ("m01_s01_e02", True), ("m02_s01_e01", True),
         ("m02_s01_e02", True), ("m01_s02_e01", True)]  # fmt: skip
#: the cheapest comparison: a refusal's test runs none on the code before it too
CHEAP = ["--similarities", "euclidean", "--features", "fluents", "--no-dad", "--peers", "none"]
NOT_LOSO = "; --cv kfold cross-validates over clips (the same person can be in training and test)"


def test_loso_asked_for_is_refused_when_the_clips_left_out_leave_one_subject(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # s02's one clip cut to its first 6 frames (0.2 s at 30 Hz): the listing shows two
    # subjects, the read leaves that clip out (shorter than the 0.4 s a movement can last)
    data = _uiprmd(shared_data, tmp_path / "data", CLIPS, short="m01_s02_e01")
    out = tmp_path / "out"
    argv = ["compare", str(data), "--cv", "loso", "-k", "1", *CHEAP, "--out", str(out)]
    assert main(argv) == 1
    assert capsys.readouterr().err == (
        f"posecbr compare: error: --cv: leave-one-subject-out is impossible in {data}: only one"
        " subject (s01), once every clip of the 1 other subject (s02) is left out (shorter"
        f" than one movement can be (0.4 s): m01_s02_e01_positions.txt.gz){NOT_LOSO}\n"
    )
    assert not out.exists()
    # not asked for by name, it falls back to k-fold over s01's four clips with its note, as
    # before; so does --within subject, whose one group k-fold trains: the listing (two
    # subjects, each its group's) does not refuse it, the read runs it
    from cbr.evaluation.folds import check_listed, check_within, make_folds

    read = [c for e in dataset_entries(data) for c in e.read()]
    listed = [c for e in dataset_entries(data) for c in e.listed() or ()]
    assert sorted({c.subject for c in listed}) == ["s01", "s02"]
    for settings in (CompareSettings(k=1), CompareSettings(k=1, within="subject")):
        assert check_listed(listed, settings, str(data)) is True
        kept = prepare(read, settings, str(data))
        scheme, folds, notes = make_folds(kept, settings, str(data))
        assert scheme == "kfold"
        assert notes[0].startswith("only one subject (s01), so leave-one-subject-out is impossible")
        assert sorted(folds.tolist()) == [0, 0, 1, 1]  # 2 clips per class: 2 folds
        check_within(kept.within, folds, settings.within_column)
    settings = CompareSettings(cv="loso", k=1)
    with pytest.raises(ConfigError) as refused:
        make_folds(prepare(read, settings, "d"), settings, "d")
    assert refused.value.source == "cv"


def test_loso_asked_for_is_refused_from_the_listing_when_a_class_of_one_clip_is_a_subject(
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # s02's one clip is the only inline lunge (m03): a class of a single clip, which every
    # comparison leaves out, and s02 with it, whatever the read leaves out besides
    clips = [*CLIPS[:4], ("m03_s02_e01", True)]
    data = _uiprmd(shared_data, tmp_path / "data", clips)
    decoded = _counted(monkeypatch, features.datasets, "read_uiprmd_kinect")
    out = tmp_path / "out"
    assert main(["compare", str(data), "--cv", "loso", "-k", "1", *CHEAP, "--out", str(out)]) == 1
    assert capsys.readouterr().err == (
        f"posecbr compare: error: --cv: leave-one-subject-out is impossible in {data}: only one"
        " subject (s01), once every clip of the 1 other subject (s02) is left out (the single"
        f" clip of its class: m03_s02_e01_positions.txt.gz){NOT_LOSO}\n"
    )
    assert decoded == []
    assert not out.exists()


def test_within_each_subject_under_loso_asked_for_is_refused_from_the_listing(
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # every clip whole: s01's four and s02's one are each their own subject's group, and
    # whichever clips a read left out each group would stay inside its subject's fold (or
    # one subject would be left, which --cv loso refuses)
    data = _uiprmd(shared_data, tmp_path / "data", CLIPS)
    decoded = _counted(monkeypatch, features.datasets, "read_uiprmd_kinect")
    out = tmp_path / "out"
    argv = ["compare", str(data), "--cv", "loso", "--within", "subject", "-k", "1", *CHEAP]
    assert main([*argv, "--out", str(out)]) == 1
    assert capsys.readouterr().err == (
        "posecbr compare: error: --within: every 'subject' value's clips lie in one fold, so no"
        " model per value is ever trained on any clip (each is tested when its fold is held"
        " out); use --cv kfold or another --within\n"
    )
    assert decoded == []
    assert not out.exists()


def test_within_each_subject_without_cv_is_refused_once_read_before_the_comparison(
    shared_data: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    # without --cv the read may leave one subject, and k-fold train every group: refused
    # once the clips are read, in the same words, but before the comparison (its modules,
    # scikit-learn among them, imported for it) is run
    import cbr.evaluation.compare

    data = _uiprmd(shared_data, tmp_path / "data", CLIPS)
    decoded = _counted(monkeypatch, features.datasets, "read_uiprmd_kinect")
    compared = _counted(monkeypatch, cbr.evaluation.compare, "run_compare")
    out = tmp_path / "out"
    argv = ["compare", str(data), "--within", "subject", "-k", "1", *CHEAP, "--out", str(out)]
    assert main(argv) == 1
    assert capsys.readouterr().err == (
        "posecbr compare: error: --within: every 'subject' value's clips lie in one fold, so no"
        " model per value is ever trained on any clip (each is tested when its fold is held"
        " out); use --cv kfold or another --within\n"
    )
    assert len(decoded) == 5
    assert compared == []
    assert not out.exists()


def test_train_json_says_why_each_clip_was_skipped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two activities of two real clips each (the demo's UI-PRMD pose files), and three clips
    no case can be made of: one with the hips out of view, one with no joint in any frame,
    one of 6 frames (0.2 s)."""
    data = tmp_path / "data"
    for label, stems in (("abduction", ("m07_s01_e01", "m07_s01_e02")),
                         ("squat", ("m01_s01_e01", "m01_s01_e02"))):  # fmt: skip
        (data / label).mkdir(parents=True)
        for stem in stems:
            (data / label / f"{stem}.npz").symlink_to(DEMO / f"{stem}.npz")
    seq = load_clip(DEMO / "m07_s02_e01.npz").to_canonical()
    no_hips = seq.positions.copy()
    no_hips[:, BELOW_THE_WAIST] = np.nan
    save_pose(dataclasses.replace(seq, positions=no_hips), data / "abduction" / "nohips.npz")
    blank = np.full_like(seq.positions, np.nan)
    save_pose(dataclasses.replace(seq, positions=blank), data / "abduction" / "blank.npz")
    short = load_clip(DEMO / "m01_s02_e01.npz")
    save_pose(dataclasses.replace(short, positions=short.positions[:6]), data / "squat" / "s.npz")
    db = tmp_path / "cb.sqlite"
    assert main(["train", str(data), "--db", str(db), "-k", "1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    reasons = {r["clip"]: r["reason"] for r in summary["skipped_reasons"]}
    # the text's words ("skipped 1 clip that shows no torso (...): nohips.npz")
    no_torso = "shows no torso (no frame shows its left hip, right hip)"
    assert [Path(c).name for c in reasons] == ["blank.npz", "nohips.npz", "s.npz (lasts 0.20 s)"]
    assert list(reasons.values()) == [
        "shows no person", no_torso, "shorter than one movement can be (0.4 s)"]  # fmt: skip
    assert [r["clip"] for r in summary["skipped_reasons"]] == summary["skipped"]  # as before
    assert summary["cases"] == 4
