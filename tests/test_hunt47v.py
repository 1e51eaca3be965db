"""Hunt 47v: ``watch`` gave a finished segment with an empty explanation.

A segment the decoders give a hop or two long (0.4-0.8 s), its activity decided by the
evidence of the hops around it, may hold no window whose own nearest activity is its label
(its one or two windows nearest another). ``watch`` explained an activity only by a window
nearest to it, and such a segment came out explained by "" (the bundled squat clip after 3 s
of nobody, each frame twice at 10 fps: KneeRaise, frames 100-105). ``segment`` tells every
segment by one of its windows (:func:`cbr.segmentation._explain_segment`); now ``watch``
tells this one by the window that lies least far from its activity.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from features.poses import PoseSequence
from tests.test_watch import case_base  # noqa: F401 - the fixture: CMU 13_29's windows

SQUAT = "squat/tfjs_pose_squats_pexels4838220.mp4"  # 65 frames at 5 fps


def test_every_finished_segment_is_explained(
    case_base: Path,  # noqa: F811 - the fixture imported above
    bundled_poses: Callable[[str], PoseSequence],
) -> None:
    """One frame with nobody, then the bundled squat clip's poses, pushed at its 5 fps (a
    hop is 2 frames): among the segments a KneeRaise of frames 36-38 whose one window is
    nearest to Squat. Every finished segment is explained: an activity's as ``told`` words
    it ("N of the 5 most similar cases are <its label>"), an unknown one's in words. Before,
    that KneeRaise's explanation was ""."""
    from casebase_store import open_store
    from cbr.live import LiveSegmenter
    from cbr.stored import load_classifier

    with open_store(case_base, readonly=True) as store:
        clf = load_classifier(store, "default").classifier
    poses = bundled_poses(SQUAT)
    assert poses.confidence is not None
    live = LiveSegmenter(clf, poses.fps, source="camera 0")
    segments = live.push(np.full((33, 3), np.nan), np.zeros(33))
    for world, seen in zip(poses.positions, poses.confidence, strict=True):
        segments += live.push(world, seen)
    segments += live.finish()
    assert [s.start_frame for s in segments[1:]] == [s.end_frame for s in segments[:-1]]
    assert segments[-1].end_frame == poses.n_frames + 1
    labelled = [s for s in segments if s.label is not None]
    assert labelled and len(labelled) < len(segments)  # known and unknown ones
    for s in labelled:
        words = rf"\d of the \d most similar cases (is|are) {s.label}(; matched: .+)?"
        assert re.fullmatch(words, s.explanation), (s.start_frame, s.end_frame, s.explanation)
    assert all(s.explanation for s in segments)
