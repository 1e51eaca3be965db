"""``CaseBaseClassifier``: the CBR cycle behind the scikit-learn estimator contract.

``X`` is a sequence (list or 1-D object array) of :class:`features.poses.PoseSequence`; ``y``
the activity labels. ``__init__`` only stores its parameters; ``fit`` extracts the problems,
builds (and optionally trims) the case base; learned state ends with ``_``. Bad ``X`` or ``y``
(not clips, empty, a missing label, one activity, a clip with no person or shorter than one
movement can be, which ``predict`` refuses too) is refused with
:class:`features.errors.InputError`, the ``ValueError`` scikit-learn users catch.

Learned at fit time from the training clips only (so cross-validation stays honest):

- which fluent states and joint angles describe the clips (available in enough of them);
- the side handling (``mirror``, :mod:`cbr.fitting`): clips as recorded, left-side clips
  described by their mirror image (``"canonical"``), or the mirror image of every training clip
  as a further, penalised case (``"augment"``), so a subject who does a movement with the left
  arm finds the right-arm cases;
- ``feature_weights``: z-normalisation and Fisher-ratio weights of the features
  (:mod:`cbr.weights`), used by the euclidean measure and cited by explanations;
- how far from the cases a held-out clip usually lies and how far outside the cases' feature
  ranges (:mod:`cbr.novelty`), so a clip unlike every stored case is flagged, whatever the
  configuration; and how often a held-out clip's answer was right at each score (its soft
  vote, :mod:`cbr.calibration`), so the confidence is a probability.

With vector problems under euclidean (clip summaries, QMPs), ``"auto"`` chooses the side
handling, the weighting and (clip summaries) the phase means by leave-one-subject-out accuracy
inside the training clips (one-standard-error rule: canonical side, fisher weights and no
phase means unless another choice is better by more than a standard error); a fold of an outer
cross-validation never sees its test clips. Fixed values skip the search.

Every classification, in Python and from the command line, goes through :meth:`solve`; a
fitted classifier is stored with its case base and loaded back whole by :mod:`cbr.stored`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Container, Mapping, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from typing import Any

import numpy as np

from features.body import arms_alone, no_person, torso_share
from features.errors import ConfigError, DataError, InputError, ParameterError
from features.poses import PoseSequence
from features.progress import progress
from features.text import counted, did_you_mean
from features.values import is_number

from .calibration import (
    NEIGHBOURS,
    ConfidenceCalibration,
    HeldOut,
    HoldOut,
    calibrate_soft,
    held_elsewhere,
    held_out_votes,
    held_out_ways,
)
from .casebase import CaseBase, frame_array, skeleton_of
from .described import DescribedClip, check_described, describe_clips
from .estimator_protocol import Classifier, check_fitted, parameters_checked
from .explain import Explanation, explain
from .fitting import (
    AUTO_PHASES,
    MIN_SUBJECTS_TO_JUDGE_WEIGHTS,
    SIDES,
    Cases,
    assemble_cases,
    inner_loso_accuracy,
    inner_loso_neighbours,
    inner_sample,
    side_name,
    subject_folds,
)
from .maintenance import EDITORS, MaintenanceReport
from .novelty import (
    CALIBRATION_SAMPLE,
    DESCRIPTION,
    RANGE_FOLDS,
    UNLIKE_QUANTILE,
    NoveltyCalibration,
    combined_calibration,
    describe,
    fit_activities,
    fit_neighbours,
    from_distances,
    from_problem,
    ranges_and_held,
    same_columns,
    sample,
    summaries,
)
from .problem import (
    STATE_GROUPS,
    FeatureConfig,
    Problem,
    candidate_config,
    check_state_names,
    column_index,
    problem_columns,
    resolve_counts,
)
from .retrieve import Retrieval, retrieve, retrieve_many
from .reuse import WEIGHTINGS as VOTE_WEIGHTINGS
from .reuse import Solution, class_balance, reuse, solutions
from .similarity import SimilarityMeasure, get_measure
from .weights import MIRROR_FLAG, WEIGHTINGS


def as_sequences(X: Any, name: str = "X") -> list[PoseSequence]:
    """``X`` as a list of PoseSequence (a list, tuple, 1-D object array or other ordered
    iterable; not a set or a dict, whose order is not the clips'); anything else is an
    :class:`features.errors.InputError` (the ``ValueError`` scikit-learn users catch) naming
    what was given (``name``: what the caller calls ``X``, as :func:`cbr.training.train`'s
    ``clips``)."""
    if isinstance(X, PoseSequence):
        raise InputError("must be a sequence of PoseSequence, got a single PoseSequence", name)
    if isinstance(X, np.ndarray) and X.dtype != object:
        raise InputError(
            f"must be a sequence of PoseSequence, got a {X.dtype} array of shape {X.shape}",
            name,
        )
    if isinstance(X, str | bytes) or not hasattr(X, "__iter__"):
        raise InputError(f"must be a sequence of PoseSequence, got {type(X).__name__}", name)
    if isinstance(X, AbstractSet | Mapping):  # no order to match the answers or labels to
        kind = "set" if isinstance(X, AbstractSet) else "mapping"
        raise InputError(
            f"must be a sequence of PoseSequence, got a {kind} ({type(X).__name__}):"
            " its order is not the clips' (a list of them keeps it)",
            name,
        )
    if isinstance(X, np.ndarray) and X.ndim != 1:  # flattened, a (2, 3) table was six clips
        raise InputError(
            f"must be a sequence of PoseSequence, got an object array of shape {X.shape}"
            " (one dimension: a clip each)",
            name,
        )
    items = list(X)
    for i, s in enumerate(items):
        if not isinstance(s, PoseSequence):
            raise InputError(f"{name}[{i}] is a {type(s).__name__}, not a PoseSequence", name)
    return items


def _missing(v: Any) -> bool:
    """Whether a label is missing: None, or a value unequal to itself (NaN of any float type,
    NaT) or whose comparison is neither true nor false (pandas' NA), without importing pandas."""
    if v is None:
        return True
    try:
        return bool(v != v)
    except TypeError:  # pd.NA: "boolean value of NA is ambiguous"
        return True
    except ValueError:  # an array: not a label, but not a missing one
        return False


def check_labels(y: Any, n: int, name: str = "y") -> np.ndarray:
    """``y`` as ``(n,)`` labels (str); None, NaN, NaT, pandas' NA and empty labels are refused
    (:class:`features.errors.InputError`; ``name``: what the caller calls ``y``)."""
    y_arr = np.asarray(y, dtype=object)
    if y_arr.ndim == 0:  # a generator, a string, None: no labels to count
        raise InputError(f"must hold one label per clip ({n}), got a {type(y).__name__}", name)
    if y_arr.ndim != 1 or len(y_arr) != n:
        raise InputError(f"{n} clips but {name} has shape {y_arr.shape}", name)
    for i, v in enumerate(y_arr):
        if _missing(v) or str(v).strip() == "":
            raise InputError(f"{name}[{i}] is {v!r}: every clip needs a label", name)
    return np.array([str(v) for v in y_arr], dtype=object)


def _classes(y: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``y`` (:func:`check_labels`) as text labels ``(n,)`` and the classes in the caller's
    type (sorted)."""
    check_labels(y, n)
    # the labels as scikit-learn reads them: in numpy's common type (1 and 2.0 are 1.0 and
    # 2.0), so the cases' text labels are the text of the classes
    values = np.asarray(y)
    try:
        classes = np.unique(values)
    except TypeError:  # objects of kinds that do not sort together: compared as text
        values = values.astype(str)
        classes = np.unique(values)
    return np.array([str(v) for v in values], dtype=object), classes


def check_two_activities(labels: np.ndarray, name: str = "y") -> None:
    """Refuse text ``labels`` (``name``: what the caller calls them) of one activity only:
    a classifier needs two (:class:`features.errors.InputError`)."""
    if len(np.unique(labels)) < 2:
        raise InputError(
            f"the training set has only one activity ({labels[0]!r}); a classifier needs "
            "at least two",
            name,
        )


def _check_someone(names: Sequence[str], nobody: Sequence[int]) -> None:
    """Refuse the training clips at positions ``nobody`` (named ``names``), which show no
    person."""
    if nobody:
        shown = ", ".join(names[i] for i in nobody[:5])
        raise InputError(
            f"{counted(len(nobody), 'training clip')} "
            f"{'shows' if len(nobody) == 1 else 'show'} no person (no frame with a torso): "
            f"{shown}{' ...' if len(nobody) > 5 else ''}",
            "X",
        )


def _stack(values: Sequence[np.ndarray], cols: np.ndarray | None) -> np.ndarray:
    """``(n, ...)`` of the clips' problems, each cut to the columns ``cols`` (last axis; None:
    all), filled row by row: no second copy of the candidate columns."""
    first = values[0] if cols is None else values[0][..., cols]
    out = np.empty((len(values), *first.shape), dtype=np.float64)
    for i, v in enumerate(values):
        out[i] = v if cols is None else v[..., cols]
    return out


def unusable(seqs: Sequence[PoseSequence]) -> list[int]:
    """Positions of the clips in which no frame shows the person's torso: nothing can be
    computed from them (all joints missing, a black video, no person found)."""
    return [i for i, s in enumerate(seqs) if torso_share(s) == 0.0]


def unclassifiable(seqs: Sequence[PoseSequence]) -> list[int]:
    """Positions of the clips :func:`unusable` that show no arms either: a clip with the hips
    out of view (:func:`features.body.arms_alone`) is classified on what it shows, its arms
    and head measured in the frame of its shoulders (:data:`features.signals.HIPLESS`), the
    columns it never shows left out of its distance."""
    return [i for i in unusable(seqs) if not arms_alone(seqs[i])]


def too_short(clip: PoseSequence, what: str = "classify") -> str | None:
    """Why ``clip`` is too short to classify, or to learn from (``what``), None when it is
    not: it lasts less than one movement can (:data:`features.repetitions.MIN_PERIOD_S`); a
    single frame, or a few, show a posture, and a classifier of movements answers it with
    confidence all the same."""
    return _shorter_than_a_movement(clip.duration_s, clip.n_frames, what)


def _shorter_than_a_movement(duration_s: float, frames: int | None, what: str) -> str | None:
    """:func:`too_short`'s words for a clip of ``duration_s`` seconds and ``frames`` frames
    (None: not known, as of a clip described elsewhere)."""
    from features.repetitions import MIN_PERIOD_S

    if duration_s >= MIN_PERIOD_S:
        return None
    counted_frames = "" if frames is None else f" ({counted(frames, 'frame')})"
    return (
        f"lasts {duration_s:.2f} s{counted_frames}, shorter than one movement can be"
        f" ({MIN_PERIOD_S:g} s): nothing to {what}"
    )


@dataclass(frozen=True)
class Solved:
    """One clip through the cycle: its problem, the retrieved cases, the reused solution (its
    ``confidence`` calibrated), how far it lies from the cases (``novelty``: nearest-case
    distance over the case base's usual held-out one) and whether it is unlike the stored
    cases (calibrated per case base; ``unlike_reason`` "distance", "features" or "sensor", see
    :mod:`cbr.novelty`); ``torso_share``: the share of its frames that show the person;
    ``description``: what the flag's feature score judged (its fluent summary ``(F,)``, or its
    problem's values when the case base judges its problems); ``arms_alone``: it shows no
    hip in any frame and was judged on its arms alone (:func:`features.body.arms_alone`)."""

    problem: Problem
    retrieval: Retrieval
    solution: Solution
    novelty: float
    unlike_cases: bool
    torso_share: float
    unlike_reason: str = ""
    description: np.ndarray | None = None
    arms_alone: bool = False


@dataclass(frozen=True)
class _Described:
    """The training clips as problems: ``config`` (resolved), ``R`` ``(n, ...)`` as recorded,
    ``M`` their mirror images (None when no side handling needs them), ``left`` which clips
    move their left side more (None: not needed), ``vectors`` (one vector per clip), ``base``
    the number of columns without phase means (clip summaries), names and words."""

    config: FeatureConfig
    R: np.ndarray
    M: np.ndarray | None
    left: np.ndarray | None
    vectors: bool
    base: int | None
    names: tuple[str, ...]
    words: tuple[str, ...]

    def columns(self, A: np.ndarray | None, phases: int) -> np.ndarray | None:
        """``A`` without the phase-mean columns when ``phases`` is 0."""
        return A if A is None or phases or self.base is None else A[:, : self.base]


@dataclass(frozen=True)
class _Choice:
    side: str
    weighting: str
    phases: int
    scores: dict[str, float]


#: training clips classified held out to calibrate (vector problems: a full scan costs little)
MAX_CALIBRATION_VECTORS = 2000
#: the class weightings of the vote (``class_weight``)
CLASS_WEIGHTS = ("balanced", "none")


def _one_recording_frames(
    clips: Sequence[DescribedClip], cb: CaseBase, sources: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The training clips' and the cases' frame ranges, ``(n_clips, 2)`` and ``(n_cases, 2)``
    (-1 where not known), when every clip is a piece of one named recording, each starting
    at a frame of its own (windows, repetitions, labelled stretches); else None (clips of
    files that share a name all start at frame 0: their frames say nothing of overlap)."""
    named = {str(s) for s in sources.tolist()}
    starts = [c.frames[0] for c in clips]
    if len(named) != 1 or named & {"", "None"} or None in starts:
        return None
    if len(set(starts)) != len(starts):
        return None
    ranges = np.array([c.frames for c in clips], dtype=np.int64)
    return ranges, frame_array(cb.frames)


def _pieces_frames(
    clips: Sequence[DescribedClip], sources: np.ndarray, clip: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The training clips' and the cases' frame ranges, ``(n_clips, 2)`` and ``(n_cases, 2)``
    (``clip`` ``(n_cases,)``: the clip each case is of), each recording moved to frame
    numbers of its own so that a piece overlaps only pieces of its own recording, when every
    clip is a piece of a named recording, each starting at a frame of its own in it, and
    some recording was cut into two pieces or more; else None."""
    names = [str(s) for s in sources.tolist()]
    starts = [c.frames[0] for c in clips]
    if set(names) & {"", "None"} or None in starts:
        return None
    if len(set(zip(names, starts, strict=True))) != len(clips) or len(set(names)) == len(clips):
        return None
    ranges = np.array([c.frames for c in clips], dtype=np.int64)
    index = {name: i for i, name in enumerate(sorted(set(names)))}
    span = int(ranges.max()) + 1
    moved = ranges + (np.array([index[v] for v in names], dtype=np.int64) * span)[:, None]
    return moved, moved[clip]


def _recording_blocks(ranges: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """Each clip's time block ``(n,)`` within its own recording (:func:`_time_blocks` of each
    recording's pieces, frame ranges ``ranges`` ``(n, 2)``): block b of every recording is
    held out together, and every recording keeps its other stretches as cases."""
    out = np.empty(len(ranges), dtype=object)
    names = np.asarray([str(s) for s in sources.tolist()], dtype=object)
    for name in set(names.tolist()):
        mine = np.flatnonzero(names == name)
        out[mine] = _time_blocks(ranges[mine])
    return out


def _time_blocks(ranges: np.ndarray) -> np.ndarray:
    """Each clip's time block ``(n,)``: the clips (pieces of one recording, frame ranges
    ``ranges`` ``(n, 2)``) by start frame, dealt into :data:`~cbr.novelty.RANGE_FOLDS` runs
    of consecutive pieces, so that a fold of the feature ranges holds out a stretch of time,
    not every other window of it."""
    n = len(ranges)
    rank = np.empty(n, dtype=np.int64)
    rank[np.argsort(ranges[:, 0], kind="stable")] = np.arange(n)
    return np.asarray(rank * min(RANGE_FOLDS, n) // max(n, 1), dtype=object)


class CaseBaseClassifier(Classifier):
    """k-nearest-case classifier over qualitative posture features.

    features: ``"fluents"`` or ``"qmp"`` (feature level).
    similarity: a registered measure name (``"euclidean"``, ``"dtw"``, ``"signature"``, ...).
    k: number of retrieved cases.
    weights: ``"distance"`` (1/d vote) or ``"uniform"``.
    class_weight: ``"none"`` (every case votes alike: the classes' counts act as their prior,
      as an activity's share of the recordings is) or ``"balanced"`` (each class's votes
      divided by its share of the cases, :func:`cbr.reuse.class_balance`: a case base of 50
      correct and 10 incorrect repetitions does not answer "correct" by numbers alone; what
      ``posecbr train --target`` and ``compare --target`` use for a column other than the
      activity).
    length: frames a fluent sequence is resampled to.
    states: fluent states (group name or list of machine names), see ``FeatureConfig``.
    similarity_params: parameters of the measure (e.g. ``{"band": 0.1}`` for dtw).
    trim: fraction of each activity's cases kept by novelty/benefit trimming at fit time (None:
      keep all); with another ``editor``, which decides how many cases it keeps, fit refuses it.
    editor: the maintenance editor run at fit time (:mod:`cbr.maintenance`):
      ``"novelty-benefit"`` (keeps ``trim`` of each activity, 0.7 when ``trim`` is None),
      ``"cnn"``, ``"renn"``, ``"icf"``; None: novelty-benefit when ``trim`` is set, else none.
      ``maintenance_`` holds its report.
    angles: add the named joint angles ("left knee angle") to the fluent confidences.
    positions: add the limb joints' positions in the person's own frame at the start of the
      clip ("left wrist height", in torso lengths; :func:`features.body.body_positions`).
    summary: describe a clip by per-feature statistics (mean, lowest, highest, variation)
      instead of its sequence; ``"auto"``: for the euclidean measure at the fluent level.
    mirror: side handling: ``"off"`` (False), ``"augment"`` (True: mirror images of the
      training clips as further cases), ``"canonical"`` (left-side clips mirrored), or
      ``"auto"``: chosen by inner leave-one-subject-out for vector problems under euclidean
      when the training clips name two or more subjects ("off" otherwise).
    feature_weights: ``"fisher"`` (z-normalised, weighted by between/within-activity variance,
      learned in fit), ``"none"`` (raw values), or ``"auto"``: chosen like ``mirror`` when the
      training clips name three or more subjects; fisher with fewer (an inner fold would learn
      the weights from one person) and for clip summaries without subjects; none otherwise.
    phases: with clip summaries, also the mean of every feature over each of this many equal
      stretches of the clip ("left knee angle (middle third)"); ``"auto"``: three or none,
      chosen like ``mirror``.
    velocity: with clip summaries, also the statistics of every feature's rate of change
      ("left knee angle rate of change (highest)"); off by default.
    """

    def __init__(
        self,
        features: str = "fluents",
        similarity: str = "euclidean",
        k: int = 5,
        weights: str = "distance",
        class_weight: str = "none",
        length: int = 32,
        states: str | Sequence[str] = "angles",
        similarity_params: dict[str, Any] | None = None,
        trim: float | None = None,
        angles: bool = True,
        summary: bool | str = "auto",
        mirror: bool | str = "auto",
        feature_weights: str = "auto",
        phases: int | str = "auto",
        positions: bool = True,
        editor: str | None = None,
        velocity: bool = False,
    ) -> None:
        self.features = features
        self.similarity = similarity
        self.k = k
        self.weights = weights
        self.class_weight = class_weight
        self.length = length
        self.states = states
        self.similarity_params = similarity_params
        self.trim = trim
        self.angles = angles
        self.summary = summary
        self.mirror = mirror
        self.feature_weights = feature_weights
        self.phases = phases
        self.positions = positions
        self.editor = editor
        self.velocity = velocity

    # -- parameters

    def _summary(self) -> bool:
        if self.summary == "auto":
            return self.features == "fluents" and self.similarity == "euclidean"
        return bool(self.summary) and self.features == "fluents"

    def _feature_config(self) -> FeatureConfig:
        states = self.states if isinstance(self.states, str) else tuple(self.states)
        fluents = self.features == "fluents"
        return FeatureConfig(
            level=self.features,  # type: ignore[arg-type]
            length=self.length,
            states=states,
            angles=bool(self.angles) and fluents,
            positions=bool(self.positions) and fluents,
            summary=self._summary(),
            velocity=bool(self.velocity) and self._summary(),
            # "auto": computed with the phases, which fit may then drop
            phases=(self._auto_phases() if self.phases == "auto" else int(self.phases))
            if self._summary()
            else 0,
        )

    def _auto_phases(self) -> int:
        """The phases "auto" computes: AUTO_PHASES (tried against none), or none when the
        sequences are shorter than that (a phase is one frame at least)."""
        length = self.length
        if isinstance(length, int | np.integer) and not isinstance(length, bool):
            return AUTO_PHASES if int(length) >= AUTO_PHASES else 0
        return AUTO_PHASES  # not a length: FeatureConfig refuses it

    @parameters_checked
    def _check_vote(self) -> None:
        """Refuse a ``k`` or ``weights`` the vote cannot use: checked by fit, and again by
        every classification (``set_params(k=...)`` after fit, as ``classify -k`` votes)."""
        if isinstance(self.k, bool) or not isinstance(self.k, int | np.integer) or self.k < 1:
            raise ConfigError(f"must be a positive integer, got {self.k!r}", "k")
        if self.weights not in VOTE_WEIGHTINGS:
            raise ConfigError(f"must be 'distance' or 'uniform', got {self.weights!r}", "weights")
        if self.class_weight not in CLASS_WEIGHTS:
            raise ConfigError(
                f"must be 'balanced' or 'none', got {self.class_weight!r}",
                "class_weight",
            )

    def _balance(self, case_labels: np.ndarray, classes: np.ndarray) -> np.ndarray | None:
        """The vote factor of every class of ``classes`` given the voting cases' labels
        (:func:`cbr.reuse.class_balance`), None when ``class_weight`` is "none"."""
        if self.class_weight == "none":
            return None
        return class_balance(case_labels, classes)

    @parameters_checked
    def _check_params(self) -> None:
        self._check_vote()
        self._check_kinds()
        if self.editor is not None and self.editor not in EDITORS:
            raise ConfigError(
                f"must be None or one of {', '.join(EDITORS)}, got {self.editor!r}"
                f"{did_you_mean(str(self.editor), EDITORS)}",
                "editor",
            )
        if not isinstance(self.velocity, bool | np.bool_):
            raise ConfigError(f"must be True or False, got {self.velocity!r}", "velocity")
        if self.summary != "auto" and not isinstance(self.summary, bool | np.bool_):
            raise ConfigError(f"must be True, False or 'auto', got {self.summary!r}", "summary")
        if not isinstance(self.mirror, bool | np.bool_) and self.mirror not in ("auto", *SIDES):
            raise ConfigError(
                f"must be True, False, 'auto', {', '.join(repr(s) for s in SIDES)}; "
                f"got {self.mirror!r}{did_you_mean(str(self.mirror), ('auto', *SIDES))}",
                "mirror",
            )
        if self.phases != "auto" and (
            isinstance(self.phases, bool)
            or not isinstance(self.phases, int | np.integer)
            or int(self.phases) < 0
        ):
            raise ConfigError(
                f"must be 'auto' or a whole number >= 0, got {self.phases!r}", "phases"
            )
        if self.feature_weights not in ("auto", *WEIGHTINGS):
            raise ConfigError(
                f"must be 'auto', 'fisher' or 'none', got {self.feature_weights!r}"
                f"{did_you_mean(str(self.feature_weights), ('auto', *WEIGHTINGS))}",
                "feature_weights",
            )
        states = self.states
        if not isinstance(states, str) and not (
            isinstance(states, Sequence | np.ndarray)
            and not isinstance(states, bytes)
            and all(isinstance(n, str) for n in states)
        ):  # tuple(5) was a TypeError, and b"angles" the states 97, 110, ...
            raise ConfigError(
                f"must be one of {', '.join(STATE_GROUPS)} or a list of state names, got"
                f" {states!r}",
                "states",
            )
        self._feature_config()  # length, states, phases: FeatureConfig's own checks

    @parameters_checked
    def _check_trim_editor(self) -> None:
        """Refuse, at fit, a ``trim`` with an ``editor`` other than novelty-benefit: the share
        kept is novelty-benefit's, the others decide how many cases they keep (it was
        ignored). Not in :meth:`_check_params`: a model stored with both loads as it did."""
        if self.trim is not None and self.editor not in (None, "novelty-benefit"):
            raise ConfigError(
                f"goes with editor='novelty-benefit' (the share of each activity it keeps);"
                f" editor={self.editor!r} decides how many cases it keeps, got trim={self.trim!r}",
                "trim",
            )

    def _check_kinds(self) -> None:
        """Refuse ``trim``, ``angles``, ``positions`` and ``similarity_params`` of the wrong
        kind (``bool("no")`` is true; True is no fraction; ``**"band=0.1"`` a TypeError)."""
        trim = self.trim
        if trim is not None and not (is_number(trim) and 0.0 < float(trim) <= 1.0):
            raise ConfigError(f"must be in (0, 1], got {trim!r}", "trim")
        for name in ("angles", "positions"):
            if not isinstance(getattr(self, name), bool | np.bool_):
                raise ConfigError(f"must be True or False, got {getattr(self, name)!r}", name)
        if self.similarity_params is not None and not isinstance(self.similarity_params, Mapping):
            raise ConfigError(
                "must be None or a dict of the measure's parameters, got "
                f"{self.similarity_params!r}",
                "similarity_params",
            )

    def _measure(self) -> SimilarityMeasure:
        """The measure of ``similarity`` with ``similarity_params``; a parameter it has not,
        or a value it refuses, is an error of ``similarity_params`` (it named ``similarity``
        or "similarity dtw": the parameter the user gave goes unnamed)."""
        try:
            return get_measure(self.similarity, **(self.similarity_params or {}))
        except ConfigError as exc:
            if not self.similarity_params or exc.message.startswith("unknown similarity"):
                raise
            raise ConfigError(exc.message, "similarity_params") from None

    @staticmethod
    def _selectable(vectors: bool, measure: SimilarityMeasure) -> bool:
        """Whether the side handling and weighting can be chosen by inner cross-validation:
        vector problems under a measure that takes learned weights (euclidean)."""
        return vectors and hasattr(measure, "multiplier")

    def wanted_config(self) -> FeatureConfig:
        """The feature configuration these parameters ask for, before fit resolves it."""
        self._check_params()
        return self._feature_config()

    def _candidates(self, vectors: bool, measure: SimilarityMeasure) -> tuple[list[str], list[str]]:
        """The side handlings and weightings fit chooses between."""
        selectable = self._selectable(vectors, measure)
        if self.mirror == "auto":
            sides = list(SIDES) if selectable else ["off"]
        else:
            sides = [side_name(self.mirror)]
        if self.feature_weights == "auto":
            weightings = ["none", "fisher"] if selectable else ["none"]
        else:
            weightings = [str(self.feature_weights)]
        if "augment" in sides and not vectors:
            sides = ["augment"]  # sequence problems: plain augmentation, nothing to choose
        return sides, weightings

    # -- fit, step by step

    @parameters_checked
    def describe_plan(self) -> tuple[FeatureConfig, bool, bool]:
        """How :meth:`fit` describes each training clip (:func:`cbr.described.describe_clip`):
        the candidate columns, whether the mirror images are needed, whether the favoured
        side is. Refuses parameters that cannot work together before any clip is read."""
        self._check_params()
        self._check_trim_editor()
        if not isinstance(self.states, str):
            check_state_names(self.states)
        measure = self._measure()
        vectors = self.features == "qmp" or self._summary()
        if self.feature_weights not in ("auto", "none") and not self._selectable(vectors, measure):
            raise ConfigError(
                "learned feature weights need vector problems and a measure that takes them "
                "(summary=True or QMP features, with similarity='euclidean')",
                "feature_weights",
            )
        sides, _ = self._candidates(vectors, measure)
        mirror = "augment" in sides or "canonical" in sides
        return candidate_config(self._feature_config()), mirror, "canonical" in sides

    def fit(self, X: Any, y: Any) -> CaseBaseClassifier:
        """Build the case base from clips ``X`` and labels ``y``.

        With ``mirror="auto"`` / ``feature_weights="auto"`` on vector problems, the side
        handling and the weighting are chosen by leave-one-subject-out cross-validation inside
        the training clips (``selection_`` holds the scores); the test clips of an outer
        cross-validation never take part. Each clip is reduced to what the fit needs of it as
        it is read (:mod:`cbr.described`): memory grows by kilobytes per clip. Bad labels
        (:func:`check_labels`, one activity only), a clip that shows no person and one
        :meth:`solve` would refuse as too short (:func:`too_short`) are refused (an
        :class:`~features.errors.InputError` naming ``y`` or the clip) before any clip is
        described: no case is made of what could not be classified (``cbr.training.train``
        skips such a clip, naming it, as ``posecbr train`` does).
        """
        candidates, mirror, sides = self.describe_plan()
        seqs = as_sequences(X)
        if len(seqs) == 0:
            raise InputError("the training set is empty", "X")
        # what the labels and the poses alone tell, refused before any clip is described
        # (fit_described checks it again, of clips described elsewhere), in its order there
        labels, _ = _classes(y, len(seqs))
        _check_someone([s.source or f"X[{i}]" for i, s in enumerate(seqs)], unusable(seqs))
        for i, seq in enumerate(seqs):  # as solve refuses it
            why = too_short(seq, "learn from")
            if why is not None:
                raise InputError(why, seq.source or f"X[{i}]")
        check_two_activities(labels)
        clips = progress(seqs, desc="features", total=len(seqs), unit="clip")
        return self.fit_described(list(describe_clips(clips, candidates, mirror, sides)), y)

    def fit_described(self, clips: Sequence[DescribedClip], y: Any) -> CaseBaseClassifier:
        """:meth:`fit` on clips already described by :func:`cbr.described.describe_clip` with
        :meth:`describe_plan` (in this process or on a cluster's workers): the same model.
        Records described for another plan are refused (:func:`cbr.described.check_described`)."""
        check_described(clips, *self.describe_plan())
        labels, classes = self._check_training_set(clips, y)
        measure = self._measure()
        subjects = np.array([c.subject or "" for c in clips], dtype=object)
        described = self._describe(clips)
        choice = self._choose(described, labels, subjects, measure)
        config = described.config
        if choice.side == "canonical":
            config = dataclasses.replace(config, side="canonical")
        if choice.phases != config.phases:
            config = dataclasses.replace(config, phases=choice.phases)
        R = described.columns(described.R, choice.phases)
        M = described.columns(described.M, choice.phases)
        assert R is not None
        cases = assemble_cases(
            R, M, described.left, labels, choice.side, choice.weighting, described.vectors
        )
        measure = self._weighted(measure, cases)
        cb = self._case_base(clips, described, config, measure, cases, choice.side)
        origin = cases.origin
        self.maintenance_ = self._edit(cb)
        if self.maintenance_ is not None:
            cb, origin = self.maintenance_.casebase, origin[self.maintenance_.kept]
        sources = np.array([c.source or f"clip {i}" for i, c in enumerate(clips)], dtype=object)
        self.novelty_, self.confidence_ = self._calibrate(
            clips, cb, cases, origin, subjects, sources
        )
        nested = self._nested_votes(described, choice, labels, subjects, measure)
        if nested is not None:
            inner = calibrate_soft(nested, len(classes), "nested leave-one-subject-out")
            if inner.n:  # else no subject's activity was another's too: as calibrated above
                self.confidence_ = inner
        self.classes_ = classes
        self.case_origin_ = origin
        self.feature_config_ = config
        self.measure_ = measure
        self.case_base_ = cb
        # the unknown judges calibrated on cb (cbr.unknown): filled when the model is stored
        # (cbr.stored); until then judge_of calibrates them on demand
        self.judges_: dict[str, Any] = {}
        # the column the labels come from: unknown when fitted here (the labels' own words);
        # a loaded model's is the one it was stored with (cbr.stored), e.g. "correct"
        self.target_: str | None = None
        self.feature_names_ = cb.names
        self.feature_weights_ = cases.weights
        self.side_ = choice.side
        self.weighting_ = choice.weighting
        self.phases_ = int(config.phases)
        self.mirror_ = choice.side == "augment"
        self.mirror_flag_ = cases.flag
        self.mirror_cases_ = int((cases.origin >= len(clips)).sum())
        self.selection_ = choice.scores
        return self

    @staticmethod
    def _check_training_set(
        clips: Sequence[DescribedClip], y: Any
    ) -> tuple[np.ndarray, np.ndarray]:
        """The labels as text ``(n,)`` and the classes in the caller's type (sorted)."""
        if len(clips) == 0:
            raise InputError("the training set is empty", "X")
        labels, classes = _classes(y, len(clips))
        _check_someone(
            [c.source or f"X[{i}]" for i, c in enumerate(clips)],
            [i for i, c in enumerate(clips) if c.torso_share == 0.0],
        )
        for i, c in enumerate(clips):  # a case of it would answer what solve refuses to ask
            why = _shorter_than_a_movement(c.duration_s, None, "learn from")
            if why is not None:
                raise InputError(why, c.source or f"X[{i}]")
        check_two_activities(labels)
        return labels, classes

    def _describe(self, clips: Sequence[DescribedClip]) -> _Described:
        """The training clips' problems under the configuration their columns resolve to (and
        their mirror images', when described)."""
        wanted = self._feature_config()
        candidates = candidate_config(wanted)
        if wanted.resolved:
            config, cols = wanted, None
        else:
            counts = np.zeros(len(candidates.states), dtype=np.int64)
            for c in clips:
                counts += c.available
            config = resolve_counts(wanted, counts, len(clips))
            cols = column_index(config, candidates)
        R = _stack([c.values for c in clips], cols)
        vectors = R.ndim == 2
        has_mirror = clips[0].mirror is not None
        M = _stack([c.mirror for c in clips], cols) if has_mirror else None  # type: ignore[misc]
        left = None if clips[0].left is None else np.array([bool(c.left) for c in clips])
        if config.level == "qmp":
            names, words = clips[0].names or (), clips[0].words or ()
        else:
            names, words = problem_columns(config)
        # phase columns come last: without them, the problem is the first `base` columns
        base = R.shape[1] - len(config.states) * int(config.phases) if config.summary else None
        return _Described(config, R, M, left, vectors, base, names, words)

    def _choose(
        self,
        d: _Described,
        labels: np.ndarray,
        subjects: np.ndarray,
        measure: SimilarityMeasure,
    ) -> _Choice:
        """The side handling, weighting and phase means, by inner leave-one-subject-out
        accuracy with the one-standard-error rule (fixed parameters: no search)."""
        sides, weightings = self._candidates(d.vectors, measure)
        phase_options = [int(d.config.phases)]
        if self.phases == "auto" and d.config.phases and self._selectable(d.vectors, measure):
            phase_options = [0, int(d.config.phases)]
        n_subjects = len(set(subjects.tolist()) - {""})
        if len(weightings) > 1 and n_subjects < MIN_SUBJECTS_TO_JUDGE_WEIGHTS:
            # an inner fold would learn the weights from one subject, whose within-activity
            # spread leaves out how people differ: the judgement would be biased against them
            weightings = ["fisher"]
        if len(sides) * len(weightings) * len(phase_options) == 1:
            return _Choice(sides[0], weightings[0], phase_options[-1], {})
        if n_subjects < 2 or "" in set(subjects.tolist()):  # no subjects to hold out
            weighting = "fisher" if "fisher" in weightings and self._summary() else "none"
            side = sides[0] if len(sides) == 1 else "off"  # a side asked for is kept
            return _Choice(side, weighting, phase_options[-1], {})
        # a capped, stratified sample: the inner scores cost the square of the clips
        R, M, left = d.R, d.M, d.left
        pick = inner_sample(labels, subjects)
        if len(pick) < len(labels):
            R, M = R[pick], None if M is None else M[pick]
            left = None if left is None else left[pick]
            labels, subjects = labels[pick], subjects[pick]
        scores = {
            (sd, wt, ph): inner_loso_accuracy(
                d.columns(R, ph),  # type: ignore[arg-type]
                d.columns(M, ph),
                left,
                labels,
                subjects,
                sd,
                wt,
                int(self.k),
                self.weights,  # type: ignore[arg-type]
            )
            for ph in phase_options
            for sd in sides
            for wt in weightings
        }
        best = max(scores, key=lambda c: scores[c])  # first best wins
        # one-standard-error rule: the plain choice (the side-invariant handling, the learned
        # weights, no phase means) stays unless another beats it by more than the standard
        # error of the best inner accuracy; inner scores are noisy, and chasing their small
        # differences lost accuracy on held-out subjects
        plain = (sides[0], "fisher" if "fisher" in weightings else weightings[0], phase_options[0])
        se = float(np.sqrt(scores[best] * (1.0 - scores[best]) / len(labels)))
        if scores[best] - scores[plain] <= se:
            best = plain
        named = {f"{sd}/{wt}/{ph} phases": a for (sd, wt, ph), a in scores.items()}
        return _Choice(best[0], best[1], best[2], named)

    @staticmethod
    def _weighted(measure: SimilarityMeasure, cases: Cases) -> SimilarityMeasure:
        """The measure with the learned feature weights in it (when any were learned)."""
        if cases.weights is None:
            return measure
        return get_measure(
            measure,
            centre=tuple(float(v) for v in cases.weights.centre),
            multiplier=tuple(float(v) for v in cases.weights.multiplier()),
        )

    @staticmethod
    def _case_base(
        clips: Sequence[DescribedClip],
        d: _Described,
        config: FeatureConfig,
        measure: SimilarityMeasure,
        cases: Cases,
        side: str,
    ) -> CaseBase:
        """The case base of ``cases``, with each case's clip as provenance."""
        n = len(clips)
        origin = cases.origin.tolist()
        # a case is the clip's mirror image when it is an augmenting image (origin >= n) or,
        # under the canonical side, the clip of one that moves its left side more
        image = [
            i >= n or (side == "canonical" and d.left is not None and bool(d.left[i % n]))
            for i in origin
        ]
        width = cases.values.shape[-1] - int(cases.flag)
        names, words = d.names[:width], d.words[:width]
        if cases.flag:
            names, words = (*names, MIRROR_FLAG), (*words, "mirror image of a training clip")
        of = [clips[i % n] for i in origin]
        return CaseBase(
            config,
            measure,
            cases.values,
            cases.labels,
            names,
            words,
            sources=tuple(c.mirror_source if m else c.source for c, m in zip(of, image,
                                                                              strict=True)),
            subjects=tuple(c.subject for c in of),
            frames=tuple(c.frames for c in of),
            skeletons=tuple(c.skeleton for c in of),
            poses=tuple(c.poses for c in of),
        )  # fmt: skip

    def _calibrate(
        self,
        clips: Sequence[DescribedClip],
        cb: CaseBase,
        cases: Cases,
        origin: np.ndarray,
        subjects: np.ndarray,
        sources: np.ndarray,
    ) -> tuple[NoveltyCalibration, ConfidenceCalibration]:
        """The training clips classified held out as a new clip will be: by subject when the
        clips name two or more subjects; else by source recording when there are two or more
        (the repetitions cut from one recording are near copies of each other, not what a new
        recording is); else by clip (a clip's mirror image goes with it). From them, how far
        from the cases a held-out clip usually lies and how far outside the cases' summary
        feature ranges (the "unlike the stored cases" flag) and how often the answer was right
        at each soft vote (the confidence)."""
        n = len(subjects)
        real = cases.origin < n
        queries = cases.values[real]  # the training clips as queries see them
        labels = cases.labels[real]
        clip = origin % n
        named = "" not in set(subjects.tolist()) and len(set(subjects.tolist())) >= 2
        # by subject when some subject's activity is another's too: held out by subject, a
        # clip of an activity one subject alone did cannot be answered right, and if that is
        # every clip, the subjects cannot say how often an answer is right
        if named and held_elsewhere(labels, subjects[cases.origin[real]], cb.labels,
                                    subjects[clip]).any():  # fmt: skip
            groups, case_groups, basis = subjects, subjects[clip], "leave-one-subject-out"
        elif len(set(sources.tolist())) >= 2:
            groups, case_groups, basis = sources, sources[clip], "leave-one-recording-out"
        else:
            groups, case_groups, basis = np.arange(n), clip, "leave-one-out"
        # pieces cut from one recording (windows, repetitions, labelled stretches): held out
        # with the pieces whose frames overlap theirs, and in time blocks where folds are
        # dealt (the windows of one stretch, 0.5 s apart, are near copies of each other)
        frames = _one_recording_frames(clips, cb, sources) if basis == "leave-one-out" else None
        if frames is not None:
            basis = "leave-overlapping-out"
        query_clip = cases.origin[real]
        # a full scan per clip: every clip of vector problems, a sample of sequences
        size = MAX_CALIBRATION_VECTORS if queries.ndim == 2 else CALIBRATION_SAMPLE
        pick = sample(len(queries), size)
        ways = [
            HoldOut(
                np.asarray(groups, dtype=object)[pick],
                np.asarray(case_groups, dtype=object),
                None if frames is None else (frames[0][query_clip][pick], frames[1]),
            )
        ]
        # every recording the only one of its activities: held out by recording, each clip is
        # of an activity the case base then lacks, and the flag's threshold would be set by
        # how unlike the activities are (nothing a new clip of an unseen exercise exceeds);
        # the pieces of one recording that do not overlap in time stand in, for the flag alone
        # (the confidence stays the vote share: near copies of one take answer every piece),
        # held out in the same scan
        alone = basis == "leave-one-recording-out" and not held_elsewhere(
            labels, sources[query_clip], cb.labels, sources[clip]).any()  # fmt: skip
        pieces = _pieces_frames(clips, sources, clip) if alone else None
        if pieces is not None:
            ways.append(HoldOut(np.arange(n, dtype=object)[query_clip][pick],
                                np.asarray(clip, dtype=object),
                                (pieces[0][query_clip][pick], pieces[1])))  # fmt: skip
        h, *piece = held_out_ways(
            cb,
            queries[pick],
            labels[pick],
            ways,
            int(self.k),
            self.weights,  # type: ignore[arg-type]
            balanced=self.class_weight == "balanced",
        )
        flag_nearest, flag_pick = h.nearest, pick
        if piece:
            (piece_h,) = piece
            # a piece whose every other case of its activity overlaps it in time has none to
            # stand in: its nearest case is another activity's, no distance of a known one
            own = piece_h.truth >= 0
            keep = own if own.any() else np.ones(len(own), dtype=bool)
            flag_nearest, flag_pick = piece_h.nearest[keep], pick[keep]
        skeletons = tuple(sorted({c.skeleton for c in clips}))
        # every training clip's summary against the feature ranges and the nearest clip of
        # the others (cheap: no scan of the measure), then one statistic of the three and the
        # distance, calibrated on the clips whose distance was measured
        group_of = np.asarray(groups, dtype=object)
        if frames is not None:
            group_of = _time_blocks(frames[0])
        elif pieces is not None:
            group_of = _recording_blocks(pieces[0], sources)
        clip_labels = np.empty(n, dtype=object)
        clip_labels[query_clip] = labels
        cases_d, case_clip, image, queries_d, config = self._summaries(
            clips, cb, origin, queries, query_clip
        )
        ranges = ranges_and_held(cases_d, group_of[case_clip], queries_d,
                                 group_of[query_clip], labels, description=config)  # fmt: skip
        plain = case_clip[~image]  # the summary neighbours: the clips kept, no mirror image
        near = None if ranges is None else fit_neighbours(
            cases_d[~image], group_of[plain], clip_labels[plain], queries_d, group_of[query_clip]
        )  # fmt: skip
        spread = None if ranges is None else fit_activities(
            cases_d[~image], group_of[plain], clip_labels[plain], queries_d, group_of[query_clip]
        )  # fmt: skip
        flag_basis = basis if pieces is None else "leave-overlapping-out"
        novelty = from_distances(flag_nearest, flag_basis, UNLIKE_QUANTILE, skeletons)
        if ranges is not None and near is not None:
            (found, outside), (neighbours, neighbour, near_labels) = ranges, near
            novelty = combined_calibration(novelty, flag_nearest, found, outside, neighbours,
                                           neighbour, near_labels, flag_pick,
                                           activities=spread)  # fmt: skip
        elif ranges is not None:
            novelty = dataclasses.replace(novelty, features=ranges[0])
        return (
            novelty,
            calibrate_soft(h, len(np.unique(cb.labels.astype(str))), basis),
        )

    def _summaries(
        self,
        clips: Sequence[DescribedClip],
        cb: CaseBase,
        origin: np.ndarray,
        queries: np.ndarray,
        query_clip: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, FeatureConfig | None]:
        """What the flag's feature scores judge: the cases' summaries ``(m, F)``, the clip
        each case is of ``(m,)`` and whether it is an augmenting mirror image ``(m,)``; the
        training clips' as queries ``(n, F)`` (the clips ``query_clip`` ``(n,)``, in the order
        of their problems ``queries``); and the description they were computed with (None:
        the problems' own summaries)."""
        n, wanted = len(clips), self._feature_config()
        if clips[0].summary is not None:
            D, config = CaseBaseClassifier._description_summaries(clips)
        elif same_columns(wanted):  # the description, from the problems as recorded
            D, config = CaseBaseClassifier._own_descriptions(clips, wanted)
        else:  # other columns than the description's: the problems' own summaries
            return summaries(cb.problems), origin % n, origin >= n, summaries(queries), None
        kept = origin[origin < n]  # mirror images left out: the clips' own description
        return D[kept], kept, np.zeros(len(kept), dtype=bool), D[query_clip], config

    @staticmethod
    def _own_descriptions(
        clips: Sequence[DescribedClip], config: FeatureConfig
    ) -> tuple[np.ndarray, FeatureConfig]:
        """The clips' fluent summaries ``(n, F)`` from their problems as recorded (a
        :func:`cbr.novelty.same_columns` configuration ``config``: the candidate columns of
        :data:`cbr.novelty.DESCRIPTION`), with the description resolved as :meth:`_describe`
        resolves the problem's columns."""
        candidates = candidate_config(DESCRIPTION)
        counts = np.zeros(len(candidates.states), dtype=np.int64)
        for c in clips:
            counts += c.available
        described = resolve_counts(DESCRIPTION, counts, len(clips))
        wide = candidate_config(config)  # the columns each clip's problem was described over
        D = np.stack([from_problem(c.values, wide, described) for c in clips])
        return D, described

    @staticmethod
    def _description_summaries(
        clips: Sequence[DescribedClip],
    ) -> tuple[np.ndarray, FeatureConfig]:
        """The clips' fluent summaries ``(n, F)`` (:data:`cbr.novelty.DESCRIPTION`, its
        columns those enough training clips have) and that resolved description."""
        candidates = candidate_config(DESCRIPTION)
        counts = np.zeros(len(candidates.states), dtype=np.int64)
        for c in clips:
            assert c.summary_available is not None
            counts += c.summary_available
        config = resolve_counts(DESCRIPTION, counts, len(clips))
        D = _stack([c.summary for c in clips], column_index(config, candidates))  # type: ignore[misc]
        return D, config

    def _nested_votes(
        self,
        d: _Described,
        choice: _Choice,
        labels: np.ndarray,
        subjects: np.ndarray,
        measure: SimilarityMeasure,
    ) -> HeldOut | None:
        """The training clips, each classified by a case base whose weights were learned
        without its subject (None: no learned weights, or no subjects to hold out). Weights
        learned with a clip's own subject make its held-out votes look surer than a new
        person's will be: the confidence would promise too much."""
        named = set(subjects.tolist())
        if not self._selectable(d.vectors, measure) or "" in named or len(named) < 2:
            return None
        if choice.weighting == "none":
            return None
        # the same capped sample as the inner selection: the votes cost the square of the clips
        pick = inner_sample(labels, subjects)
        R = d.columns(d.R[pick], choice.phases)
        M = None if d.M is None else d.columns(d.M[pick], choice.phases)
        left = None if d.left is None else d.left[pick]
        assert R is not None
        k = int(self.k)
        dist, codes, classes = inner_loso_neighbours(
            R, M, left, labels[pick], subjects[pick], choice.side, choice.weighting,
            max(k, NEIGHBOURS),
        )  # fmt: skip
        ok = np.isfinite(dist[:, 0])
        if not ok.any():
            return None
        folds = subject_folds(subjects[pick])  # the inner folds: whose cases answered whom
        return held_out_votes(
            dist[ok],
            codes[ok],
            classes,
            labels[pick][ok],
            k,
            self.weights,  # type: ignore[arg-type]
            held_elsewhere(labels[pick][ok], folds[ok], labels[pick], folds),
            self._balance(labels[pick], classes),
        )

    def _edit(self, cb: CaseBase) -> MaintenanceReport | None:
        """Run the maintenance editor these parameters ask for (None: no editing)."""
        trims = self.trim is not None and float(self.trim) < 1.0
        editor = self.editor or ("novelty-benefit" if trims else None)
        if editor is None:
            return None
        if editor == "novelty-benefit":
            keep = 0.7 if self.trim is None else float(self.trim)
            return EDITORS[editor](cb, keep, int(self.k), self.weights)
        return EDITORS[editor](cb, weights=self.weights)

    # -- the cycle

    def problems(self, X: Any) -> list[Problem]:
        """The problem of every clip in ``X`` under the fitted configuration."""
        check_fitted(self, "case_base_")
        return [self.case_base_.problem_of(s) for s in as_sequences(X)]

    def _class_labels(self) -> np.ndarray:
        return np.array([str(c) for c in self.classes_], dtype=object)

    def solve(self, X: Any, flag: bool = True) -> list[Solved]:
        """Every clip of ``X`` through retrieve and reuse: problem, retrieved cases, solution
        and how unlike the stored cases it is. A clip that shows no person, or lasts less
        than one movement can (:func:`too_short`: one frame, or a few), is refused
        (:class:`features.errors.InputError`, a ``DataError`` and ``ValueError``, naming it):
        nothing can be said about it, as ``classify`` calls it unclassifiable.

        ``flag`` False: the "unlike the stored cases" flag is not judged (``unlike_cases``
        False, no reason, no description), for callers with a judge of their own (segmenting
        a recording judges its stretches by :mod:`cbr.unknown`) that would pay for it unused;
        not True or False, an InputError naming it ("no" was taken as True)."""
        check_fitted(self, "case_base_")
        if not isinstance(flag, bool | np.bool_):
            raise InputError(f"must be True or False, got {flag!r}", "flag")
        self._check_vote()
        self.case_base_.check_not_empty("case_base_")
        seqs = as_sequences(X)
        if not seqs:
            raise InputError("no clips to classify", "X")
        bad = unclassifiable(seqs)
        if bad:
            seq = seqs[bad[0]]
            raise InputError(f"{no_person(seq)}: nothing to classify", seq.source or f"X[{bad[0]}]")
        for i, seq in enumerate(seqs):  # as the commands call it unclassifiable
            why = too_short(seq)
            if why is not None:
                raise InputError(why, seq.source or f"X[{i}]")
        labels = self._class_labels()
        out = []
        problems = [self.case_base_.problem_of(seq) for seq in seqs]
        # every clip's neighbours in one batched search (the same as one retrieve per clip)
        # and the wider neighbourhood the confidence's soft vote reads (the first k of it are
        # the k nearest: neighbours are ordered, ties to the lower case)
        k = int(self.k)
        wide = max(k, self.confidence_.neighbours)
        code = {str(c): i for i, c in enumerate(labels)}
        retrieved = retrieve_many(self.case_base_, problems, wide)
        self._check_known(np.concatenate([w.labels for w in retrieved]), code)
        # every clip's vote and confidence score in one pass over the rows (row by row alike)
        distances = np.stack([w.distances for w in retrieved])
        codes = np.array([[code[str(lab)] for lab in w.labels] for w in retrieved],
                         dtype=np.int64).reshape(distances.shape)  # fmt: skip
        balance = self._balance(self.case_base_.labels, labels)
        voted = solutions(distances[:, :k], codes[:, :k], labels, self.weights, balance)  # type: ignore[arg-type]
        scores = self.confidence_.scores(
            distances, codes, len(labels), [code[s.label] for s in voted],
            [s.vote_share for s in voted],
        )  # fmt: skip
        for seq, p, w, s, score in zip(seqs, problems, retrieved, voted, scores, strict=True):
            r = Retrieval(w.indices[:k], w.distances[:k], w.labels[:k], w.case_ids[:k])
            s = dataclasses.replace(s, confidence=self.confidence_(score))
            nearest = float(r.distances[0]) if len(r.distances) else float("inf")
            seen = self._description(seq, p) if flag else None
            reason = self.novelty_.reason(nearest, skeleton_of(seq), seen, s.label) if flag else ""
            ratio = self.novelty_.ratio(nearest)
            share = torso_share(seq)
            alone = share == 0.0 and arms_alone(seq)
            out.append(Solved(p, r, s, ratio, bool(reason), share, reason, seen, alone))
        return out

    def _description(self, seq: PoseSequence, p: Problem) -> np.ndarray:
        """What the feature score of the flag judges of ``seq``: its fluent summary
        (:data:`cbr.novelty.DESCRIPTION`) when the calibration has one, else its problem."""
        config = self.novelty_.description
        return p.values if config is None else describe(seq, config)

    def predict_proba(self, X: Any) -> np.ndarray:
        """``(n_clips, n_classes)`` vote shares, columns in ``classes_`` order (the calibrated
        probability of the winner is ``solve(X)[i].solution.confidence``)."""
        return np.stack([s.solution.proba for s in self.solve(X)])

    def predict(self, X: Any) -> np.ndarray:
        """``(n_clips,)`` predicted labels (values of ``classes_``)."""
        proba = self.predict_proba(X)
        return np.asarray(self.classes_[np.argmax(proba, axis=1)])

    def explain(self, X: Any, target: str | None = None) -> list[Explanation]:
        """An explanation in words for every clip in ``X`` (``target``: the column the labels
        come from: ``"label"``, the activity; ``"correct"`` reads them as correct / incorrect
        repetitions; None: the column the classifier was trained to predict, ``target_``, the
        only other column taken). Another ``target`` is refused with a ParameterError."""
        self._check_target(target)
        return [self.explain_solved(s, target) for s in self.solve(X)]

    def explain_solved(
        self, solved: Solved, target: str | None = None, counterfactual: bool = True
    ) -> Explanation:
        """The explanation of one :meth:`solve` result (``counterfactual`` False: without the
        counterfactual search, for callers that need the neighbours only; ``target`` as
        :meth:`explain`'s)."""
        self._check_target(target)
        if target is None:  # a model pickled before target_ was kept has none
            target = getattr(self, "target_", None)
        return explain(
            self.case_base_,
            solved,
            self.answer,
            target=target,
            unlike_ratio=self.novelty_.unlike_ratio,
            k=int(self.k),
            weights=self.weights,  # type: ignore[arg-type]
            balanced=self.class_weight == "balanced",
            counterfactual_search=counterfactual,
            confidence=self.confidence_.words,
            calibrated=self.confidence_.calibrated,
        )

    def _check_target(self, target: Any) -> None:
        """Refuse an ``explain`` target other than None, "label", "correct" and the column
        the classifier was trained to predict (``target_``): any other (a mistyped "corect")
        was taken without a word, explained as activities. ParameterError naming ``target``."""
        own = getattr(self, "target_", None)
        allowed = list(dict.fromkeys(["label", "correct", *([] if own is None else [own])]))
        if target is None or (isinstance(target, str) and target in allowed):
            return
        guess = did_you_mean(target, allowed) if isinstance(target, str) else ""
        whose = "target_: the column the classifier was trained to predict"
        said = (
            f"'label', 'correct' or None ({whose})"
            if len(allowed) == 2
            else f"'label', 'correct', {own!r} ({whose}) or None"
        )
        raise ParameterError(f"must be {said}, got {target!r}{guess}", "target")

    def answer(self, values: np.ndarray | Problem) -> str:
        """The label the classifier gives a problem ``values`` (retrieve and reuse, as
        :meth:`solve` does; a :class:`Problem`'s fills of features its clip never showed left
        out of the distances, as there): how counterfactuals are checked."""
        check_fitted(self, "case_base_")
        self._check_vote()
        self.case_base_.check_not_empty("case_base_")
        query = values if isinstance(values, Problem) else np.asarray(values)
        r = retrieve(self.case_base_, query, int(self.k))
        classes = self._class_labels()
        self._check_known(r.labels, set(classes.tolist()))
        balance = self._balance(self.case_base_.labels, classes)
        return reuse(r, classes, self.weights, balance).label  # type: ignore[arg-type]

    def refresh(self) -> None:
        """Follow changes to ``case_base_`` (revised or retained cases): the classes are the
        labels the cases have now. While every one of them is a class already, the classes
        keep their type and order (labels fitted as numbers stay numbers); a label new to the
        classifier (retained with feedback: text) makes them the cases' labels as text."""
        now = set(np.unique(self.case_base_.labels.astype(str)).tolist())
        old = getattr(self, "classes_", None)
        if old is not None and now <= {str(c) for c in old}:
            self.classes_ = np.asarray(old)[[str(c) in now for c in old]]
        else:
            self.classes_ = np.array(sorted(now))

    def _check_known(self, found: np.ndarray, known: Container[str]) -> None:
        """Refuse cases whose labels are not among the classes (cases retained or relabelled
        in ``case_base_`` without :meth:`refresh`): their votes would have no class."""
        unknown = sorted(v for v in {str(x) for x in found.tolist()} if v not in known)
        if unknown:
            raise DataError(
                f"the case base holds {counted(len(unknown), 'label')} not among classes_ "
                f"({', '.join(repr(u) for u in unknown)}): call refresh() after retaining or "
                "revising cases",
                "case_base_",
            )

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.input_tags.two_d_array = False
        tags.non_deterministic = False
        return tags


__all__ = [
    "CaseBaseClassifier",
    "NoveltyCalibration",
    "Solved",
    "as_sequences",
    "check_labels",
    "check_two_activities",
    "too_short",
    "unusable",
]
