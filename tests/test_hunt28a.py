"""Hunt 28a: "data is sacred", command by command. Outputs that reach an input by a way the
commands did not compare (a case base named by a ``sqlite:///`` URL), a demo output folder
holding the demo data, ..."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.badinput import refused

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


@pytest.mark.parametrize(
    ("argv", "what"),
    [
        (["watch", "v.mp4", "--db", "sqlite:///{db}", "--out", "{out}"], "output video"),
        (["segment", "v.mp4", "--db", "sqlite:///{db}", "--overlay", "{out}"], "overlay"),
        (["segment", "c.npz", "--db", "sqlite:///{db}", "--plot", "{out}"], "picture"),
    ],
    ids=["watch --out", "segment --overlay", "segment --plot"],
)
def test_an_output_onto_the_case_base_its_url_names_is_refused(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    what: str,
) -> None:
    """``--db sqlite:///x/cb.mp4 --out x/cb.mp4``: the URL's text was compared with the output
    path, so the case base was no input; the command read it and replaced it with the video
    (or picture) it wrote, exit 0."""
    suffix = ".png" if what == "picture" else ".mp4"
    db = tmp_path / f"cb{suffix}"
    db.write_bytes(b"not opened: refused before")
    (tmp_path / "v.mp4").write_bytes(b"not read: refused before")
    (tmp_path / "c.npz").write_bytes(b"not read: refused before")
    filled = [a.format(db=db, out=db) for a in argv]
    filled[1] = str(tmp_path / filled[1])
    refused(filled, tmp_path, capsys, f"the {what} would overwrite an input ({db})")
    # a URL relative to the current folder, the output spelt absolute: the same file
    monkeypatch.chdir(tmp_path)
    filled = [a.format(db=db.name, out=tmp_path / "." / db.name) for a in argv]
    refused(filled, tmp_path, capsys, f"the {what} would overwrite an input ({db.name})")


def test_demo_data_inside_the_comparison_folder_it_replaces_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``demo --data out/compare --out out`` in a folder an earlier demo wrote: the demo
    removed ``out/compare`` (its earlier comparison) with the data in it, then failed on the
    missing clip."""
    out = tmp_path / "out"
    out.mkdir()
    (out / ".posecbr-demo").touch()
    data = out / "compare"
    shutil.copytree(DEMO, data)
    refused(["demo", "--data", str(data), "--out", str(out), "--quick"], tmp_path, capsys,
            f"{data}: the demo data is in {data}, which the demo replaces")  # fmt: skip
    nested = out / "compare" / "mine"
    data.rename(tmp_path / "moved")
    data.mkdir()
    (tmp_path / "moved").rename(nested)
    refused(["demo", "--data", f"{nested}/", "--out", f"{out}/.", "--quick"], tmp_path, capsys,
            "which the demo replaces with its comparison: choose another --out")  # fmt: skip


def test_a_timeline_column_averages_the_frames_a_state_is_known_in(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The picture's columns (frames averaged, 2,000 columns at most) counted a frame where a
    state is unknown (nobody in view) as confidence 0: a person seen in every other frame,
    knees straight whenever seen, was drawn at half shade, and a stretch with nobody as "not
    holding". A column averages the frames the state is known in; none: NaN, drawn grey."""
    from dataclasses import replace

    import matplotlib.image
    import numpy as np

    import features.timeline as timeline
    from tests.badinput import standing_clip

    seq = standing_clip(40)
    positions = seq.positions.copy()
    positions[1::2] = np.nan  # nobody in every other frame
    positions[24:] = np.nan  # nor in the last 16
    monkeypatch.setattr(timeline, "PLOT_COLUMNS", 10)  # 4 frames a column
    tl = timeline.describe_clip(replace(seq, positions=positions))
    knee = tl.layout.state_names.index("left_leg_bent.straight")  # standing: 180 degrees
    assert tl.columns[:6, knee].tolist() == [1.0] * 6
    assert np.isnan(tl.columns[6:, knee]).all()
    picture = timeline.plot_timeline(tl, tmp_path / "t.png")
    pixels = matplotlib.image.imread(picture)[..., :3]
    grey = np.array([0xD9, 0xD9, 0xD9]) / 255
    assert (np.abs(pixels - grey).max(axis=-1) < 0.01).sum() > 100  # the unknown stretch


def test_a_first_store_through_a_dangling_link_is_refused_not_retried_for_ever(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``train --db cb.sqlite`` where cb.sqlite is a symbolic link to a file not made yet: the
    new store, built under a temporary name, could not be linked to the name (link() finds
    the link there) and was built again, and again, for ever (a temporary of each left behind
    when the run was killed). Refused in one line before any clip is read; the store's own
    writer stops too."""
    from casebase_store import StoreError, write_store

    folder = tmp_path / "data"
    folder.mkdir()
    (folder / "a.npz").write_bytes(b"not read: refused before")
    link = tmp_path / "cb.sqlite"
    link.symlink_to("target.sqlite")
    refused(["train", str(folder), "--db", str(link)], tmp_path, capsys,
            f"{link}: is a symbolic link to target.sqlite, which does not exist")  # fmt: skip
    calls = []

    def action(tx: object) -> None:
        calls.append(tx)
        if len(calls) > 2:
            raise RuntimeError("the store was built again and again")

    with pytest.raises(StoreError, match="is a symbolic link to target.sqlite"):
        write_store(link, action)
    assert len(calls) <= 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cb.sqlite", "data"]


def test_compare_out_onto_a_link_to_nothing_is_refused_before_it_cross_validates(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``compare DATA --out res`` where res is a symbolic link to a folder not made yet: the
    run cross-validated every configuration, then failed making the folder with a traceback
    (FileExistsError), the results written nowhere."""
    demo = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"
    link = tmp_path / "res"
    link.symlink_to("nowhere")
    argv = ["compare", str(demo), "--similarities", "euclidean", "--features", "fluents",
            "--no-dad", "--peers", "none", "--out", str(link)]  # fmt: skip
    refused(argv, tmp_path, capsys,
            f"cannot write the results file: {link} is a symbolic link to nowhere, which does"
            " not exist")  # fmt: skip


def test_a_failed_demo_leaves_the_earlier_demo_outputs_as_they_were(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo removed the earlier run's case base and comparison before its steps ran: a
    step that failed (here describe, on a clip that is no pose file) or a Ctrl-C left neither
    the old outputs nor new ones. They are put back as they were."""
    from posecbr.cli import main
    from tests.badinput import good_pose_file, snapshot

    data = tmp_path / "data"
    rows = ["path,label,subject"]
    for subject in ("s01", "s02", "s03"):
        good_pose_file(data / f"m02_{subject}_e01.npz", label="deep_squat")
        rows.append(f"m02_{subject}_e01.npz,deep_squat,{subject}")
    (data / "labels.csv").write_text("\n".join(rows) + "\n")
    (data / "m01_s01_e01.npz").write_text("not a pose file")  # the clip step 1 describes
    out = tmp_path / "out"
    (out / "compare").mkdir(parents=True)
    (out / ".posecbr-demo").touch()
    (out / "casebase.sqlite").write_bytes(b"the earlier demo's case base")
    (out / "compare" / "results.json").write_text('{"the earlier": "comparison"}')
    before = snapshot(out)
    assert main(["demo", "--data", str(data), "--out", str(out), "--quick"]) == 1
    assert "m01_s01_e01.npz" in capsys.readouterr().err
    assert snapshot(out) == before
