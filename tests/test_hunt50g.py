"""Case base stores under several processes at once (hunt 50g): real SQLite files, real
processes where the point is a process."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casebase_store import open_store
from cbr.classification import classify_with_feedback
from cbr.stored import load_classifier
from cbr.training import append, append_described, append_plan, describe
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


def test_an_activity_another_append_added_meanwhile_is_not_said_to_be_new(
    tmp_path: Path,
) -> None:
    # before: two `train --append` at once of clips of one new activity both said "note: 1
    # activity the case base did not hold, added as new: ...": the second was told so of
    # the case base as it read it, though the first had added that activity before its cases
    db = small_case_base(tmp_path)
    clips = sorted((tmp_path / "train").rglob("*.npz"))
    plan, uid, _, _ = append_plan(db, "default")  # the second append reads the case base
    late = [describe(_without_first_frame(clips[0]), plan)]
    first = append(db, "default", [_without_first_frame(clips[1])], ["hop"])
    assert first.new_labels == ["hop"]
    second = append_described(db, "default", late, ["hop"], plan, uid)
    assert second.new_labels == []
    with open_store(db, readonly=True) as store:
        assert store.get_case_base("default").label_counts["hop"] == 2
