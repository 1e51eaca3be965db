"""Fuzz every reader of user files with Hypothesis: each must answer one clear error (a
``PosecbrError``) or a valid result, never a traceback.

    nice -n 10 python -m tools.fuzz_readers --seconds 600            # every reader, 10 min each
    python -m tools.fuzz_readers --seconds 30 bvh asfamc --json out.json

Readers (targets): ``npz`` (pose files through ``posecbr describe``), ``labels_csv`` (labels
CSVs through the dataset loader), ``asfamc``, ``bvh``, ``uiprmd`` (Kinect and Vicon),
``thresholds`` (JSON and TOML, and the accepted table evaluated on a pose), ``add`` (the ADD
TOML). Inputs are valid seeds changed by Hypothesis-drawn mutations (tokens replaced by
awkward values, lines dropped, doubled or swapped, bytes flipped, files truncated) and, for the
structured formats, documents drawn from the format's own vocabulary. Seeds for ASF/AMC and
UI-PRMD are cut from the real data in ``../shared/data`` (those readers are skipped without it).

Per reader it prints the inputs tried, how many were accepted, how many gave a clear error and
how many distinct messages, and every traceback (type, where it was raised, an example input).
Runs in batches of Hypothesis examples under its own seeds until the time is up; nothing is
written outside a temporary folder.
"""

from __future__ import annotations

import argparse
import contextlib
import gzip
import io
import json
import os
import re
import sys
import tempfile
import time
import traceback
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from features.errors import PosecbrError
from features.skeleton import BLAZEPOSE_33

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("POSECBR_SHARED_DATA", ROOT.parent / "shared" / "data"))

# Values that break parsers: empty, not-a-number, infinities, huge and tiny numbers, integers
# beyond the digit limit, signs alone, control and format characters, quotes and brackets.
AWKWARD = (
    "", " ", "nan", "NaN", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e309", "1e-320",
    "0", "-0", "-1", "1", "2", "99999999999999999999", "9" * 5000, "0x10", "1_000", "+", "-",
    ".", "..", "/", "pi", "3pi/0", "pi/0.0", "abc", "\x00", "\x1b]0;title\x07", "\x1b[2J",
    "\u202e", "\ufeff", "é", "π", '"', "'", "[", "]", "{", "}", "=", ",", "#", ";", "\n",
    "\r", "\t", "true", "null", "[]", "{}", "../../etc/passwd", "/dev/zero", "a" * 300,
    "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
)  # fmt: skip
OPS = ("replace", "delete_line", "double_line", "swap_lines", "truncate", "insert", "flip",
       "repeat")  # fmt: skip
MUTATIONS = st.lists(
    st.tuples(
        st.sampled_from(OPS),
        st.floats(0.0, 1.0),
        st.floats(0.0, 1.0),
        st.one_of(st.sampled_from(AWKWARD), st.text(max_size=6)),
    ),
    min_size=1,
    max_size=6,
)


def mutate(text: str, ops: list[tuple[str, float, float, str]]) -> str:
    """``text`` changed by each ``(op, where, where2, value)`` in turn."""
    for op, a, b, value in ops:
        lines = text.split("\n")
        i, j = int(a * len(lines)) % max(len(lines), 1), int(b * len(lines)) % max(len(lines), 1)
        if op == "replace":
            tokens = re.split(r"([\s,=]+)", text)
            k = int(a * len(tokens)) % max(len(tokens), 1)
            tokens[k] = value
            text = "".join(tokens)
        elif op == "delete_line" and lines:
            del lines[i]
            text = "\n".join(lines)
        elif op == "double_line" and lines:
            lines.insert(i, lines[i])
            text = "\n".join(lines)
        elif op == "swap_lines" and lines:
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        elif op == "truncate":
            text = text[: int(a * len(text))]
        elif op == "insert":
            k = int(a * len(text))
            text = text[:k] + value + text[k:]
        elif op == "flip" and text:
            k = int(a * len(text)) % len(text)
            text = text[:k] + chr((ord(text[k]) + 1 + int(b * 200)) % 0x250) + text[k + 1 :]
        elif op == "repeat":
            k = int(a * len(text))
            text = text[:k] + text[k : k + 64] * (1 + int(b * 50)) + text[k:]
    return text


def mutate_bytes(data: bytes, ops: list[tuple[str, float, float, str]]) -> bytes:
    """Byte-level changes for binary formats (the zip of a pose file, a gzip)."""
    out = bytearray(data)
    for op, a, b, value in ops:
        k = int(a * len(out)) % max(len(out), 1)
        if op in ("flip", "replace") and out:
            out[k] ^= 1 + int(b * 254)
        elif op == "truncate":
            del out[k:]
        elif op in ("insert", "double_line"):
            out[k:k] = value.encode("utf-8", "surrogatepass")
        elif op in ("delete_line", "swap_lines") and out:
            del out[k : k + 1 + int(b * 16)]
        elif op == "repeat":
            out[k:k] = bytes(out[k : k + 16]) * (1 + int(b * 20))
    return bytes(out)


# ---- findings ---------------------------------------------------------------------------


def _normalise(message: str) -> str:
    """A message with its particulars (paths, quoted values, numbers) blanked, so that
    distinct kinds of error count once."""
    text = re.sub(r"^\S+?: ", "", message, count=1)  # the file it names
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "Q", text)
    text = re.sub(r"/[^\s:,()]+", "P", text)
    return re.sub(r"[-+]?\d[\d.e+\-]*", "N", text)[:160]


@dataclass
class Stats:
    """What one reader did with the inputs it was given."""

    tried: int = 0
    accepted: int = 0
    refused: int = 0
    messages: Counter[str] = field(default_factory=Counter)
    tracebacks: dict[str, dict[str, Any]] = field(default_factory=dict)
    slow: list[float] = field(default_factory=list)

    def record(self, outcome: str | BaseException | None, example: Any, seconds: float) -> None:
        self.tried += 1
        if seconds > 5.0:
            self.slow.append(round(seconds, 2))
        if outcome is None:
            self.accepted += 1
        elif isinstance(outcome, str):
            self.refused += 1
            self.messages[_normalise(outcome)] += 1
        else:
            frame = traceback.extract_tb(outcome.__traceback__)[-1]
            where = f"{Path(frame.filename).name}:{frame.lineno}"
            key = f"{type(outcome).__name__} at {where}"
            hit = self.tracebacks.setdefault(
                key,
                {
                    "count": 0,
                    "message": str(outcome)[:300],
                    "example": repr(example)[:1500],
                    "traceback": "".join(traceback.format_exception(outcome))[-3000:],
                },
            )
            hit["count"] += 1

    def summary(self) -> dict[str, Any]:
        return {
            "inputs_tried": self.tried,
            "accepted": self.accepted,
            "clear_errors": self.refused,
            "distinct_errors": len(self.messages),
            "tracebacks": sum(t["count"] for t in self.tracebacks.values()),
            "distinct_tracebacks": len(self.tracebacks),
            "slower_than_5s": self.slow,
            "traceback_kinds": self.tracebacks,
            "error_kinds": dict(self.messages.most_common()),
        }


def _attempt(run: Callable[[], str | None]) -> str | BaseException | None:
    """None: accepted; a string: a clear one-line error; an exception: a traceback."""
    try:
        return run()
    except PosecbrError as exc:
        if "\n" in str(exc):
            return ValueError(f"error message spans lines: {str(exc)[:200]!r}")
        return str(exc)
    except (KeyboardInterrupt, MemoryError):
        raise
    except BaseException as exc:  # noqa: BLE001 - every other exception is a finding
        return exc


# ---- targets ----------------------------------------------------------------------------


def _standing(frames: int = 6) -> np.ndarray:
    """``(frames, 33, 3)``: a person standing, arms down (enough for every fluent)."""
    from tests.bodies import standing

    body = standing()
    one = np.array([body[n] for n in BLAZEPOSE_33])
    return np.repeat(one[None], frames, axis=0)


def _cli(argv: list[str]) -> str | None:
    """Run a command in-process; its one error line, or None on success."""
    from posecbr.cli import main

    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(argv)
    lines = err.getvalue().strip().splitlines()
    if code == 0:
        return None
    if len(lines) != 1:
        raise AssertionError(f"exit {code} with {len(lines)} lines on stderr: {lines[:3]}")
    return lines[0]


def _good_arrays() -> dict[str, Any]:
    pos = _standing()
    return {
        "positions": pos,
        "joint_names": np.array(BLAZEPOSE_33),
        "fps": 30.0,
        "confidence": np.full(pos.shape[:2], 0.9),
        "skeleton": "blazepose33",
        "metadata": json.dumps({"label": "squat", "subject": "s01", "frame_offset": 0}),
    }


_DTYPES = st.sampled_from(
    [np.float64, np.float32, np.int64, np.uint8, np.bool_, np.complex128, "<U6", "S4"]
)
ANY_ARRAY = hnp.arrays(_DTYPES, hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=5))
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.sampled_from(AWKWARD),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),  # fmt: skip
    max_leaves=12,
)
METADATA = st.one_of(
    st.dictionaries(
        st.sampled_from(["label", "subject", "source", "frame_offset", "correct", "path"]),
        JSON_VALUES,
        max_size=4,
    ).map(json.dumps),
    st.sampled_from(AWKWARD),
)


@st.composite
def _npz_document(draw: st.DrawFn) -> dict[str, Any]:
    """A pose file's arrays: each kept good, dropped, replaced by any array, or (positions)
    a good one with awkward values written into it."""
    arrays = _good_arrays()
    for key in list(arrays):
        choice = draw(st.sampled_from(["keep", "keep", "drop", "any"]))
        if choice == "drop":
            del arrays[key]
        elif choice == "any":
            arrays[key] = draw(METADATA) if key == "metadata" else draw(ANY_ARRAY)
    raw = np.asarray(arrays.get("positions", ""))
    if raw.dtype.kind in "fiu" and raw.size and draw(st.booleans()):
        pos = raw.astype(np.float64)
        if pos.size:
            values = st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e5, 0.0, 1e-320])
            for _ in range(draw(st.integers(1, 4))):
                pos.flat[draw(st.integers(0, pos.size - 1))] = draw(values)
            arrays["positions"] = pos
    if draw(st.booleans()):
        arrays["extra_image_landmarks"] = draw(ANY_ARRAY)
    return arrays


def _npz_bytes(arrays: dict[str, Any], compressed: bool) -> bytes:
    buf = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    return buf.getvalue()


NPZ = st.one_of(
    st.tuples(st.just("arrays"), _npz_document(), st.booleans()),
    st.tuples(st.just("bytes"), MUTATIONS, st.booleans()),
)


def run_npz(work: Path, value: Any) -> str | None:
    kind, payload, compressed = value
    if kind == "arrays":
        data = _npz_bytes(payload, compressed)
    else:
        data = mutate_bytes(_npz_bytes(_good_arrays(), compressed), payload)
    path = work / "clip.npz"
    path.write_bytes(data)
    from features.poses import load_pose_arrays

    found = _cli(["describe", str(path), "--json", "--min-run", "1"])
    if found is None:
        load_pose_arrays(path)
    return found


LABELS_SEED = (
    "path,label,subject,start,end,correct\n"
    "good.npz,squat,s01,0,4,true\n"
    "sub/other.npz,lunge,s02,,,false\n"
    "good.npz,squat,s03,1,3,yes\n"
)
CSV_FIELDS = st.one_of(
    st.sampled_from(["good.npz", "sub/other.npz", "renamed.npz", "missing.npz", "sub",
                     "labels.csv", "path", "label", "start", "end", "0", "5", "-1"]),
    st.sampled_from(AWKWARD),
    st.text(max_size=6),
)  # fmt: skip
LABELS = st.one_of(
    st.tuples(st.just("mutated"), MUTATIONS),
    st.tuples(
        st.just("rows"),
        st.lists(st.lists(CSV_FIELDS, min_size=1, max_size=7), min_size=1, max_size=6),
    ),
)


def _clip_folder(work: Path) -> None:
    from features.poses import PoseSequence, save_pose

    seq = PoseSequence(_standing(), BLAZEPOSE_33, 30.0)
    save_pose(seq, work / "good.npz")
    save_pose(seq, work / "sub" / "other.npz")
    np.save(work / "renamed.npy", _standing())
    (work / "renamed.npy").replace(work / "renamed.npz")


def run_labels_csv(work: Path, value: Any) -> str | None:
    import csv

    from features.datasets import iter_dataset

    if not (work / "good.npz").exists():
        _clip_folder(work)
    kind, payload = value
    if kind == "mutated":
        text = mutate(LABELS_SEED, payload)
    else:
        buf = io.StringIO()
        csv.writer(buf).writerows(payload)
        text = buf.getvalue()
    path = work / "labels.csv"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    for clip in iter_dataset(path):
        assert clip.seq.n_frames >= 1
    return None


BVH_SEED = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -40 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT LeftFoot
      {
        OFFSET 0 -40 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 0 5
        }
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
0 90 0 0 0 0 0 0 0 10 20 0 0 0 0
0 90 0 0 0 0 0 0 0 30 40 0 0 0 0
"""
TEXT = st.tuples(MUTATIONS, st.sampled_from(["auto", "cm", "m"]))


def run_bvh(work: Path, value: Any) -> str | None:
    from features.readers.bvh import read_bvh

    ops, unit = value
    path = work / "clip.bvh"
    path.write_text(mutate(BVH_SEED, ops), encoding="utf-8", errors="surrogatepass")
    read_bvh(path, unit=unit)
    return None


def _first_lines(path: Path, n: int) -> str:
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rt", encoding="latin-1") as fh:  # type: ignore[operator]
        return "".join(next(fh) for _ in range(n))


def _amc_seed(path: Path, frames: int = 3) -> str:
    out, seen = [], 0
    for line in path.read_text(encoding="latin-1").splitlines():
        if line.strip().isdigit():
            seen += 1
            if seen > frames:
                break
        out.append(line)
    return "\n".join(out) + "\n"


def _seeds() -> dict[str, str]:
    """Text seeds cut from the real data (empty when it is absent)."""
    hdm = SHARED / "hdm05" / "train" / "3"
    kinect = SHARED / "ui-prmd" / "data" / "Segmented Movements" / "Kinect"
    vicon = SHARED / "ui-prmd" / "data" / "Segmented Movements" / "Vicon" / "Positions"
    if not (hdm.is_dir() and kinect.is_dir() and vicon.is_dir()):
        return {}
    amc = sorted(hdm.glob("*.amc"))[0]
    return {
        "asf": (hdm / "HDM_bd.asf").read_text(encoding="latin-1"),
        "amc": _amc_seed(amc),
        "kinect_positions": _first_lines(kinect / "Positions" / "m01_s01_e01_positions.txt.gz", 3),
        "kinect_angles": _first_lines(kinect / "Angles" / "m01_s01_e01_angles.txt.gz", 3),
        "vicon": _first_lines(vicon / "m01_s01_e01_positions.txt.gz", 3),
    }


SEEDS: dict[str, str] = {}
ASFAMC = st.tuples(st.sampled_from(["asf", "amc"]), MUTATIONS)


def run_asfamc(work: Path, value: Any) -> str | None:
    from features.readers.asfamc import read_asf_amc

    which, ops = value
    asf, amc = work / "HDM_bd.asf", work / "HDM_bd_squat1Reps_001_120.amc"
    asf.write_text(SEEDS["asf"], encoding="latin-1")
    amc.write_text(SEEDS["amc"], encoding="latin-1")
    target = asf if which == "asf" else amc
    target.write_text(mutate(SEEDS[which], ops), encoding="utf-8", errors="surrogatepass")
    read_asf_amc(asf, amc)
    return None


UIPRMD = st.tuples(
    st.sampled_from(["kinect_positions", "kinect_angles", "vicon"]), MUTATIONS, st.booleans()
)


def run_uiprmd(work: Path, value: Any) -> str | None:
    from features.readers.uiprmd import read_uiprmd_kinect, read_uiprmd_vicon

    which, ops, as_gzip = value
    files = {
        "kinect_positions": work / "m01_s01_e01_positions.txt",
        "kinect_angles": work / "m01_s01_e01_angles.txt",
        "vicon": work / "vicon" / "m01_s01_e01_positions.txt",
    }
    files["vicon"].parent.mkdir(exist_ok=True)
    for name, path in files.items():
        path.write_text(SEEDS[name], encoding="latin-1")
    text = mutate(SEEDS[which], ops).encode("utf-8", "surrogatepass")
    target = files[which]
    if as_gzip:
        # a whole gzip, or a damaged one
        data = gzip.compress(text)
        if ops[0][0] in ("flip", "truncate"):
            data = mutate_bytes(data, ops[:1])
        target.write_bytes(data)
        target = target.rename(target.with_name(target.name + ".gz"))
        if which == "kinect_angles":
            files["kinect_positions"].rename(files["kinect_positions"].with_suffix(".txt.gz"))
            files["kinect_positions"] = files["kinect_positions"].with_suffix(".txt.gz")
        files[which] = target
    else:
        target.write_bytes(text)
    if which == "vicon":
        read_uiprmd_vicon(files["vicon"])
    else:
        read_uiprmd_kinect(files["kinect_positions"], files["kinect_angles"])
    return None


def _thresholds_seed() -> tuple[str, str]:
    from features.fluents import DEFAULT_TABLE

    toml = 'window = 5\nreference_fps = 30\n[fluents.leg_bent.lower]\ntau = "3pi/4"\n'
    return json.dumps(DEFAULT_TABLE.to_dict(), indent=1), toml


THRESHOLD_KEYS = st.sampled_from(
    ["epsilon", "window", "reference_fps", "touching_m", "fluents", "leg_bent", "left_leg_bent",
     "near", "near:left_index~nose", "head_tilted_forward", "lower", "upper", "motion", "tau",
     "delta", "signal", "states"]
)  # fmt: skip
THRESHOLD_DOCS = st.recursive(
    st.sampled_from(AWKWARD) | st.floats() | st.integers(-10, 10**6) | st.booleans(),
    lambda inner: st.dictionaries(THRESHOLD_KEYS, inner, max_size=4) | st.lists(inner, max_size=3),
    max_leaves=16,
)
THRESHOLDS = st.one_of(
    st.tuples(st.just("json"), MUTATIONS),
    st.tuples(st.just("toml"), MUTATIONS),
    st.tuples(st.just("doc"), THRESHOLD_DOCS),
)


def run_thresholds(work: Path, value: Any) -> str | None:
    from features.fluents import FluentTable, evaluate
    from features.poses import PoseSequence

    kind, payload = value
    seed_json, seed_toml = _thresholds_seed()
    if kind == "doc":
        path, text = work / "t.json", json.dumps(payload)
    elif kind == "json":
        path, text = work / "t.json", mutate(seed_json, payload)
    else:
        path, text = work / "t.toml", mutate(seed_toml, payload)
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    table = FluentTable.from_file(path)
    # An accepted table must give confidences in [0, 1] (or NaN), never anything else.
    pos = _standing(12)
    pos[6:, 13] += 0.1  # the left elbow moves: temporal states change
    conf = evaluate(PoseSequence(pos, BLAZEPOSE_33, 30.0), table).confidence
    bad = ~np.isnan(conf) & ((conf < 0) | (conf > 1))
    if bad.any():
        raise AssertionError(f"accepted table gives confidences outside [0, 1]: {conf[bad][:3]}")
    return None


ADD = st.tuples(MUTATIONS, st.booleans())


def run_add(work: Path, value: Any) -> str | None:
    from features.qmp.add import default_add_path, load_add

    ops, crlf = value
    text = mutate(default_add_path().read_text(encoding="utf-8"), ops)
    if crlf:
        text = text.replace("\n", "\r\n")
    path = work / "add.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    load_add(path)
    return None


@dataclass(frozen=True)
class Target:
    strategy: st.SearchStrategy[Any]
    run: Callable[[Path, Any], str | None]
    needs_seeds: bool = False


TARGETS: dict[str, Target] = {
    "npz": Target(NPZ, run_npz),
    "labels_csv": Target(LABELS, run_labels_csv),
    "asfamc": Target(ASFAMC, run_asfamc, needs_seeds=True),
    "bvh": Target(TEXT, run_bvh),
    "uiprmd": Target(UIPRMD, run_uiprmd, needs_seeds=True),
    "thresholds": Target(THRESHOLDS, run_thresholds),
    "add": Target(ADD, run_add),
}


def fuzz(
    name: str, seconds: float = 0.0, examples: int | None = None, batch: int = 200, start: int = 0
) -> Stats:
    """Fuzz one reader for ``seconds`` (or exactly ``examples`` inputs, deterministically)."""
    target = TARGETS[name]
    if target.needs_seeds and not SEEDS:
        SEEDS.update(_seeds())
        if not SEEDS:
            raise FileNotFoundError(f"the real data for the seeds is not in {SHARED}")
    stats = Stats()
    deadline = time.monotonic() + seconds
    with tempfile.TemporaryDirectory(prefix="posecbr-fuzz-") as tmp:
        work = Path(tmp)

        def one(value: Any) -> None:
            t0 = time.perf_counter()
            outcome = _attempt(lambda: target.run(work, value))
            stats.record(outcome, value, time.perf_counter() - t0)

        size = examples if examples is not None else batch
        run_batch = settings(
            max_examples=size,
            deadline=None,
            database=None,
            phases=[Phase.generate],
            suppress_health_check=list(HealthCheck),
            derandomize=examples is not None,
        )(given(target.strategy)(one))
        n = start
        while True:
            seed(n)(run_batch)()
            n += 1
            if examples is not None or time.monotonic() >= deadline:
                return stats


def _table(results: dict[str, dict[str, Any]]) -> str:
    head = (
        f"{'reader':<12}{'tried':>9}{'accepted':>10}{'errors':>9}{'distinct':>10}{'tracebacks':>12}"
    )
    rows = [head, "-" * len(head)]
    for name, r in results.items():
        rows.append(
            f"{name:<12}{r['inputs_tried']:>9}{r['accepted']:>10}{r['clear_errors']:>9}"
            f"{r['distinct_errors']:>10}{r['tracebacks']:>12}"
        )
    return "\n".join(rows)


def _write(path: Path, started: float, seconds: float, results: dict[str, Any]) -> None:
    import platform

    from benchmarks import write_json

    doc = {
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(started)),
        "seconds_per_reader": seconds,
        "load_average": os.getloadavg(),
        "machine": {"python": platform.python_version(), "cpus": os.cpu_count()},
        "readers": results,
    }
    write_json(doc, path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("targets", nargs="*", metavar="READER", help=", ".join(TARGETS))
    parser.add_argument("--seconds", type=float, default=600.0, help="per reader (default 600)")
    parser.add_argument("--json", type=Path, help="write the figures and findings here")
    args = parser.parse_args(argv)
    names = args.targets or list(TARGETS)
    unknown = sorted(set(names) - set(TARGETS))
    if unknown:
        parser.error(f"unknown reader {unknown[0]!r} (known: {', '.join(TARGETS)})")
    results: dict[str, dict[str, Any]] = {}
    started = time.time()
    for name in names:
        t0 = time.perf_counter()
        stats = fuzz(name, args.seconds)
        results[name] = {**stats.summary(), "seconds": round(time.perf_counter() - t0, 1)}
        r = results[name]
        print(
            f"{name}: {r['inputs_tried']} inputs in {r['seconds']} s, {r['tracebacks']} tracebacks",
            file=sys.stderr,
            flush=True,
        )
        for key, hit in stats.tracebacks.items():
            print(f"  {key} (x{hit['count']}): {hit['message'][:200]}", file=sys.stderr)
        if args.json:  # after every reader: a long run stopped early keeps what it found
            _write(args.json, started, args.seconds, results)
    print(_table(results))
    total = sum(r["tracebacks"] for r in results.values())
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())


__all__ = ["TARGETS", "Stats", "fuzz", "main"]
