"""Command-line consistency (hunt 33h): where "written to" lines go, which command an unknown
argument is blamed on, a guess for a mistyped choice, and what a zip given as --db is."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused
from tests.test_cbr_cli import _write_classes


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A synthetic arm movement (tests.test_cbr_cli's: three activities, two clips each)."""
    root = _write_classes(tmp_path_factory.mktemp("clips"), 2, 5)
    return sorted(root.rglob("*.npz"))[0]


@pytest.mark.parametrize("as_json", [False, True])
@pytest.mark.parametrize(
    ("command", "said"), [("reps", "picture written to"), ("describe", "timeline written to")]
)
def test_written_to_goes_to_stderr(
    clip: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
    said: str,
    as_json: bool,
) -> None:
    """`reps --plot` and `describe --plot` said where the picture went on stdout (`segment
    --plot` on stderr), and with --json not at all; now on stderr, with or without --json,
    and stdout holds only the answer."""
    plot = tmp_path / "picture.png"
    capsys.readouterr()
    assert main([command, str(clip), "--plot", str(plot), *(["--json"] if as_json else [])]) == 0
    out, err = capsys.readouterr()
    assert plot.stat().st_size > 0
    assert err.splitlines()[-1] == f"{said} {plot}", err
    assert "written to" not in out
    if as_json:
        assert isinstance(json.loads(out), dict)


def test_report_says_where_the_page_went_on_stderr(
    clip: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`report` said "report written to ..." on stdout, unlike segment's "written to"."""
    results = tmp_path / "results.json"
    clips = clip.parents[1]
    argv = ["compare", str(clips), "--similarities", "euclidean", "--features", "fluents",
            "--no-dad", "--peers", "none", "--k", "1", "--json", str(results)]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    page = tmp_path / "r.html"
    assert main(["report", str(results), "--out", str(page)]) == 0
    out, err = capsys.readouterr()
    assert out == ""
    assert err.splitlines()[-1] == f"report written to {page}"
    assert page.stat().st_size > 0


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        # before: "posecbr casebase list: error: unrecognized arguments: --bogus"
        (["casebase", "--bogus", "list", "--db", "cb.sqlite"],
         "posecbr casebase: error: unrecognized arguments: --bogus; see posecbr casebase --help"),
        # before: "posecbr casebase list: error: ..."; posecbr's own --help lists its options
        (["--bogus", "casebase", "list", "--db", "cb.sqlite"],
         "posecbr: error: unrecognized arguments: --bogus; see posecbr --help"),
        # before: both named together, blamed on casebase list; the first is casebase's
        (["casebase", "--bogus", "list", "--db", "cb.sqlite", "--jsn"],
         "posecbr casebase: error: unrecognized arguments: --bogus; see posecbr casebase --help"),
        # as before: given to the action
        (["casebase", "list", "--db", "cb.sqlite", "--jsn"],
         "posecbr casebase list: error: unrecognized arguments: --jsn (did you mean '--json'?);"
         " see posecbr casebase list --help"),
        (["--bogus", "reps", "clip.npz"],
         "posecbr: error: unrecognized arguments: --bogus; see posecbr --help"),
        # before: "posecbr describe: ... --json (did you mean '--json'?)", which it was
        (["--json", "describe", "clip.npz"],
         "posecbr: error: unrecognized arguments: --json (--json is an option of posecbr "
         "describe: give it after describe); see posecbr --help"),
        (["casebase", "--json", "list", "--db", "cb.sqlite"],
         "posecbr casebase: error: unrecognized arguments: --json (--json is an option of "
         "posecbr casebase list: give it after casebase list); see posecbr casebase --help"),
    ],
)  # fmt: skip
def test_an_unknown_argument_is_blamed_on_the_command_it_was_given_to(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert capsys.readouterr().err == said + "\n"


@pytest.mark.parametrize(
    ("argv", "wanted"),
    [
        (["segment", "rec.npz", "--db", "cb.sqlite", "--unknown", "helt-out"], "held-out"),
        (["watch", "0", "--db", "cb.sqlite", "--unknown", "spread-margn"], "spread-margin"),
        (["casebase", "trim", "--db", "cb.sqlite", "--editor", "rennn"], "renn"),
        (["train", "data", "--db", "cb.sqlite", "--split", "window"], "windows"),
        # a value holding a quote is said in double quotes: it got no guess
        (["segment", "rec.npz", "--db", "cb.sqlite", "--unknown", "held'out"], "held-out"),
        (["clas'sify", "clip.npz"], "classify"),
    ],
)
def test_a_mistyped_choice_gets_a_guess(
    argv: list[str], wanted: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A mistyped command or option got "(did you mean ...?)", a mistyped value of an option
    with fixed choices only the list of choices."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "invalid choice" in err, err
    assert "(choose from " in err and f"(did you mean {wanted!r}?); see posecbr " in err, err


def test_a_far_off_choice_gets_no_guess(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["segment", "rec.npz", "--db", "cb.sqlite", "--unknown", "zzz"])
    err = capsys.readouterr().err
    assert "invalid choice: 'zzz'" in err and "did you mean" not in err


@pytest.mark.parametrize(
    ("kind", "said"),
    [
        ("npz", "(a NumPy file, such as a pose file: --db takes the case base file)"),
        ("zip", "(a zip archive, not a pose file: --db takes the case base file)"),
        ("xlsx", "(a zip archive, not a pose file: --db takes the case base file)"),
    ],
)
def test_db_given_a_zip_says_whether_it_holds_arrays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, said: str
) -> None:
    """Every zip given as --db was "a NumPy file, such as a pose file": a .npz is a zip of
    .npy members, a .zip of pictures or an .xlsx spreadsheet is not."""
    clip = good_pose_file(tmp_path / "clip.npz", frames=12)
    db = tmp_path / f"given.{kind}"
    if kind == "npz":
        db.write_bytes(clip.read_bytes())
    else:
        with zipfile.ZipFile(db, "w") as z:
            first = "[Content_Types].xml" if kind == "xlsx" else "labels.csv"
            z.writestr(first, "<Types/>" if kind == "xlsx" else "path,label\n")
            z.writestr("positions.npy.txt", "not an array")
    refused(["classify", str(clip), "--db", str(db)], tmp_path, capsys,
            f"{db.name}: not a readable SQLite database {said}")  # fmt: skip


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ("videos/squat/tfjs_pose_squats_pexels4838220.mp4", "a video file"),
        ("media/vtest.avi", "a video file"),
        ("media/messi5.jpg", "a PNG or JPEG picture"),
        ("media/basketball1.png", "a PNG or JPEG picture"),
    ],
)
def test_db_given_a_video_or_picture_says_so(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], given: str, said: str
) -> None:
    """`classify cb.sqlite --db video.mp4` (the two swapped; classify reads videos) said
    "corrupt or not a database", where a pose file or a labels CSV is named for what it is."""
    clip = good_pose_file(tmp_path / "clip.npz", frames=12)
    db = tmp_path / Path(given).name
    db.write_bytes((shared_data / given).read_bytes())
    refused(["classify", str(clip), "--db", str(db)], tmp_path, capsys,
            f"{db.name}: not a readable SQLite database",
            f"({said}: --db takes the case base file)")  # fmt: skip
