"""Bad datasets, labels CSVs, motion capture files and convert arguments: one clear line, exit
status 1, and every file (inputs and the output folder) as it was (issue 15)."""

from __future__ import annotations

import gzip
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from features.datasets import read_labels_csv
from features.poses import load_pose
from posecbr.cli import main
from tests.badinput import (
    good_pose_file,
    leg_bvh,
    pose_file,
    refused,
    refused_in_process,
    snapshot,
)

BVH = leg_bvh("0.0333333", "0 90 0 0 0 0 0 0 0 10 20 0", "0 90 0 0 0 0 0 0 0 30 40 0")


def _clips(folder: Path) -> None:
    """Two good pose files of 8 frames, one in a subfolder."""
    good_pose_file(folder / "a.npz")
    good_pose_file(folder / "sub" / "b.npz")


def _labels(folder: Path, text: str | bytes) -> Path:
    _clips(folder)
    path = folder / "labels.csv"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


CSV_CASES: list[tuple[str, str | bytes, str]] = [
    ("an empty CSV", "", "empty CSV: a header row path,label[,subject][,start,end] is required"),
    ("no label column", "path,subject\na.npz,s01\n", "line 1: header must name columns"),
    ("a repeated column", "path,label,label\na.npz,x,y\n", "line 1: repeated column names"),
    ("start without end", "path,label,start\na.npz,x,1\n",
     "line 1: columns start and end go together"),
    ("a row with a missing field", "path,label,subject\na.npz,x\n",
     "line 2: 2 fields, the header has 3"),
    ("an empty path", "path,label\n,squat\n", "line 2: empty path"),
    ("an empty label", "path,label\na.npz,\n", "line 2: empty label"),
    ("a clip that does not exist", "path,label\nnope.npz,squat\n",
     "line 2: no such file nope.npz"),
    ("start and end not numbers", "path,label,start,end\na.npz,x,one,two\n",
     "line 2: start and end must be whole frame numbers, got 'one', 'two'"),
    ("end before start", "path,label,start,end\na.npz,x,5,2\n",
     "line 2: need 0 <= start < end (end exclusive), got 5, 2"),
    ("a negative start", "path,label,start,end\na.npz,x,-1,2\n", "need 0 <= start < end"),
    ("end past the clip", "path,label,start,end\na.npz,x,0,9\n",
     "line 2: end 9 is past the clip's 8 frames"),
    ("an unclosed quote", 'path,label\n"a.npz,squat\nsub/b.npz,x\n',
     "line 2: malformed CSV"),
    ("not UTF-8", "path,label\na.npz,squ\xe4t\n".encode("latin-1"), "not UTF-8 text"),
    ("a path too long for the system", "path,label\n" + "a" * 5000 + ".npz,squat\n",
     "line 2: cannot use the path (File name too long)"),
    ("a clip path that is a folder", "path,label\nsub,squat\n",
     "is a folder, not a clip file"),
    ("the CSV listing itself", "path,label\nlabels.csv,squat\n", "unknown clip format"),
    ("a start of a hundred digits", "path,label,start,end\na.npz,x,0," + "9" * 100 + "\n",
     "is past the clip's 8 frames"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "text", "needle"), CSV_CASES, ids=[c[0] for c in CSV_CASES])
def test_bad_labels_csv_is_one_clear_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str, text: str | bytes, needle: str
) -> None:
    data = tmp_path / "data"
    csv = _labels(data, text)
    out = tmp_path / "out"
    refused(["convert", str(csv), "--out", str(out)], tmp_path, capsys, needle)
    assert not out.exists()


def test_a_bad_clip_halfway_leaves_the_output_folder_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two good clips convert, the third is a renamed .npy: the earlier pose files were
    staged, not written, so the output folder (holding an earlier conversion) is unchanged."""
    data = tmp_path / "data"
    _clips(data)
    np.save(data / "c.npy", np.zeros((4, 33, 3)))
    (data / "c.npy").rename(data / "c.npz")
    (data / "labels.csv").write_text("path,label\na.npz,x\nsub/b.npz,y\nc.npz,z\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "labels.csv").write_text("path,label\nold.npz,old\n")
    (out / "old.npz").write_bytes(b"an earlier conversion")
    refused(["convert", str(data / "labels.csv"), "--out", str(out)], tmp_path, capsys,
            "c.npz: is a single NumPy array (.npy)")  # fmt: skip


def test_convert_into_the_folder_of_its_inputs_is_refused_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 15, data loss 5: converting a labels CSV into its own folder would overwrite the
    source clips with their slices and the hand-written labels.csv."""
    data = tmp_path / "data"
    _labels(data, "path,label,start,end\na.npz,squat,0,4\nsub/b.npz,lunge,2,6\n")
    refused(["convert", str(data / "labels.csv"), "--out", str(data)], tmp_path, capsys,
            "the output folder holds inputs of this conversion (labels.csv and 1 more)",
            "choose another --out")  # fmt: skip
    # the same for a folder of pose files, and for one pose file beside its output
    folder = tmp_path / "poses"
    good_pose_file(folder / "c.npz", label="squat")
    refused(["convert", str(folder), "--out", str(folder)], tmp_path, capsys,
            "the output folder holds inputs of this conversion (c.npz)")  # fmt: skip
    refused(["convert", str(folder / "c.npz"), "--out", str(folder)], tmp_path, capsys,
            "the output folder holds inputs")  # fmt: skip


def test_convert_elsewhere_keeps_the_inputs_and_metadata_cannot_redirect_paths(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The good path: the inputs stay byte for byte, and a pose file's metadata keys named
    like the labels CSV's own columns (path, start, Label) do not replace them."""
    data = tmp_path / "data"
    good_pose_file(data / "a.npz", label="squat", path="/etc/passwd", start=5, Label="x")
    before = snapshot(data)
    out = tmp_path / "out"
    assert main(["convert", str(data), "--out", str(out)]) == 0
    assert "wrote 1 pose file and labels.csv" in capsys.readouterr().out
    assert snapshot(data) == before
    rows = read_labels_csv(out / "labels.csv")
    assert [(r["path"].name, r["label"], r["start"]) for r in rows] == [("a.npz", "squat", None)]
    assert sorted(p.name for p in out.iterdir()) == ["a.npz", "labels.csv"]  # nothing staged left


def _bvh(folder: Path, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "clip.bvh"
    path.write_text(text)
    return path


def _uiprmd(folder: Path, positions: str, angles: str | None, gz: bool = False) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    suffix = ".txt.gz" if gz else ".txt"
    p = folder / f"m01_s01_e01_positions{suffix}"
    for path, text in ((p, positions), (folder / f"m01_s01_e01_angles{suffix}", angles)):
        if text is not None:
            data = text.encode()
            path.write_bytes(gzip.compress(data) if gz else data)
    return p


ROW = ",".join(["1.0"] * 66) + "\n"
ASF = """:version 1.10
:units
  length 0.45
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     name lfemur
     direction 0 -1 0
     length 7
     axis 0 0 0 XYZ
    dof rx ry rz
  end
:hierarchy
  begin
    root lfemur
  end
"""
AMC = (
    ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\nlfemur 0 0 0\n"
    "2\nroot 0 0 0 0 0 0\nlfemur 0 0 0\n"
)


def _asf_amc(folder: Path, asf: str, amc: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "skel.asf").write_text(asf)
    (folder / "walk.amc").write_text(amc)
    return folder / "walk.amc"


READER_CASES: list[tuple[str, Callable[[Path], Path], str]] = [
    ("BVH without HIERARCHY", lambda d: _bvh(d, "hello"), "does not start with HIERARCHY"),
    ("BVH truncated in the motion", lambda d: _bvh(d, BVH[:-20]),
     "numbers after the header, expected 2 frames x 12 channels"),
    ("BVH frame time zero", lambda d: _bvh(d, BVH.replace("0.0333333", "0")),
     "Frame Time must be positive, got 0.0"),
    ("BVH frame time not a number (it named the frame rate, not the Frame Time line)",
     lambda d: _bvh(d, BVH.replace("0.0333333", "nan")), "Frame Time must be positive, got nan"),
    ("BVH frame time infinite", lambda d: _bvh(d, BVH.replace("0.0333333", "inf")),
     "Frame Time must be positive, got inf"),
    ("BVH frame time of a nanosecond", lambda d: _bvh(d, BVH.replace("0.0333333", "1e-9")),
     "fps must be between 0.01 and 10000 frames per second"),
    ("BVH End Site outside a joint",
     lambda d: _bvh(d, BVH.replace("ROOT Hips", "End Site { OFFSET 0 0 0 }\nROOT Hips")),
     "End Site outside a joint"),
    ("BVH a rotation axis twice in a row (a fuzz finding)",
     lambda d: _bvh(d, BVH.replace("Zrotation Xrotation", "Zrotation Yrotation", 1)),
     "a channel listed twice in CHANNELS xposition yposition zposition zrotation yrotation"
     " yrotation"),
    ("BVH unknown channel", lambda d: _bvh(d, BVH.replace("Zrotation", "Wrotation", 1)),
     "unknown channel 'wrotation'"),
    ("BVH positions of a kilometre in metres",
     lambda d: _bvh(d, BVH.replace("0 90 0", "0 9000000 0")),
     "not metres of a person's pose"),
    ("ASF name without a value", lambda d: _asf_amc(d, ASF.replace("name lfemur", "name"), AMC),
     "line 12: 'name' without a value"),
    ("ASF rotation order of one letter repeated (a fuzz finding)",
     lambda d: _asf_amc(d, ASF.replace("axis 0 0 0 XYZ", "axis 0 0 0 XZZ"), AMC),
     "line 15: 'XZZ' is not a rotation order like XYZ"),
    ("ASF root axis not a rotation order (a fuzz finding)",
     lambda d: _asf_amc(d, ASF.replace("axis XYZ", "axis 1e-320"), AMC),
     "line 7: '1e-320' is not a rotation order like XYZ"),
    ("ASF root order with an unknown channel",
     lambda d: _asf_amc(d, ASF.replace("order TX TY TZ RX RY RZ", "order TX TQ TZ RX RY RZ"), AMC),
     "root order has unknown channel 'TQ'"),
    ("ASF bone length nan", lambda d: _asf_amc(d, ASF.replace("length 7", "length nan"), AMC),
     "line 14: expected finite numbers, got 'nan'"),
    ("AMC angle inf",
     lambda d: _asf_amc(d, ASF, AMC.replace("lfemur 0 0 0\n2", "lfemur 0 inf 0\n2")),
     "bone 'lfemur': not a finite number in frame 1"),
    ("BVH offset nan", lambda d: _bvh(d, BVH.replace("OFFSET 10 0 0", "OFFSET 10 nan 0")),
     "expected finite numbers after OFFSET, got '10 nan 0'"),
    ("BVH motion value inf", lambda d: _bvh(d, BVH.replace("30 40 0", "30 inf 0")),
     "a motion value in frame 2 is not a finite number"),
    ("BVH motion value a word", lambda d: _bvh(d, BVH.replace("30 40 0", "30 forty 0")),
     "motion value 'forty' (value "),
    ("ASF bone missing from the hierarchy",
     lambda d: _asf_amc(d, ASF.replace("root lfemur", "root"), AMC),
     "bone 'lfemur' is not in the :hierarchy"),
    ("AMC bone not in the skeleton", lambda d: _asf_amc(d, ASF, AMC.replace("lfemur", "rfemur")),
     "bone 'rfemur' is not in the skeleton"),
    ("AMC with no frames", lambda d: _asf_amc(d, ASF, ":DEGREES\n"),
     "no frames (not an AMC file?)"),
    ("AMC with a short frame",
     lambda d: _asf_amc(d, ASF, AMC.replace("lfemur 0 0 0\n2", "lfemur 0\n2")),
     "bone 'lfemur' has 1 values, the skeleton says 3"),
    ("AMC without its ASF",
     lambda d: (d.mkdir(), (d / "walk.amc").write_text(AMC), d / "walk.amc")[-1],
     "no .asf skeleton file beside it (put the subject's .asf there, or give it: --asf"
     " FILE.asf)"),
    ("AMC between two ASF files",
     lambda d: (_asf_amc(d, ASF, AMC), (d / "other.asf").write_text(ASF), d / "walk.amc")[-1],
     "2 .asf files beside it and none named for its actor"),
    ("UI-PRMD Kinect without its angles file", lambda d: _uiprmd(d, ROW * 3, None),
     "no angles file m01_s01_e01_angles.txt beside it"),
    ("UI-PRMD Kinect angles with fewer frames", lambda d: _uiprmd(d, ROW * 3, ROW * 2),
     "3 frames but its angles file m01_s01_e01_angles.txt has 2 (truncated?)"),
    ("UI-PRMD Kinect row too short", lambda d: _uiprmd(d, ROW + "1,2,3\n", ROW * 2),
     "line 2: expected 66 comma-separated numbers, got 3"),
    ("UI-PRMD Kinect non-finite numbers", lambda d: _uiprmd(d, ROW.replace("1.0", "inf", 1) * 2,
                                                            ROW * 2),
     "contains non-finite numbers"),
    ("UI-PRMD Kinect a word among the numbers",
     lambda d: _uiprmd(d, ROW * 2 + ROW.replace("1.0", "x", 1), ROW * 3),
     "line 3: not a number"),
    ("UI-PRMD truncated gzip",
     lambda d: (lambda p: (p.write_bytes(p.read_bytes()[:-10]), p)[-1])(
         _uiprmd(d, ROW * 50, ROW * 50, gz=True)),
     "cannot read (EOFError"),
    ("UI-PRMD empty file", lambda d: _uiprmd(d, "", ""), "file is empty"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("case", "build", "needle"), READER_CASES, ids=[c[0] for c in READER_CASES]
)
def test_bad_motion_capture_file_is_one_clear_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    case: str,
    build: Callable[[Path], Path],
    needle: str,
) -> None:
    path = build(tmp_path / "mocap")
    refused(["describe", str(path)], tmp_path, capsys, needle)


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--correct", "--incorrect"], "choose --correct or --incorrect, not both"),
        (["--episodes", "one-three"], "--episodes: not a number or range a-b: 'one-three'"),
        (["--episodes", "3-1"], "--episodes: the range '3-1' runs backwards: write 1-3"),
        (["--limit", "0"], "--limit: must be at least 1, got 0"),
        (["--limit", "-5"], "--limit: must be at least 1, got -5"),
        (["--bvh-unit", "-1"], "--bvh-unit: must be a unit name or a positive number, got '-1'"),
        (["--bvh-unit", "nan"], "--bvh-unit: must be a unit name or a positive number"),
        (["--bvh-unit", "furlong"], "unknown unit 'furlong'"),
        (["--bvh-unit", "1e6"], "not metres of a person's pose"),
    ],
)
def test_bad_convert_arguments_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], needle: str
) -> None:
    bvh = _bvh(tmp_path / "in", BVH)
    refused(["convert", str(bvh), "--out", str(tmp_path / "out"), *flags], tmp_path, capsys,
            needle)  # fmt: skip


def test_convert_sources_and_outputs_that_cannot_be(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bvh = _bvh(tmp_path / "in", BVH)
    refused(["convert", str(tmp_path / "nope"), "--out", str(tmp_path / "o")], tmp_path, capsys,
            "no such file or folder")  # fmt: skip
    (tmp_path / "empty").mkdir()
    refused(["convert", str(tmp_path / "empty"), "--out", str(tmp_path / "o")], tmp_path,
            capsys, "cannot tell what dataset this is")  # fmt: skip
    (tmp_path / "file.txt").write_text("x")
    refused(["convert", str(bvh), "--out", str(tmp_path / "file.txt")], tmp_path, capsys,
            "exists and is not a folder")  # fmt: skip
    unlabelled = tmp_path / "unlabelled"
    pose_file(unlabelled.mkdir() or unlabelled / "u.npz", metadata=json.dumps({}))
    refused(["convert", str(unlabelled), "--out", str(tmp_path / "o")], tmp_path, capsys,
            "no label: its metadata has none (put it in a labels CSV)")  # fmt: skip
    # a labels CSV with its header alone, no filter given: "check the filters" sent one looking
    (tmp_path / "header.csv").write_text("path,label\n")
    refused(["convert", str(tmp_path / "header.csv"), "--out", str(tmp_path / "o")], tmp_path,
            capsys, "header.csv: holds no clip to convert")  # fmt: skip


def test_episodes_as_wide_ranges_cost_nothing(tmp_path: Path) -> None:
    from posecbr.commands.convert import parse_ranges

    wide = parse_ranges("1-1000000000,5")
    assert wide is not None and 999_999_999 in wide and 0 not in wide and 1_000_000_001 not in wide


def test_a_gzip_that_expands_past_the_limit_is_refused_without_expanding_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A UI-PRMD file of 2 MB of text in a gzip of a few kilobytes, over a 1 MB limit."""
    clip = _uiprmd(tmp_path / "mocap", ROW * 6000, ROW * 6000, gz=True)
    assert clip.stat().st_size < 50_000
    monkeypatch.setenv("POSECBR_MAX_POSE_BYTES", "1000000")
    refused(["describe", str(clip)], tmp_path, capsys,
            "holds more than 1.00 MB of text",
            "(raise the limit with POSECBR_MAX_POSE_BYTES=BYTES)")  # fmt: skip
    monkeypatch.setenv("POSECBR_MAX_POSE_BYTES", "3000000")
    from features.datasets import load_clip

    # read whole under the raised limit (describe now refuses its pose, every number 1.0: its
    # shoulders lie on one another, no person, as reps and segment refuse it)
    assert load_clip(clip).n_frames == 6000


def test_data_loss_refusal_in_a_real_process(tmp_path: Path) -> None:
    data = tmp_path / "data"
    _labels(data, "path,label\na.npz,squat\nsub/b.npz,lunge\n")
    refused_in_process(["convert", str(data / "labels.csv"), "--out", str(data)], tmp_path,
                       "the output folder holds inputs of this conversion")  # fmt: skip


@pytest.mark.parametrize("source", ["..", "../../x/.hidden", "a\x1b[2Jb"])
def test_clip_names_from_metadata_stay_inside_the_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str
) -> None:
    """A pose file is named as the file it is (its metadata ``source``, what it was made from,
    is provenance: ``made_from``), so no ``source`` names a converted file: never a path out
    of the output folder, a hidden file or a name with control characters."""
    data = tmp_path / "data"
    clip = good_pose_file(data / "a.npz", label="x")
    arrays = dict(np.load(clip))
    arrays["metadata"] = np.array(json.dumps({"label": "x", "source": source}))
    np.savez(clip, **arrays)
    out = tmp_path / "out"
    assert main(["convert", str(data), "--out", str(out)]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == ["a.npz", "labels.csv"]
    assert load_pose(out / "a.npz").metadata["made_from"] == source
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "out"]


def test_a_pose_file_named_with_control_characters_is_converted_to_a_safe_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = tmp_path / "data"
    good_pose_file(data / "a\x1b[2Jb.npz", label="x")
    out = tmp_path / "out"
    assert main(["convert", str(data), "--out", str(out)]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == ["a_[2Jb.npz", "labels.csv"]


def test_a_pose_file_naming_a_video_too_long_to_look_up_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pose file whose metadata names its source video by a name over 255 bytes (written on
    another system, or by hand): the look for an older variable-frame-rate extraction asked
    whether that video is a file, and Python's "File name too long" came out as a traceback
    from every command reading the clip. The video is taken as not there: the file is read,
    in silence."""
    from features.datasets import load_clip
    from features.poses import PoseSequence, save_pose
    from features.skeleton import BLAZEPOSE_33

    meta = {"pose_model": "blazepose", "source_video": "v" * 300 + ".mp4"}
    path = tmp_path / "clip.npz"
    save_pose(PoseSequence(np.zeros((4, 33, 3)), BLAZEPOSE_33, 25.0, metadata=meta), path)
    capsys.readouterr()
    assert load_clip(path).n_frames == 4
    assert capsys.readouterr().err == ""
