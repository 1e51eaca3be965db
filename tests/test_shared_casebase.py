"""One case base, many writers (issue 16): several processes train into (``train --append``),
classify against and retain into one case base at the same time, on SQLite and on a real
PostgreSQL server (CI starts one with .ci/postgres.sh), and no case is lost or duplicated."""

from __future__ import annotations

import csv
from collections import Counter
from pathlib import Path

import pytest

from casebase_store import open_store
from tests.postgres import postgres_copy_of
from tests.processes import posecbr_process
from tests.test_feedback_safety import trained  # noqa: F401 (a fixture)

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "posecbr" / "demo_data" / "uiprmd"
LABELS = DEMO / "labels.csv"
# the appending writers each add subject s03's clips of their own movement
SHARES = ("deep_squat", "side_lunge")


def _clips_of(labels: str, subject: str) -> list[str]:
    wanted = set(labels.split(","))
    with open(LABELS, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["label"] in wanted and r["subject"] == subject]
    return [str((DEMO / r["path"]).resolve()) for r in rows]


@pytest.fixture(params=["sqlite", "postgresql"])
def db_url(request: pytest.FixtureRequest, trained: Path, tmp_path: Path) -> str:  # noqa: F811
    """A case base of subjects s01 and s02 (120 cases) on each backend: a copy of the one
    tests/test_feedback_safety.py trains (made once; on PostgreSQL by ``casebase copy``)."""
    if request.param == "sqlite":
        db = tmp_path / "cb.sqlite"
        db.write_bytes(trained.read_bytes())
        return str(db)
    return postgres_copy_of(trained)


def _state(url: str) -> tuple[int, list[int], list[str], list[str], list[str]]:
    store = open_store(url, readonly=True)
    try:
        info, cases = store.load_case_base("default")
        log = [e.action for e in store.maintenance_log("default")]
        return info.version, cases.ids.tolist(), list(cases.sources), list(cases.origins), log
    finally:
        store.close()


def test_four_writers_appending_and_retaining_lose_and_duplicate_nothing(db_url: str) -> None:
    """Two processes train into the case base (``train --append``) while two others classify
    clips against it and retain them, all four at once: every clip of each writer ends up in
    it exactly once (a clip both classifying writers give is retained by one), and the case
    base's version counts every commit."""
    version, ids, sources, _, _ = _state(db_url)
    retained = _clips_of("standing_shoulder_scaption", "s03")  # six clips
    writers = [
        posecbr_process("train", str(LABELS), "--db", db_url, "--append", "--subjects", "s03",
                        "--labels", share)  # fmt: skip
        for share in SHARES
    ] + [
        posecbr_process("classify", *retained, "--db", db_url, "--feedback",
                        "standing_shoulder_scaption", "--novelty", "0", "--benefit", "0")
        for _ in range(2)
    ]  # fmt: skip
    for p in writers:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
    new_version, new_ids, new_sources, _, log = _state(db_url)
    added = Counter(new_sources) - Counter(sources)
    appended = [c for share in SHARES for c in _clips_of(share, "s03")]
    assert len(appended) == 12 and len(retained) == 6
    # none lost, none twice: each retained clip once, its case stored already when the other
    # classifying writer came to it (not retained again: its feedback revises the case base)
    assert added == Counter(appended) + Counter(retained)
    assert len(new_ids) == len(set(new_ids)) == len(ids) + 12 + 6
    assert set(ids) <= set(new_ids)  # the trained cases are all still there
    assert log.count("append") == 2 and log.count("retain") == 12 and log.count("revise") == 6
    assert new_version == version + 2 + 12  # one per append, per retained clip, per revision
