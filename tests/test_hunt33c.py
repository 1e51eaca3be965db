"""Hunt 33c: label files (``--frame-labels``, ``--label-names``, a labels CSV's
``label_file``) and ``casebase`` subcommands given odd but plausible input."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.badinput import good_pose_file, refused


def _recording(folder: Path, frames: int = 60) -> Path:
    """A pose file of ``frames`` frames at 30 fps (a person standing)."""
    return good_pose_file(folder / "rec.npz", frames=frames)


@pytest.mark.parametrize(
    ("labels", "names", "needle"),
    [
        # the 4th word of line 2 (a label per frame, ten per line)
        ("a a a a a a a a a a\nb b b b\x00 b b b b b b\n" + "c " * 40, None,
         "labels.txt: line 2, word 4: 'b\\x00' contains a NUL character"),
        # a code's name in --label-names
        ("1 " * 30 + "2 " * 30, "1 walk\n2 ru\x00n\n",
         "names.txt: line 2, word 2: 'ru\\x00n' contains a NUL character"),
        # a UTF-16 file (no BOM) read as UTF-8 is half NULs: said so
        ("1 " * 60, None, "(UTF-16 text? save the file as UTF-8)"),
    ],
)  # fmt: skip
def test_a_nul_in_a_label_file_or_its_names_is_refused_in_one_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    labels: str,
    names: str | None,
    needle: str,
) -> None:
    """A NUL in a label file or a label names file was read into a label (a case's label, or
    left out as a flicker naming it): a labels CSV's label column refuses it; now these do
    too, naming the file, the line and the word, whether given to ``train --frame-labels``
    or named by a labels CSV's ``label_file`` / ``label_names`` columns."""
    rec = _recording(tmp_path)
    track = tmp_path / "labels.txt"
    if "UTF-16" in needle:
        track.write_bytes(labels.encode("utf-16-le"))
    else:
        track.write_text(labels, encoding="utf-8")
    extra = []
    if names is not None:
        (tmp_path / "names.txt").write_text(names, encoding="utf-8")
        extra = ["--label-names", str(tmp_path / "names.txt")]
    db = str(tmp_path / "cb.sqlite")
    argv = ["train", str(rec), "--frame-labels", str(track), *extra, "--split", "clips",
            "--db", db]  # fmt: skip
    refused(argv, tmp_path, capsys, needle)
    csv = tmp_path / "recordings.csv"
    csv.write_text(
        "path,label_file,label_names\n"
        f"rec.npz,labels.txt,{'names.txt' if names is not None else ''}\n",
        encoding="utf-8",
    )
    refused(["train", str(csv), "--split", "clips", "--db", db], tmp_path, capsys, needle)
