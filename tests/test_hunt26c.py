"""Hunt 26c: ``posecbr classify`` (feedback, ``-k``, ``--json`` and the text beside it) and
the ``posecbr casebase`` actions (info, list, export, trim), checked against the store's
rows counted by hand and against what the options say."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import cbr.classification
from casebase_store import NewCase, open_store
from posecbr.cli import main
from tests.badinput import refused, small_case_base


@pytest.fixture(scope="module")
def case_base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small real case base (three synthetic arm activities, three clips each; k = 5)."""
    return small_case_base(tmp_path_factory.mktemp("cb"))


def _copy(db: Path, folder: Path) -> Path:
    out = folder / "cb.sqlite"
    out.write_bytes(db.read_bytes())
    return out


def _clips(case_base: Path) -> list[str]:
    return sorted(str(p) for p in (case_base.parent / "train").rglob("*.npz"))


def test_feedback_keeps_the_k_asked_for_after_another_process_changes_the_cases(
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``classify --feedback -k 1``: when another process changed the case base during the
    run, the classifier was read again from the store with the k it was trained with (5),
    so the clips after the change were answered and retained by 5 neighbours, not 1. Every
    clip is now answered by the one nearest case asked for."""
    db = _copy(case_base, tmp_path)
    clips = _clips(case_base)[:3]
    solve = cbr.classification.classify_clip
    calls = []

    def other_process_between(*args: object, **kwargs: object) -> object:
        calls.append(1)
        if len(calls) == 2:  # after the first clip's feedback: another writer adds a case
            with open_store(db, create=False) as other:
                a = other.load_cases("default", ids=None)
                case = NewCase(str(a.labels[0]), a.features[0], source="another process")
                other.add_cases("default", [case])
        return solve(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(cbr.classification, "classify_clip", other_process_between)
    label = Path(clips[0]).parent.name
    argv = ["classify", *clips, "--db", str(db), "--feedback", label, "-k", "1", "--json"]
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 0, err
    assert len(calls) >= 3
    results = json.loads(out)["results"]
    assert [len(r["neighbours"]) for r in results] == [1, 1, 1]


@pytest.mark.parametrize(
    ("options", "flag"),
    [(["--quiet"], "--quiet"), (["--verbose", "--top", "1"], "--top")],
)
def test_json_with_an_option_it_would_ignore_is_refused(
    case_base: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    options: list[str],
    flag: str,
) -> None:
    """``classify --json --quiet`` printed every clip's full record (the summary alone was
    asked for), and ``--json --verbose --top 1`` every similar case (one was asked for): the
    option was ignored without a word. Each is now refused in one line naming it, before the
    case base is read."""
    db = _copy(case_base, tmp_path)
    argv = ["classify", _clips(case_base)[0], "--db", str(db), "--json", *options]
    refused(argv, tmp_path, capsys, f"{flag}: ", "--json")


def test_export_holds_each_cases_frames_as_list_shows_them(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``casebase export`` wrote the cases' problems, labels, sources, subjects and origins
    but not the frames of its recording each case is (``list`` shows them): the cases of a
    case base cut into repetitions or windows, several per file, could not be told apart.
    ``frames`` now holds each case's first frame and end frame (exclusive), as ``list``
    shows them; here every case is a whole training clip, 0 to its length."""
    from features.poses import load_pose

    out = tmp_path / "cases.npz"
    assert main(["casebase", "export", "--db", str(case_base), "--out", str(out)]) == 0
    capsys.readouterr()
    with np.load(out) as z:
        sources, frames = z["sources"].tolist(), z["frames"]
    assert frames.shape == (len(sources), 2)
    assert frames.tolist() == [[0, load_pose(s).n_frames] for s in sources]
    assert main(["casebase", "list", "--db", str(case_base), "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["cases"]
    assert [c["frames"] for c in listed] == frames.tolist()


@pytest.mark.parametrize("subjects", ["s03,s99", "s03,"])
def test_classify_refuses_a_subject_no_clip_has(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case_base: Path, subjects: str
) -> None:
    """``classify labels.csv --subjects s03,s99`` (a mistyped subject, or a stray comma)
    classified the clips of s03 alone and reported their accuracy as if the subjects asked
    for had been: the one that matched nothing went unsaid. It is refused in one line naming
    it (the labels CSV holds subjects s01 and s03)."""
    from tests.test_feedback_safety import DEMO

    labels = tmp_path / "labels.csv"
    rows = [f"{DEMO / f'm01_{s}_e01.npz'},deep_squat,{s}" for s in ("s01", "s03")]
    labels.write_text("\n".join(["path,label,subject", *rows]) + "\n", encoding="utf-8")
    db = _copy(case_base, tmp_path)
    argv = ["classify", str(labels), "--db", str(db), "--subjects", subjects]
    missing = subjects.split(",")[1]
    refused(argv, tmp_path, capsys, "--subjects: ", f"{missing!r}")


def test_a_trim_that_drops_nothing_writes_nothing(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Three well-apart activities, three cases each: every case's 3 nearest others (RENN's
    k) hold two of its own activity, so RENN drops none. The trim still wrote the case base:
    a new version (another process's change since it read would be refused) and a trim in
    its history. Now the file is left byte for byte as it was, and the line says so."""
    import hashlib

    db = _copy(case_base, tmp_path)
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    with open_store(db, readonly=True) as store:
        version = store.get_case_base("default").version
    capsys.readouterr()
    assert main(["casebase", "trim", "--db", str(db), "--editor", "renn"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("RENN: 9 -> 9 cases") and "(nothing dropped: nothing changed)" in out
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before
    assert main(["casebase", "trim", "--db", str(db), "--editor", "renn", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["size_before"], doc["size_after"], doc["changed"]) == (9, 9, False)
    with open_store(db, readonly=True) as store:
        assert store.get_case_base("default").version == version
        assert [e.action for e in store.maintenance_log("default")] == ["build"]


def test_info_after_a_trim_says_the_calibrations_are_of_the_training_cases(
    case_base: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A trim calibrates the unknown judges anew on the cases it keeps, not the confidence
    or the unlike-the-cases flag: ``casebase info`` after one described those as holding for
    the case base as it is (the note it gives after an append, retain or revise was left
    out for a trim)."""
    db = _copy(case_base, tmp_path)
    assert main(["casebase", "trim", "--db", str(db), "--keep", "0.5", "-k", "1"]) == 0
    capsys.readouterr()
    assert main(["casebase", "info", "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert "trim x1" in out
    assert "; cases added, changed or dropped since are not taken into account)" in out
