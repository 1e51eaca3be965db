"""What the cases of each label look like, column by column: the statistics explanations and
counterfactuals read values against.

A case base's problems are read through a *view*: readable columns, each with its machine
name, its words and the *feature* it belongs to.

- vector problems (clip summaries, QMP vectors): the problem's own columns without the
  mirror-image flag, grouped into features by the signal they are computed from
  (:func:`signal_of`: every statistic of the left knee angle and of the fluent states read
  from it, "left knee bent", "left knee bending", ..., is one feature);
- sequence problems ``(length, channels)`` (DTW, signatures): the mean, lowest and highest
  value of every channel over the clip; a feature is the channels of one signal over time.

:class:`Profiles` holds, per label, the mean, spread and the 10th-90th percentile range of
every view column, and per column the spread *within* labels (pooled), which is the yardstick
below which two values do not differ. Binary columns (QMPs detected or not) keep the share of
cases that show them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from features.fluents import DEFAULT_TABLE
from features.signals import ANGLE_SIGNALS

from .casebase import CaseBase
from .problem import ANGLE_PREFIX, POSITION_PREFIX
from .weights import MIRROR_FLAG

#: the share of a label's cases inside its typical range
TYPICAL = (0.1, 0.9)
_SEQUENCE_STATS = (("mean", ""), ("min", " (lowest)"), ("max", " (highest)"))


@dataclass(frozen=True)
class View:
    """Readable columns of a case base's problems.

    names / words ``(m,)``: each column's machine name (``"angle:left_knee@min"``) and words;
    feature ``(m,)``: index of the column's feature in ``features``; features / feature_words:
    the features (groups of columns that change together in a counterfactual); sequence:
    whether the problems are ``(length, channels)`` sequences (a feature is then its channels
    over time); binary ``(m,)``: 0/1 columns (QMPs); channel_feature ``(width,)``: the feature
    of each column of a problem's last axis (-1: none, the mirror-image flag).
    """

    names: tuple[str, ...]
    words: tuple[str, ...]
    feature: np.ndarray
    features: tuple[str, ...]
    feature_words: tuple[str, ...]
    sequence: bool
    columns: np.ndarray  # vector problems: the problem column of each view column
    binary: np.ndarray
    channel_feature: np.ndarray

    def of(self, problems: np.ndarray) -> np.ndarray:
        """``(n, *problem_shape)`` -> ``(n, m)`` view columns."""
        p = np.asarray(problems, dtype=np.float64)
        if self.sequence:
            return np.concatenate([p.mean(axis=1), p.min(axis=1), p.max(axis=1)], axis=1)
        return p[:, self.columns]

    def feature_mask(self, problem_shape: tuple[int, ...], feature: int) -> np.ndarray:
        """Which entries of a problem ``problem_shape`` belong to ``feature`` (bool)."""
        mask = np.zeros(problem_shape, dtype=bool)
        mask[..., self.channel_feature == feature] = True
        return mask


@cache
def _fluent_signals() -> dict[str, tuple[str, str]]:
    """Each fluent of the default table: the signal it is computed from and its subject."""
    return {spec.name: (spec.signal, spec.subject) for spec in DEFAULT_TABLE.specs}


#: the joint each angle signal and joint position belongs to: what the joint does is one
#: feature (the hip: the hip angle and the thigh's direction, and the hip's position)
_JOINT_OF = {
    "elbow": "elbow", "knee": "knee", "armpit": "shoulder", "upper_arm_sagittal": "shoulder",
    "upper_arm_frontal": "shoulder", "upper_arm_plane": "shoulder", "hip": "hip",
    "upper_leg_sagittal": "hip", "upper_leg_frontal": "hip", "shoulder": "shoulder",
    "wrist": "hand", "index": "hand", "ankle": "foot", "heel": "foot", "foot_index": "foot",
}  # fmt: skip


def _joint(name: str) -> str:
    """``left_upper_leg_sagittal`` -> ``left hip``; ``torso_frontal`` -> ``torso``; ``nose``
    and the neck's angles -> ``head``."""
    if name.startswith(("torso", "neck", "nose", "head")):
        return "torso" if name.startswith("torso") else "head"
    side, _, part = name.partition("_")
    if side in ("left", "right") and part in _JOINT_OF:
        return f"{side} {_JOINT_OF[part]}"
    return name.replace("_", " ")


def signal_of(base: str, words: str) -> tuple[str, str]:
    """The feature a column belongs to, and its words: one joint with everything measured at
    it (the angles at the joint, the fluent states read from them, the joint's position: "left
    knee" is the knee angle, "left knee bent", "left knee bending", ..., and where the knee
    is), so a counterfactual that changes one of them changes the others with it, as moving
    the joint does; any other column (a QMP, a near pair) is its own feature."""
    if base.startswith(ANGLE_PREFIX):
        return _feature(_joint(base[len(ANGLE_PREFIX) :]))
    if base.startswith(POSITION_PREFIX):
        return _feature(_joint(base[len(POSITION_PREFIX) :].partition(".")[0]))
    fluent = base.partition(".")[0]
    hit = _fluent_signals().get(fluent)
    if hit is None or hit[0] not in ANGLE_SIGNALS:
        return base, words
    return _feature(_joint(hit[0]))


def _feature(joint: str) -> tuple[str, str]:
    return f"joint:{joint}", joint


def _feature_words(word: str, name: str) -> str:
    """The words of a feature from one of its columns' words (statistic removed)."""
    stat = name.partition("@")[2]
    for suffix in (" (lowest confidence)", " (highest confidence)", " (lowest)", " (highest)",
                   " (variation)"):  # fmt: skip
        if word.endswith(suffix):
            return word[: -len(suffix)]
    if stat.startswith("phase") and word.endswith(")"):
        return word[: word.rfind(" (")]
    return word


def view_of(cb: CaseBase) -> View:
    """The readable columns of ``cb``'s problems (cached on the case base)."""
    key = ("view", cb.problems.shape[1:], cb.names)
    hit = cb.cache.get("view")
    if hit is not None and hit[0] == key:
        cached: View = hit[1]
        return cached
    names, words = cb.names, cb.words
    width = cb.problems.shape[-1]
    if len(names) != width:
        names = tuple(f"feature {i}" for i in range(width))
    if len(words) != width:
        words = names
    keep = [i for i, n in enumerate(names) if n != MIRROR_FLAG]
    bases: dict[str, int] = {}
    base_words: list[str] = []
    channel_feature = np.full(width, -1, dtype=np.int64)
    for i in keep:
        base, said = signal_of(names[i].partition("@")[0], _feature_words(words[i], names[i]))
        if base not in bases:
            bases[base] = len(bases)
            base_words.append(said)
        channel_feature[i] = bases[base]
    features, feature_words = tuple(bases), tuple(base_words)
    if cb.problems.ndim == 3:
        view_names = tuple(f"{n}@{st}" for st, _ in _SEQUENCE_STATS for n in names)
        view_words = tuple(
            _stat_words(n, w, st, said)
            for st, said in _SEQUENCE_STATS
            for n, w in zip(names, words, strict=True)
        )
        feature = np.tile(channel_feature, len(_SEQUENCE_STATS))
        columns = np.arange(len(view_names))
        sequence = True
    else:
        columns = np.array(keep, dtype=np.int64)
        view_names = tuple(names[i] for i in columns)
        view_words = tuple(words[i] for i in columns)
        feature = channel_feature[columns]
        sequence = False
    blank = np.zeros(len(view_names), dtype=bool)
    values = View(view_names, view_words, feature, features, feature_words, sequence, columns,
                  blank, channel_feature).of(cb.problems)  # fmt: skip
    binary = np.all((values == 0.0) | (values == 1.0), axis=0)
    view = View(view_names, view_words, feature, features, feature_words, sequence, columns,
                binary, channel_feature)  # fmt: skip
    cb.cache["view"] = (key, view)
    return view


def _stat_words(name: str, word: str, stat: str, said: str) -> str:
    """Words of one statistic of a channel, as :func:`cbr.problem.summarise` words them."""
    if stat == "mean" or name.startswith((ANGLE_PREFIX, POSITION_PREFIX)):
        return f"{word}{said}"
    return f"{word}{said[:-1]} confidence)"


@dataclass(frozen=True)
class Profiles:
    """Per label (``labels``, sorted) and view column: ``mean``, ``sd``, ``low`` / ``high``
    (the :data:`TYPICAL` percentiles) and ``share`` (binary columns: share of the label's cases
    that show it), each ``(n_labels, m)``; ``count`` ``(n_labels,)``; ``within`` ``(m,)`` the
    pooled within-label standard deviation; ``overall`` ``(m,)`` the standard deviation over
    all cases."""

    labels: tuple[str, ...]
    count: np.ndarray
    mean: np.ndarray
    sd: np.ndarray
    low: np.ndarray
    high: np.ndarray
    within: np.ndarray
    overall: np.ndarray

    def row(self, label: str) -> int:
        return self.labels.index(label)


def profiles_of(cb: CaseBase) -> Profiles:
    """The label profiles of ``cb`` (cached on the case base until its cases change)."""
    hit: Profiles | None = cb.cache.get("profiles")
    if hit is not None:
        return hit
    view = view_of(cb)
    X = view.of(cb.problems)
    labels = cb.labels.astype(str)
    names = tuple(sorted(set(labels.tolist())))
    rows = [X[labels == lab] for lab in names]
    mean = np.stack([r.mean(axis=0) for r in rows])
    sd = np.stack([r.std(axis=0) for r in rows])
    low = np.stack([np.quantile(r, TYPICAL[0], axis=0) for r in rows])
    high = np.stack([np.quantile(r, TYPICAL[1], axis=0) for r in rows])
    count = np.array([len(r) for r in rows], dtype=np.float64)
    resid = sum(((r - m) ** 2).sum(axis=0) for r, m in zip(rows, mean, strict=True))
    within = np.sqrt(np.asarray(resid) / max(len(X) - len(rows), 1))
    out = Profiles(names, count, mean, sd, low, high, within, X.std(axis=0))
    cb.cache["profiles"] = out
    return out
