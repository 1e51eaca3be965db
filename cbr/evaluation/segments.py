"""A segmentation scored against labels over time (``posecbr segment --truth``, and
``python -m benchmarks.segment``: one function, so the two cannot drift).

- :func:`truth_blocks`: the true label of every :data:`cbr.segmentation.BLOCK_S` block, from
  one label per frame (a block's label is that of its first frame, as a label file's blocks
  are read, or below 10 fps, where a block may hold no frame, that of the frame before it);
- :func:`label_blocks`: the same from one label per fixed time (``--label-block``), read at
  each block's time whatever the recording's frame rate;
- :func:`score_segmentation`: the figures: the share of blocks of labels the case base has
  that got their label (a block called unknown counts wrong), the share of blocks of labels
  it lacks that were called unknown, and each labelled change's distance to the nearest
  segment boundary.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from features.label_tracks import code_order
from features.text import spelt_as


def truth_blocks(per_frame: np.ndarray, fps: float, block_s: float) -> np.ndarray:
    """``(n_blocks,)``: the label of each ``block_s`` block of a recording labelled frame by
    frame ``per_frame`` ``(n_frames,)``: that of the block's first frame (the first whose time
    lies in it), as many blocks as :func:`cbr.segmentation.segment` gives."""
    per_block = fps * block_s
    n_blocks = int(math.ceil(len(per_frame) / per_block - 1e-9))
    start = np.arange(n_blocks) * per_block  # each block's start, in frames
    first = np.ceil(start - 1e-9)
    # below 10 fps a block may hold no frame: the frame before it holds its time
    first = np.where(first < start + per_block - 1e-9, first, np.floor(start + 1e-9))
    index = np.minimum(first.astype(np.int64), len(per_frame) - 1)
    out: np.ndarray = np.asarray(per_frame, dtype=object)[index]
    return out


def label_blocks(
    labels: Sequence[str], label_s: float, n_frames: int, fps: float, block_s: float
) -> np.ndarray:
    """``(n_blocks,)``: the label of each ``block_s`` block of a recording of ``n_frames`` at
    ``fps`` from one label per ``label_s`` seconds (``labels``, checked to fit it:
    :func:`features.label_tracks.frame_labels`): the one whose time holds the block's start.
    Labels are per time, so a recording thinned to 2 fps is scored on the same blocks as at
    120 fps, not on the blocks its frames fall in; as many blocks as
    :func:`cbr.segmentation.segment` gives, but none past the labels' end (at a low rate the
    last frame's time may lie up to a frame before the frames' end)."""
    n_blocks = int(math.ceil(n_frames / (fps * block_s) - 1e-9))
    labelled = int(math.ceil(len(labels) * label_s / block_s - 1e-9))
    starts = np.arange(min(n_blocks, labelled)) * block_s
    index = np.minimum(np.floor(starts / label_s + 1e-9).astype(np.int64), len(labels) - 1)
    out: np.ndarray = np.asarray(labels, dtype=object)[index]
    return out


@dataclass(frozen=True)
class SegmentationScores:
    """How a segmentation fits the true labels of its blocks.

    ``seen_*``: blocks whose true label is an activity of the case base, and how many got it
    (unknown counts wrong); ``unseen_*``: blocks of labels the case base lacks (``unseen_labels``)
    and how many were called unknown; ``boundary_errors_s``: for every change of the true
    label, the distance in seconds to the nearest segment boundary (inf when the
    segmentation has none)."""

    blocks: int
    block_s: float
    seen_blocks: int
    seen_right: int
    unseen_labels: tuple[str, ...]
    unseen_blocks: int
    unseen_unknown: int
    called_unknown: int
    boundary_errors_s: tuple[float, ...]

    @property
    def seen_accuracy(self) -> float | None:
        return self.seen_right / self.seen_blocks if self.seen_blocks else None

    @property
    def unseen_called_unknown(self) -> float | None:
        return self.unseen_unknown / self.unseen_blocks if self.unseen_blocks else None

    @property
    def median_boundary_error_s(self) -> float | None:
        errors = self.boundary_errors_s
        return float(np.median(errors)) if errors else None

    def to_dict(self) -> dict[str, Any]:
        """The figures as JSON takes them (a distance to no boundary: null)."""

        def finite(x: float | None) -> float | None:
            return x if x is not None and math.isfinite(x) else None

        return {
            "blocks": self.blocks,
            "block_s": self.block_s,
            "seen_blocks": self.seen_blocks,
            "seen_right": self.seen_right,
            "seen_accuracy": self.seen_accuracy,
            "unseen_labels": list(self.unseen_labels),
            "unseen_blocks": self.unseen_blocks,
            "unseen_called_unknown": self.unseen_unknown,
            "unseen_unknown_share": self.unseen_called_unknown,
            "blocks_called_unknown": self.called_unknown,
            "boundary_errors_s": [finite(e) for e in self.boundary_errors_s],
            "median_boundary_error_s": finite(self.median_boundary_error_s),
        }


def score_segmentation(
    result: Any, truth: np.ndarray, known: Iterable[object], block_s: float = 0.1
) -> SegmentationScores:
    """The figures of ``result`` (:class:`cbr.segmentation.Segmentation`) against the true
    label of every ``block_s`` block ``truth`` (:func:`truth_blocks`), ``known`` the case
    base's activities. The blocks both cover are scored; a true label that is an activity
    written in other Unicode characters (:func:`features.text.spelt_as`) is that activity."""
    pred = np.array(result.blocks[: len(truth)], dtype=object)
    truth = np.asarray(truth, dtype=object)[: len(pred)]
    known = {str(k) for k in known}
    labels = list(dict.fromkeys(truth.tolist()))
    spelt = {t: s for t, s in zip(labels, spelt_as(labels, known), strict=True) if s != str(t)}
    if spelt:
        truth = truth.copy()
        truth[:] = [spelt.get(t, t) for t in truth.tolist()]
    seen = np.array([str(t) in known for t in truth], dtype=bool)
    unknown = np.array([p is None for p in pred], dtype=bool)
    fps = result.fps
    found = np.array([s.start_frame / fps for s in result.segments[1:]])
    changes = (np.flatnonzero(truth[1:] != truth[:-1]) + 1) * block_s
    # to the nanosecond: a boundary on a labelled change is 0, not 2.2e-16 s of rounding
    errors = [round(float(np.min(np.abs(found - b))), 9) if len(found) else float("inf")
              for b in changes]  # fmt: skip
    return SegmentationScores(
        blocks=len(truth),
        block_s=block_s,
        seen_blocks=int(seen.sum()),
        seen_right=int(np.sum((pred == truth) & seen)),
        # 1, 2, 10: as a user counts codes (the note on none known lists them so too)
        unseen_labels=tuple(sorted({str(t) for t in truth[~seen]}, key=code_order)),
        unseen_blocks=int((~seen).sum()),
        unseen_unknown=int(np.sum(unknown & ~seen)),
        called_unknown=int(unknown.sum()),
        boundary_errors_s=tuple(errors),
    )
