"""The report page in a real browser (Debian's headless Chromium): it loads with no console
message, shows the results table and every picture (naturalWidth > 0), and a screenshot is
kept under tests/artifacts/ for people to look at."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from posecbr.cli import main

ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = ROOT / "tests" / "artifacts"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip

# Appended to a copy of the page: after load, count the images that did not decode and write
# the counts into the DOM (read back with --dump-dom), and log one known console message so
# the test proves console capture works.
PROBE = """<script>
window.addEventListener("load", () => {
  const imgs = [...document.images];
  const r = {images: imgs.length,
             broken: imgs.filter(i => !(i.complete && i.naturalWidth > 0)).length,
             widths: imgs.map(i => i.naturalWidth),
             rows: document.querySelectorAll("table#results tbody tr").length,
             table_visible: document.querySelector("table#results").offsetHeight > 0};
  const p = document.createElement("pre"); p.id = "probe"; p.textContent = JSON.stringify(r);
  document.body.appendChild(p);
  console.log("probe-console-check");
});
</script></body>"""

pytestmark = [
    pytest.mark.skipif(
        CHROMIUM is None,
        reason="chromium is not installed (apt-get install -y chromium; .ci/run installs it)",
    ),
    # under pytest-xdist the module's tests run on one worker: the report is made once
    pytest.mark.xdist_group("report-chromium"),
]


def _chromium(tmp: Path, *args: str) -> subprocess.CompletedProcess[str]:
    profile = tmp / f"profile-{len(list(tmp.glob('profile-*')))}"  # fresh profile per run
    cmd = [str(CHROMIUM), *FLAGS, f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)


@pytest.fixture(scope="module")
def report(compared_slice: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """The report of a comparison on 54 real clips (tests/conftest.py, shared with
    tests/test_compare_cli.py: three movements, fluents by euclidean and dtw, DAD, two
    explanations), made from a copy of its results folder."""
    out = tmp_path_factory.mktemp("report") / "o"
    shutil.copytree(compared_slice / "o", out)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("POSECBR_NO_PROGRESS", "1")
        assert main(["report", str(out), "--out", str(out / "report.html")]) == 0
    return out / "report.html", json.loads((out / "results.json").read_text())


def test_report_is_self_contained(report: tuple[Path, dict]) -> None:
    page = report[0].read_text()
    # Nothing is fetched: every src/href is inline data.
    refs = re.findall(r'(?:src|href)=["\']([^"\']+)', page)
    assert refs and all(r.startswith("data:") for r in refs)


def test_report_loads_without_console_messages_and_shows_every_picture(
    report: tuple[Path, dict], tmp_path: Path
) -> None:
    page, results = report
    pics = results["pictures"]
    n_pictures = 2 + len(pics["confusion"]) + len(pics["timelines"])  # + accuracy, prevalence
    probe_page = tmp_path / "probe.html"
    probe_page.write_text(page.read_text().replace("</body>", PROBE))
    run = _chromium(
        tmp_path,
        "--enable-logging=stderr",
        "--v=0",
        "--virtual-time-budget=10000",
        "--dump-dom",
        probe_page.as_uri(),
    )
    m = re.search(r'<pre id="probe">([^<]*)</pre>', run.stdout)
    assert m, f"the page did not finish loading: {run.stderr[-2000:]}"
    probe = json.loads(m.group(1))
    assert probe["images"] == n_pictures == 2 + 2 + 3
    assert probe["broken"] == 0 and min(probe["widths"]) > 100
    assert probe["table_visible"] and probe["rows"] == len(results["methods"])
    console = [ln for ln in run.stderr.splitlines() if ":CONSOLE" in ln]
    assert any("probe-console-check" in ln for ln in console), "console capture did not work"
    others = [ln for ln in console if "probe-console-check" not in ln]
    assert others == []


def test_screenshot_of_the_report_is_kept(report: tuple[Path, dict], tmp_path: Path) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / "report.png"
    shot.unlink(missing_ok=True)
    run = _chromium(
        tmp_path,
        f"--screenshot={shot}",
        "--window-size=1280,2400",
        "--hide-scrollbars",
        report[0].as_uri(),
    )
    assert shot.exists(), run.stderr[-2000:]
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width = int.from_bytes(data[16:20], "big")
    height = int.from_bytes(data[20:24], "big")
    assert (width, height) == (1280, 2400)
    shutil.copy(report[0], ARTIFACTS / "report.html")
