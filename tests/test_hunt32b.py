"""Hunt 32b: a skeleton with no limbs refused at convert time; compare --trim with fewer cases
than k in a fold; casebase trim's held-out accuracy with mirror twins; Ctrl-C of a Dask
LocalCluster run."""

from __future__ import annotations

import os
import signal
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.badinput import ROOT, refused
from tests.processes import terminal_job

# ---- 1. a skeleton with no limbs ----------------------------------------------------------

_ROOT = """:units
  length 0.45
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
"""

_BONE = """  begin
     name {name}
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx
  end
"""


def _asf(folder: Path, *bones: str) -> Path:
    path = folder / "s.asf"
    blocks = "".join(_BONE.format(name=b) for b in bones)
    tree = f"    root {' '.join(bones)}\n" if bones else ""
    path.write_text(f"{_ROOT}:bonedata\n{blocks}:hierarchy\n  begin\n{tree}  end\n")
    return path


def _amc(folder: Path, *bones: str, name: str = "m.amc") -> Path:
    path = folder / name
    frames = "".join(
        f"{i}\nroot {i} 17 0 0 0 0\n" + "".join(f"{b} 5\n" for b in bones) for i in (1, 2, 3)
    )
    path.write_text(":FULLY-SPECIFIED\n:DEGREES\n" + frames)
    return path


def test_asf_of_the_root_alone_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    # it was refused before as "no :bonedata bones (not an ASF file?)": it is one, of a root
    asf, amc = _asf(tmp_path), _amc(tmp_path)
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, "s.asf: the skeleton has only its root", "no limbs to draw")


def test_a_file_without_root_nor_bones_is_still_not_an_asf(tmp_path: Path) -> None:
    from features.errors import DataError
    from features.readers.asfamc import read_asf

    path = tmp_path / "x.asf"
    path.write_text("hello\n")
    with pytest.raises(DataError, match="not an ASF file"):
        read_asf(path)


def test_asf_whose_bones_place_no_joint_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    # lowerback and head place no BlazePose joint: the clip converted, every joint missing in
    # every frame, and every later command said it "shows no person"
    asf = _asf(tmp_path, "lowerback", "head")
    amc = _amc(tmp_path, "lowerback", "head")
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, "s.asf: none of its bones", "it has lowerback, head")


def test_amc_listing_only_the_root_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    asf = _asf(tmp_path, "lhipjoint", "rhipjoint")
    amc = _amc(tmp_path)  # root lines only
    argv = ["convert", str(amc), "--asf", str(asf), "--out", str(tmp_path / "out")]
    line = refused(argv, tmp_path, capsys, "m.amc: lists only root")
    assert "no values for lhipjoint, rhipjoint (bones of s.asf that turn)" in line


def test_real_hdm05_skeleton_with_an_amc_of_the_root_alone_is_refused(
    tmp_path: Path, shared_data: Path, capsys: pytest.CaptureFixture
) -> None:
    # HDM05's hip bones do not turn: the root alone placed the two hips, and nothing else, so
    # the clip converted (2 of 33 joints) and then showed no person to every command
    folder = shared_data / "hdm05" / "train" / "3"
    source = sorted(folder.glob("HDM_bd_*.amc"))[0]
    kept = [
        line
        for line in source.read_text(encoding="latin-1").split("\n")
        if line.startswith((":", "#", "root ")) or line.strip().isdigit()
    ]
    amc = tmp_path / "root_only.amc"
    amc.write_text("\n".join(kept[: kept.index("11")]) + "\n", encoding="latin-1")  # 10 frames
    argv = ["convert", str(amc), "--asf", str(folder / "HDM_bd.asf"), "--out", str(tmp_path / "o")]
    refused(argv, tmp_path, capsys, "root_only.amc: lists only root", "lfemur")


_BVH = """HIERARCHY
ROOT {root}
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
{end}}}
MOTION
Frames: 2
Frame Time: 0.0333333
0 90 0 0 0 0
1 90 0 0 0 0
"""


@pytest.mark.parametrize("root", ["Hips", "LeftUpLeg"])
@pytest.mark.parametrize("end", ["", "  End Site\n  {\n    OFFSET 0 10 0\n  }\n"])
def test_bvh_of_the_root_alone_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, root: str, end: str
) -> None:
    # a root named as a hip (LeftUpLeg) converted: one joint of 33, no person to any command
    bvh = tmp_path / "r.bvh"
    bvh.write_text(_BVH.format(root=root, end=end))
    argv = ["convert", str(bvh), "--out", str(tmp_path / "out")]
    refused(argv, tmp_path, capsys, f"r.bvh: the skeleton has only its root ({root})")


# ---- 2. compare --trim leaving fewer cases than k in a fold --------------------------------

DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"


def test_compare_trim_below_k_marks_the_method_failed(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    import json

    from posecbr.cli import main

    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    # 3 subjects x 3 movements x 6 clips: each fold trains on 2 subjects, 12 clips of each
    # movement; --trim 0.05 keeps ceil(0.05 x 12) = 1 of each: 3 cases of 36, and k = 5
    argv = ["compare", str(DEMO), "--labels", "deep_squat,sit_to_stand,standing_shoulder_abduction",
            "--similarities", "euclidean", "--features", "fluents", "--peers", "none",
            "--explain", "0", "--trim", "0.05", "--json", str(tmp_path / "r.json")]  # fmt: skip
    assert main(argv) == 0
    err = capsys.readouterr().err
    res = json.loads((tmp_path / "r.json").read_text())
    rows = {m["name"]: m for m in res["methods"]}
    why = (
        "fold 0 (subject s01 held out): trimming kept 3 of 36 cases, fewer than the 5 the case"
        " base votes with (k): not scored (keep more with --trim, or give a smaller --k)"
    )
    assert rows["cbr fluents/euclidean"]["status"] == "failed"
    assert rows["cbr fluents/euclidean"]["message"] == why
    assert f"note: cbr fluents/euclidean failed: {why}" in err.splitlines()
    assert rows["dad"]["status"] == "ok" and res["best"] == "dad"  # the other rows are kept
    # ceil(0.1 x 12) = 2 of each movement: 6 cases, not fewer than k = 5: scored
    argv[argv.index("0.05")] = "0.1"
    assert main(argv) == 0
    res = json.loads((tmp_path / "r.json").read_text())
    row = next(m for m in res["methods"] if m["name"] == "cbr fluents/euclidean")
    assert row["status"] == "ok" and row["case_base_size"] == 6


def test_a_fold_is_named_by_the_subject_it_holds_out_only_when_it_holds_one_out() -> None:
    import numpy as np

    from cbr.evaluation.tasks import RunContext, fold_name

    def ctx(subjects: list[str], folds: list[int]) -> RunContext:
        data = SimpleNamespace(subjects=subjects)
        return RunContext(data, (), np.array(folds), ())  # type: ignore[arg-type]

    loso = ctx(["s1", "s1", "s2", "s2"], [0, 0, 1, 1])
    assert fold_name(loso, 1) == "fold 1 (subject s2 held out)"
    # k folds of one subject's clips: every fold's clips are s1's, and so are the training's
    one = ctx(["s1"] * 4, [0, 1, 0, 1])
    assert fold_name(one, 0) == "fold 0"
    mixed = ctx(["s1", "s2", "s1", "s2"], [0, 0, 1, 1])
    assert fold_name(mixed, 0) == "fold 0"


# ---- 3. casebase trim's held-out accuracy with mirror twins --------------------------------


def test_trim_accuracy_holds_out_the_mirror_twin(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    import json
    import shutil

    from posecbr.cli import main

    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    # three real Kinect clips: one deep squat, two shoulder abductions (two subjects); with
    # --mirror augment six cases, each clip and its mirror image
    data = tmp_path / "data"
    data.mkdir()
    for name in ("m01_s01_e01.npz", "m07_s01_e01.npz", "m07_s02_e01.npz"):
        shutil.copy(DEMO / name, data / name)
    (data / "labels.csv").write_text(
        "path,label\nm01_s01_e01.npz,deep_squat\nm07_s01_e01.npz,abduction\n"
        "m07_s02_e01.npz,abduction\n"
    )
    db = str(tmp_path / "cb.sqlite")
    assert main(["train", str(data), "--db", db, "--mirror", "augment", "-k", "1"]) == 0
    capsys.readouterr()
    assert main(["casebase", "trim", "--db", db, "--dry-run", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    # Held out with its mirror image, a squat case has no squat left to find (the only other
    # is its twin): both squat cases are answered abduction, wrong. Each abduction case finds
    # the other subject's abduction (or its image): right. 4 of 6, before and after (the trim
    # keeps a case and its image together: ceil(0.7 x 1) = 1 squat pair, ceil(0.7 x 2) = 2
    # abduction pairs, every case). Before, a squat case was answered by its own mirror image:
    # 5 of 6 before trimming.
    assert doc["size_before"] == 6 and doc["size_after"] == 6
    assert doc["accuracy_before"] == pytest.approx(4 / 6)
    assert doc["accuracy_after"] == pytest.approx(4 / 6)
    assert (
        doc["measured"] == "1-NN, each of the 6 cases before left out in turn with its mirror image"
    )


def test_mirror_twins_pair_a_clip_with_its_image_only() -> None:
    import numpy as np

    from cbr.casebase import CaseBase
    from cbr.maintenance import mirror_twins

    sources = ("a.npz", "b.npz", "a.npz (mirrored)", "b.npz (mirrored)", "a.npz")
    frames = ((0, 10), (0, 10), (0, 10), (0, 10), (10, 20))
    cb = CaseBase(None, None, np.zeros((5, 1)), np.array(["x"] * 5, dtype=object),  # type: ignore[arg-type]
                  ("f",), ("f",), sources=sources, frames=frames)  # fmt: skip
    got = mirror_twins(cb)
    want = np.zeros((5, 5), dtype=bool)
    want[0, 2] = want[2, 0] = want[1, 3] = want[3, 1] = True  # a's frames 10-20 have no image
    np.testing.assert_array_equal(got, want)


# ---- 4. Ctrl-C of compare --scheduler local:2 ------------------------------------------------


def _group(pgid: int) -> list[int]:
    """The processes of process group ``pgid`` that are still running (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # ended meanwhile
        if int(fields[2]) == pgid and fields[0] != "Z":  # pgrp; a zombie has ended
            out.append(int(stat.parent.name))
    return out


@pytest.mark.skipif(sys.platform != "linux", reason="process groups and /proc: Linux")
@pytest.mark.parametrize("wait_s", [0.0, 3.0])  # as the workers start; at the first tasks
def test_ctrl_c_of_compare_on_a_local_cluster_prints_one_line(
    tmp_path: Path, wait_s: float
) -> None:
    """Ctrl-C in a terminal signals every process of the group: the Dask workers (and their
    nannies' shutdown) printed KeyboardInterrupt tracebacks, CancelledError, "Failed to
    communicate with scheduler during heartbeat" and "Removing worker ... lose scattered
    data" under "posecbr compare: interrupted". Now the one line, status 130, no process of
    the run left, nothing written."""
    pytest.importorskip("dask.distributed", reason="dask is in the test extra")
    argv = ["compare", str(DEMO), "--peers", "none"]
    argv += ["--labels", "deep_squat,hurdle_step,sit_to_stand", "--scheduler", "local:2"]
    argv += ["--out", str(tmp_path / "o")]
    proc = terminal_job(argv, tmp_path)
    workers: list[int] = []
    deadline = time.monotonic() + 300
    while len(workers) < 2 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
        workers = [
            p
            for p in _group(proc.pid)
            if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()  # Dask's workers
        ]
    assert len(workers) >= 2, "the workers never started"
    time.sleep(wait_s)
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert (proc.returncode, err.decode(), out.decode()) == (
        130,
        "posecbr compare: interrupted\n",
        "",
    )
    left = _group(proc.pid)
    for _ in range(50):  # the workers end with the command
        if not left:
            break
        time.sleep(0.2)
        left = _group(proc.pid)
    assert left == []
    assert not (tmp_path / "o").exists()
