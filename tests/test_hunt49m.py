"""``posecbr watch`` of a URL or camera that cannot be opened says so before the segmenter's
warm-up (hunt 49m: a mistyped URL cost 0.5-3 s before its one line), and a ``watch --out``
that names a folder is told so (it was told the name must end in .mp4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from posecbr.cli import main
from tests.badinput import good_pose_file, refused, small_case_base
from tests.test_hunt34c import _serving


@pytest.mark.parametrize("source", ["404", "camera"])
def test_a_source_that_cannot_be_opened_is_refused_before_the_warm_up(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    source: str,
) -> None:
    """A URL the server answers 404 for, and a camera index past any camera here: one line,
    exit 1, and the segmenter was never warmed up (the source was opened first, and the
    camera once)."""
    import features.pose_estimation.video as video
    import posecbr.commands.watch as watch

    warmed: list[bool] = []
    monkeypatch.setattr(watch.Watcher, "warm_up", lambda _self: warmed.append(True))
    opened: list[int | str] = []
    open_quietly = video._open_quietly

    def counted(device: int | str, timeout_s: float | None = None) -> object:
        opened.append(device)
        return open_quietly(device, timeout_s)

    monkeypatch.setattr(video, "_open_quietly", counted)
    db = small_case_base(tmp_path)
    with _serving(tmp_path) as address:
        url = f"{address}/gone.mp4"
        watched, said = {
            "404": (url, f"{url}: the server answered HTTP 404 (Not Found)"),
            "camera": (
                "97",
                "97: cannot open camera: none at this index, or another program holds it",
            ),
        }[source]
        capsys.readouterr()
        assert main(["watch", watched, "--db", str(db)]) == 1
    assert capsys.readouterr().err == f"posecbr watch: error: {said}\n"
    assert warmed == []
    if source == "camera":
        assert opened == [97]


@pytest.mark.parametrize(("command", "option", "what"), [("watch", "--out", "output video")])
def test_a_video_to_write_named_as_a_folder_is_told_to_name_the_file(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    command: str,
    option: str,
    what: str,
) -> None:
    """An existing folder, with or without its "/", and a name ending in "/" that is no
    folder yet: each one line naming it, nothing written, where each was told that the
    video must be an .mp4 file name. (``segment --overlay DIR`` was refused so too: it
    writes ``DIR/<recording>.mp4`` now, tests/test_hunt50j.py; a camera or URL watched has
    no name to give its video.)"""
    (tmp_path / "clips").mkdir()
    recording = str(good_pose_file(tmp_path / "rec.npz"))
    source = ["watch", recording] if command == "watch" else ["segment", recording]
    argv = [*source, "--db", str(tmp_path / "cb.sqlite"), option]
    folder = tmp_path / "clips"
    for named in (str(folder), f"{folder}/"):
        line = refused([*argv, named], tmp_path, capsys)
        assert line == (
            f"posecbr {command}: error: {folder}: the {what} is a folder: name the .mp4 file"
            " to write in it"
        )
    line = refused([*argv, f"{tmp_path}/new/"], tmp_path, capsys)
    assert line == (
        f"posecbr {command}: error: {tmp_path}/new/: the {what} is named as a folder (ending"
        " in /): name the .mp4 file to write in it"
    )
