"""Case base stores under several processes at once (hunt 50g): real SQLite files, real
processes where the point is a process."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.classification import classify_with_feedback
from cbr.stored import load_classifier
from features.poses import PoseSequence, load_pose
from posecbr.cli import main
from tests.badinput import small_case_base


def _without_first_frame(clip: Path) -> PoseSequence:
    """Another take of ``clip``: its poses from the second frame on (another case)."""
    seq = load_pose(str(clip))
    return seq.slice_frames(1, None)


def test_a_case_relabelled_by_another_process_is_not_moved_toward_a_clip_of_its_old_label(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: a feedback run that read the case base before another run relabelled case c
    # moved c, now of the other activity, a quarter of the way toward its clip of c's old
    # activity ("moved: nearest case has the true label"), as it had decided on c's old label
    db = small_case_base(tmp_path)
    clip = sorted((tmp_path / "train").rglob("*.npz"))[0]
    old, new = clip.parent.name, "relabelled"
    take = _without_first_frame(clip)
    store = open_store(db)
    try:
        stale = load_classifier(store, "default")  # read before the other run's change
        nearest = stale.classifier.solve([take])[0].retrieval
        case = int(nearest.case_ids[0])
        assert nearest.labels[0] == old  # so its feedback as `old` would move that case
        # the other run: the case's own clip is `new` (it lies at 0 from it: relabelled)
        argv = ["classify", str(clip), "--feedback", new, "--new-label", "--quiet"]
        assert main([*argv, "--db", str(db)]) == 0
        capsys.readouterr()
        relabelled = store.load_cases("default", ids=[case])
        assert relabelled.labels.tolist() == [new]
        (done,) = classify_with_feedback(store, stale, [take], old)
        after = store.load_cases("default", ids=[case])
        # a relabel moves no problem, and nothing else moved the case toward `take`
        assert np.array_equal(after.features, relabelled.features)
        rev = done.revision
        if rev is not None and rev.action == "moved":  # decided again on the case base now
            moved = store.load_cases("default", ids=[rev.case_id])
            assert moved.labels.tolist() == [old]
        log = [e for e in store.maintenance_log("default") if e.case_id == case]
        assert [e.reason.split(":")[0] for e in log] == ["relabelled"]
    finally:
        store.close()
