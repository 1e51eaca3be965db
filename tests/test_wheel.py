"""The package as a user gets it: build the wheel, install it into a new environment, run the
demo from an empty folder with the installed code.

How, within the suite's time budget (about 45 s here, most of it the demo):

- the wheel is built from a copy of the checkout (``pip wheel --no-deps --no-build-isolation
  --no-index``: the build tools of this environment, nothing downloaded, nothing written into
  the checkout);
- the new environment is a ``venv`` without pip into which pip installs the wheel; its
  dependencies are not downloaded again but come from this environment's site-packages,
  added as plain path entries by a ``.pth`` file. Plain entries run no ``.pth`` file of their
  own, so the editable install's finder (which maps the packages to the checkout) is not
  there: the code that runs is the wheel's, and each test checks where it lies. A test checks
  that those site-packages satisfy every requirement the wheel declares;
- numba's kernels, compiled once by the suite from the checkout's sources, are copied beside
  the installed modules (the same sources), so the demo loads them instead of compiling them
  again; a kernel the suite has not compiled yet is compiled by the demo.
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import site
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from features.version import __version__

# under pytest-xdist the module's tests run on one worker: the wheel is built and installed once
pytestmark = pytest.mark.xdist_group("wheel")

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("posecbr", "features", "cbr", "casebase_store")
TOP_FILES = ("pyproject.toml", "README.md", "LICENSE", "CHANGELOG.md")


@dataclass(frozen=True)
class Installed:
    wheel: Path
    env: Path
    site_packages: Path
    run_env: dict[str, str]

    @property
    def python(self) -> Path:
        return self.env / "bin" / "python"

    def run(self, args: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
        return subprocess.run(
            args, cwd=cwd, env=self.run_env, capture_output=True, text=True, timeout=timeout
        )


def _clean_env() -> dict[str, str]:
    """This process's environment without what would put the checkout on the path."""
    drop = {"PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONSAFEPATH", "VIRTUAL_ENV"}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["PYTHONNOUSERSITE"] = "1"
    env["POSECBR_NO_PROGRESS"] = "1"
    env["MPLBACKEND"] = "Agg"
    return env


def _build_wheel(out: Path) -> Path:
    src = out / "src"
    src.mkdir(parents=True)
    for name in TOP_FILES:
        shutil.copy2(ROOT / name, src / name)
    for pkg in PACKAGES:
        shutil.copytree(ROOT / pkg, src / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    dist = out / "dist"
    cmd = [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
           "--no-index", "-w", str(dist), str(src)]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=_clean_env())
    assert proc.returncode == 0, proc.stderr
    (wheel,) = dist.glob("posecbr-*.whl")
    return wheel


def _new_env(base: Path, wheel: Path) -> Installed:
    env = base / "env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env)], check=True)
    python = env / "bin" / "python"
    code = "import sysconfig; print(sysconfig.get_paths()['purelib'])"
    site_packages = Path(subprocess.check_output([str(python), "-c", code], text=True).strip())
    deps = [p for p in site.getsitepackages() if Path(p).is_dir()]
    (site_packages / "_posecbr_test_dependencies.pth").write_text("\n".join(deps) + "\n")
    run_env = _clean_env()
    cmd = [str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-index",
           "--ignore-installed", str(wheel)]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=run_env)
    assert proc.returncode == 0, proc.stderr
    return Installed(wheel, env, site_packages, run_env)


def _numba_caches_of_the_checkout(site_packages: Path) -> int:
    """numba's cached kernels of the checkout (``__pycache__/*.nbi``, ``*.nbc``, written by
    the suite's first compile, ``tests/_kernels.py``) copied beside the installed modules
    they were compiled from, each installed module given its checkout twin's modification
    time (numba keys a cache by its source file's time and size): the demo loads the
    kernels instead of compiling them again from the same source (about 11 s of CPU). Only
    where the installed file is byte for byte the checkout's. Returns the files copied."""
    copied = 0
    for pkg in PACKAGES:
        for cache in sorted((ROOT / pkg).rglob("__pycache__")):
            kernels = sorted(cache.glob("*.nb[ic]"))
            if not kernels:
                continue
            source_dir = cache.parent.relative_to(ROOT)
            for source in (ROOT / source_dir).glob("*.py"):
                twin = site_packages / source_dir / source.name
                if twin.is_file() and twin.read_bytes() == source.read_bytes():
                    st = source.stat()
                    os.utime(twin, ns=(st.st_atime_ns, st.st_mtime_ns))
            (site_packages / source_dir / "__pycache__").mkdir(exist_ok=True)
            for kernel in kernels:
                shutil.copy2(kernel, site_packages / source_dir / "__pycache__" / kernel.name)
                copied += 1
    return copied


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Installed]:
    base = tmp_path_factory.mktemp("wheel")
    env = _new_env(base, _build_wheel(base))
    _numba_caches_of_the_checkout(env.site_packages)
    yield env
    shutil.rmtree(base, ignore_errors=True)  # ~40 MB of wheel, copy and install


def _package_files() -> set[str]:
    """Every file of the packages in the checkout except Python sources and caches."""
    out = set()
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".py":
                out.add(path.relative_to(ROOT).as_posix())
    return out


def test_wheel_holds_every_data_file_the_packages_have(installed: Installed) -> None:
    names = set(zipfile.ZipFile(installed.wheel).namelist())
    data = _package_files()
    # the ones the commands need, named so that a glob that lost them all would still fail
    assert {
        "features/pose_estimation/models/pose_detection.onnx",
        "features/pose_estimation/models/pose_landmark_full.onnx",
        "features/pose_estimation/models/LICENSE",
        "features/pose_estimation/models/PROVENANCE.md",
        "features/qmp/add.toml",
        "posecbr/demo_data/uiprmd/labels.csv",
        "posecbr/demo_data/uiprmd/SOURCE.md",
    } <= data
    assert (
        sum(n.startswith("posecbr/demo_data/uiprmd/") and n.endswith(".npz") for n in data) == 180
    )
    assert data - names == set()
    licence = f"posecbr-{__version__}.dist-info/LICENSE"
    assert zipfile.ZipFile(installed.wheel).read(licence) == (ROOT / "LICENSE").read_bytes()
    assert b"Apache License" in (ROOT / "LICENSE").read_bytes()[:200]


def test_wheel_version_is_the_one_in_features_version(installed: Installed) -> None:
    meta = zipfile.ZipFile(installed.wheel).read(f"posecbr-{__version__}.dist-info/METADATA")
    assert re.search(rf"^Version: {re.escape(__version__)}$", meta.decode(), re.M)
    assert installed.wheel.name.startswith(f"posecbr-{__version__}-")
    proc = installed.run([str(installed.env / "bin" / "posecbr"), "--version"], installed.env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"posecbr {__version__}"


def test_the_new_environment_satisfies_the_wheels_requirements(installed: Installed) -> None:
    code = (
        "import importlib.metadata as m, json\n"
        "from packaging.requirements import Requirement\n"
        "bad = []\n"
        "for text in m.requires('posecbr') or []:\n"
        "    req = Requirement(text)\n"
        "    if req.marker is not None and not req.marker.evaluate({'extra': ''}):\n"
        "        continue\n"
        "    try:\n"
        "        version = m.version(req.name)\n"
        "    except m.PackageNotFoundError:\n"
        "        version = None\n"
        "    if version is None or not req.specifier.contains(version, prereleases=True):\n"
        "        bad.append((text, version))\n"
        "print(json.dumps({'n': len(m.requires('posecbr') or []), 'bad': bad}))"
    )
    proc = installed.run([str(installed.python), "-c", code], installed.env)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["n"] >= 12 and doc["bad"] == []


def test_installed_demo_runs_from_an_empty_folder(installed: Installed, tmp_path: Path) -> None:
    where = [str(installed.python), "-c", "import features, posecbr, cbr, casebase_store as s;"
             "print('\\n'.join(m.__file__ for m in (features, posecbr, cbr, s)))"]  # fmt: skip
    proc = installed.run(where, tmp_path)
    assert proc.returncode == 0, proc.stderr
    for path in proc.stdout.split():
        assert Path(path).is_relative_to(installed.site_packages), path
    assert list(tmp_path.iterdir()) == []

    proc = installed.run([str(installed.env / "bin" / "posecbr"), "demo", "--quick"], tmp_path)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    # the clip it describes is the installed copy of the demo data
    described = re.search(r"^(\S+m01_s01_e01\.npz): (\d+) frames at 30 fps", out, re.M)
    assert described, out[:2000]
    assert Path(described.group(1)).is_relative_to(installed.site_packages / "posecbr")
    # trained on s01 and s02: per movement 2 subjects x 3 correct + 3 incorrect repetitions
    train = out[out.index("== 2. train") : out.index("== 3. classify")]
    counts = re.findall(r"^ +(\d+)  ([a-z_]+)$", train, re.M)
    assert len(counts) == 10 and {n for n, _ in counts} == {"12"}, train
    # classified s03's 60 clips, far above the 10 % of guessing
    accuracy = re.search(r"accuracy: ([\d.]+) % \((\d+)/(\d+) labelled clips\)", out)
    assert accuracy and accuracy.group(3) == "60" and float(accuracy.group(1)) >= 60, out
    demo = tmp_path / "demo-output"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo-output"]
    assert (demo / "casebase.sqlite").stat().st_size > 0
    assert (demo / "timeline_deep_squat.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    results = json.loads((demo / "compare" / "results.json").read_text())
    assert [m["name"] for m in results["methods"]] == ["cbr fluents/euclidean"]
    page = (demo / "report.html").read_text()
    assert page.lstrip().lower().startswith("<!doctype html") and "cbr fluents/euclidean" in page
    # every step prints the command it runs, and the one report holds them all with their
    # output and the timeline picture
    for command in ("describe", "train", "classify", "compare"):
        said = re.search(rf"^\$ posecbr {command} .+$", out, re.M)
        assert said, f"the demo does not print its {command} command"
        assert html.escape(said.group(0)) in page
    assert "accuracy: " in page and "data:image/png;base64," in page
