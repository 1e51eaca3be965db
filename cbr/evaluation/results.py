"""The results of a comparison as typed records: ``to_dict()`` gives the JSON that
``compare --json/--out`` writes, ``from_dict()`` reads it back, checking every key and type.

A results file is input to ``posecbr report``; the reader trusts nothing in it: a missing key
or a value of the wrong type is one :class:`~features.errors.DataError` naming the file and the
key (``methods[2].accuracy``), and a picture must be a file name inside the results folder.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import PurePosixPath, PureWindowsPath
from typing import Any, NoReturn, TypeVar

import numpy as np

from features.errors import DataError

KIND = "posecbr-compare"
T = TypeVar("T")


# ---------------------------------------------------------------------------- reading JSON


def _describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true/false"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, str):
        return "a string"
    return "a list" if isinstance(value, list) else "an object"


_KINDS: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "str": ("a string", lambda v: isinstance(v, str)),
    "num": ("a number", lambda v: isinstance(v, int | float) and not isinstance(v, bool)),
    "int": ("a whole number", lambda v: isinstance(v, int) and not isinstance(v, bool)),
    "bool": ("true or false", lambda v: isinstance(v, bool)),
    "list": ("a list", lambda v: isinstance(v, list)),
    "dict": ("an object", lambda v: isinstance(v, dict)),
}


class Reader:
    """Typed access to a JSON document; every problem is one DataError naming ``source`` and
    the key path."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, where: str, problem: str) -> NoReturn:
        raise DataError(f"key '{where}' {problem}", self.source)

    def value(self, v: Any, where: str, kind: str, optional: bool = False) -> Any:
        """``v`` checked to be of ``kind`` (``str``, ``num``, ``int``, ``bool``, ``list``,
        ``dict``), or None when ``optional``."""
        if v is None and optional:
            return None
        name, ok = _KINDS[kind]
        if not ok(v):
            self.fail(where, f"must be {name}{' or null' if optional else ''}, got {_describe(v)}")
        if kind != "num":
            return v
        try:
            return float(v)
        except OverflowError:  # a whole number past any float (JSON allows 4300 digits)
            self.fail(where, f"is too large a number ({len(str(abs(v)))} digits)")

    def get(
        self, obj: dict[str, Any], key: str, where: str, kind: str, optional: bool = False
    ) -> Any:
        """``obj[key]`` checked to be of ``kind``; a missing key is an error unless
        ``optional`` (then None)."""
        path = f"{where}.{key}" if where else key
        if key not in obj:
            if optional:
                return None
            raise DataError(f"missing key '{path}'", self.source)
        return self.value(obj[key], path, kind, optional)

    def items(self, obj: dict[str, Any], key: str, where: str, kind: str) -> list[Any]:
        """``obj[key]``: a list whose every item is of ``kind``."""
        path = f"{where}.{key}" if where else key
        return [
            self.value(v, f"{path}[{i}]", kind)
            for i, v in enumerate(self.get(obj, key, where, "list"))
        ]

    def records(
        self,
        obj: dict[str, Any],
        key: str,
        where: str,
        read: Callable[[Reader, dict[str, Any], str], T],
    ) -> list[T]:
        """``obj[key]``: a list of objects, each read by ``read(reader, item, path)``."""
        path = f"{where}.{key}" if where else key
        return [
            read(self, item, f"{path}[{i}]")
            for i, item in enumerate(self.items(obj, key, where, "dict"))
        ]

    def share(self, obj: dict[str, Any], key: str, where: str) -> float:
        """``obj[key]``: a share, a number in [0, 1]."""
        v: float = self.get(obj, key, where, "num")
        if not 0.0 <= v <= 1.0:
            self.fail(f"{where}.{key}", f"must be in [0, 1], got {v}")
        return v

    def amount(self, obj: dict[str, Any], key: str, where: str) -> float:
        """``obj[key]``: a finite number of 0 or more (a time)."""
        v: float = self.get(obj, key, where, "num")
        if not (math.isfinite(v) and v >= 0.0):
            self.fail(f"{where}.{key}", f"must be a finite number of 0 or more, got {v}")
        return v

    def pair(self, obj: dict[str, Any], key: str, where: str) -> tuple[float, float]:
        """``obj[key]``: two numbers (an interval)."""
        vals = self.items(obj, key, where, "num")
        if len(vals) != 2:
            self.fail(f"{where}.{key}", f"must hold two numbers, got {len(vals)}")
        return (vals[0], vals[1])

    def interval(self, obj: dict[str, Any], key: str, where: str) -> tuple[float, float]:
        """``obj[key]``: an interval of shares, two numbers in [0, 1], the lower first."""
        lo, hi = self.pair(obj, key, where)
        if not (0.0 <= lo <= hi <= 1.0):
            self.fail(f"{where}.{key}", f"must be two shares in [0, 1], the lower first, got"
                      f" [{lo:g}, {hi:g}]")  # fmt: skip
        return (lo, hi)

    def count(self, obj: dict[str, Any], key: str, where: str) -> int:
        """``obj[key]``: a whole number of 0 or more."""
        v: int = self.get(obj, key, where, "int")
        if v < 0:
            self.fail(f"{where}.{key}", f"must be a whole number of 0 or more, got {v}")
        return v

    def picture(self, obj: dict[str, Any], key: str, where: str) -> str:
        """``obj[key]``: a picture's file name, relative and inside the results folder."""
        name = self.get(obj, key, where, "str")
        path = f"{where}.{key}" if where else key
        if not is_inside_name(name):
            self.fail(path, f"is {name!r}, not a file inside the results folder")
        return str(name)


def is_inside_name(name: str) -> bool:
    """A relative file name that cannot leave its folder (no absolute path, drive or '..')."""
    if not name or "\x00" in name:
        return False
    for flavour in (PurePosixPath(name), PureWindowsPath(name)):
        if flavour.is_absolute() or flavour.anchor or ".." in flavour.parts:
            return False
    return True


# ---------------------------------------------------------------------------- records


@dataclass(frozen=True)
class Rate:
    """A share with its Wilson 95 % interval over ``n`` clips: a class's recall or a model
    group's accuracy."""

    n: int
    value: float
    ci: tuple[float, float]

    def to_dict(self, key: str) -> dict[str, Any]:
        return {"n": self.n, key: self.value, "ci": list(self.ci)}

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str, key: str) -> Rate:
        return Rate(r.get(d, "n", where, "int"), r.share(d, key, where), r.pair(d, "ci", where))


def _rates(r: Reader, d: dict[str, Any], name: str, where: str, key: str) -> dict[str, Rate]:
    table = r.get(d, name, where, "dict")
    return {
        str(k): Rate.read(r, r.value(v, f"{where}.{name}.{k}", "dict"), f"{where}.{name}.{k}", key)
        for k, v in table.items()
    }


@dataclass(frozen=True)
class McNemar:
    """Exact McNemar test against ``versus`` on the same clips: ``b`` clips only it got
    right, ``c`` only this method, two-sided p-value ``p``."""

    versus: str
    b: int
    c: int
    p: float


@dataclass(frozen=True)
class SignedRank:
    """Wilcoxon's signed-rank test against ``versus`` over the subjects held out, on their
    accuracies: ``n`` subjects whose accuracies differ, ``w`` the smaller rank sum,
    two-sided p-value ``p`` (:func:`cbr.evaluation.stats.signed_rank`)."""

    versus: str
    n: int
    w: float
    p: float


def spread(rates: dict[str, Rate]) -> tuple[float, float, float, float] | None:
    """Mean, sample standard deviation, min and max of the rates' values (each subject
    weighs the same, however many clips it has; the deviation NaN for one value), None for
    no rate."""
    if not rates:
        return None
    v = np.array([r.value for r in rates.values()])
    sd = float(v.std(ddof=1)) if len(v) > 1 else math.nan
    return float(v.mean()), sd, float(v.min()), float(v.max())


@dataclass(frozen=True)
class Scores:
    """How a method that ran did: figures over all clips, per class, per model group, per
    subject held out (leave-one-subject-out only), the confusion matrix ``(classes,
    classes)`` (``unassigned``: predictions outside the classes, per true class), costs
    summed over folds, and every clip's prediction."""

    accuracy: float
    accuracy_ci: tuple[float, float]
    macro_f1: float
    macro_f1_ci: tuple[float, float]
    per_class: dict[str, Rate]
    per_group: dict[str, Rate]
    confusion: list[list[int]]
    unassigned: list[int]
    fit_s: float
    predict_s: float
    predict_ms_per_clip: float
    case_base_size: float | None
    training_size: float
    predictions: list[str]
    correct: list[bool]
    fold_notes: list[str]
    mcnemar: McNemar | None = None
    per_subject: dict[str, Rate] = field(default_factory=dict)
    accuracy_ci_people: tuple[float, float] | None = None
    wilcoxon: SignedRank | None = None

    def subject_spread(self) -> tuple[float, float, float, float] | None:
        """Accuracy over the subjects held out: mean, sd, min, max (:func:`spread`); None
        when not left out one by one (k-fold, or a file written before)."""
        return spread(self.per_subject)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "accuracy": self.accuracy,
            "accuracy_ci": list(self.accuracy_ci),
            "macro_f1": self.macro_f1,
            "macro_f1_ci": list(self.macro_f1_ci),
            "per_class": {c: v.to_dict("recall") for c, v in self.per_class.items()},
            "per_group": {g: v.to_dict("accuracy") for g, v in self.per_group.items()},
            "per_subject": {p: v.to_dict("accuracy") for p, v in self.per_subject.items()},
            "confusion": [list(row) for row in self.confusion],
            "unassigned": list(self.unassigned),
            "fit_s": self.fit_s,
            "predict_s": self.predict_s,
            "predict_ms_per_clip": self.predict_ms_per_clip,
            "case_base_size": self.case_base_size,
            "training_size": self.training_size,
            "predictions": list(self.predictions),
            "correct": list(self.correct),
            "fold_notes": list(self.fold_notes),
        }
        if self.mcnemar is not None:
            m = self.mcnemar
            out.update(mcnemar_vs=m.versus, mcnemar_b=m.b, mcnemar_c=m.c, mcnemar_p=m.p)
        if self.accuracy_ci_people is not None:
            out["accuracy_ci_people"] = list(self.accuracy_ci_people)
        if self.wilcoxon is not None:
            w = self.wilcoxon
            out.update(wilcoxon_vs=w.versus, wilcoxon_n=w.n, wilcoxon_w=w.w, wilcoxon_p=w.p)
        return out

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> Scores:
        mcnemar = None
        if "mcnemar_vs" in d:
            mcnemar = McNemar(
                r.get(d, "mcnemar_vs", where, "str"),
                r.get(d, "mcnemar_b", where, "int"),
                r.get(d, "mcnemar_c", where, "int"),
                r.get(d, "mcnemar_p", where, "num"),
            )
        wilcoxon = None
        if "wilcoxon_vs" in d:
            wilcoxon = SignedRank(
                r.get(d, "wilcoxon_vs", where, "str"),
                r.count(d, "wilcoxon_n", where),
                r.amount(d, "wilcoxon_w", where),
                r.share(d, "wilcoxon_p", where),
            )
        confusion = [
            [r.value(x, f"{where}.confusion[{i}][{j}]", "int") for j, x in enumerate(row)]
            for i, row in enumerate(r.items(d, "confusion", where, "list"))
        ]
        return Scores(
            accuracy=r.share(d, "accuracy", where),
            accuracy_ci=r.pair(d, "accuracy_ci", where),
            macro_f1=r.share(d, "macro_f1", where),
            macro_f1_ci=r.pair(d, "macro_f1_ci", where),
            per_class=_rates(r, d, "per_class", where, "recall"),
            per_group=_rates(r, d, "per_group", where, "accuracy"),
            confusion=confusion,
            unassigned=r.items(d, "unassigned", where, "int"),
            fit_s=r.amount(d, "fit_s", where),
            predict_s=r.amount(d, "predict_s", where),
            predict_ms_per_clip=r.amount(d, "predict_ms_per_clip", where),
            case_base_size=r.get(d, "case_base_size", where, "num", optional=True),
            training_size=r.get(d, "training_size", where, "num"),
            predictions=r.items(d, "predictions", where, "str"),
            correct=r.items(d, "correct", where, "bool"),
            fold_notes=r.items(d, "fold_notes", where, "str"),
            mcnemar=mcnemar,
            # absent in a file written before it was (or under k-fold): none
            per_subject=_rates(r, d, "per_subject", where, "accuracy")
            if "per_subject" in d
            else {},
            # absent under k-fold and in a file written before they were given
            accuracy_ci_people=r.interval(d, "accuracy_ci_people", where)
            if "accuracy_ci_people" in d
            else None,
            wilcoxon=wilcoxon,
        )


@dataclass(frozen=True)
class MethodResult:
    """One row of the comparison: the method, whether it ran (``status`` "ok", "skipped" or
    "failed", with ``message``), and its scores when it did."""

    name: str
    kind: str
    interpretable: bool
    params: dict[str, Any]
    status: str
    message: str = ""
    scores: Scores | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "name": self.name,
            "kind": self.kind,
            "interpretable": self.interpretable,
            "params": dict(self.params),
            "status": self.status,
            "message": self.message,
        }
        if self.scores is not None:
            out.update(self.scores.to_dict())
        return out

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> MethodResult:
        status = r.get(d, "status", where, "str")
        if status not in ("ok", "skipped", "failed"):
            r.fail(f"{where}.status", f"must be ok, skipped or failed, got {status!r}")
        return MethodResult(
            name=r.get(d, "name", where, "str"),
            kind=r.get(d, "kind", where, "str"),
            interpretable=r.get(d, "interpretable", where, "bool"),
            params=r.get(d, "params", where, "dict"),
            status=status,
            message=r.get(d, "message", where, "str"),
            scores=Scores.read(r, d, where) if status == "ok" else None,
        )


@dataclass(frozen=True)
class DatasetSummary:
    """The clips compared: where from, how many, whose, and of which classes."""

    source: str
    n_clips: int
    subjects: list[str]
    classes: list[str]
    class_counts: dict[str, int]
    activities: list[str]

    def to_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "n_clips": self.n_clips,
            "subjects": list(self.subjects),
            "classes": list(self.classes),
            "class_counts": dict(self.class_counts),
            "activities": list(self.activities),
        }

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> DatasetSummary:
        counts = r.get(d, "class_counts", where, "dict")
        return DatasetSummary(
            source=r.get(d, "source", where, "str"),
            n_clips=r.get(d, "n_clips", where, "int"),
            subjects=r.items(d, "subjects", where, "str"),
            classes=r.items(d, "classes", where, "str"),
            class_counts={
                str(k): r.value(v, f"{where}.class_counts.{k}", "int") for k, v in counts.items()
            },
            activities=r.items(d, "activities", where, "str"),
        )


@dataclass(frozen=True)
class CVSummary:
    """The cross-validation used: scheme ("loso", "kfold" or "given"), folds, the fold of
    every clip ``(n_clips,)``, and what macro-F1's bootstrap resampled ("subjects" under
    leave-one-subject-out, else "clips"; "clips" for a file written before it was said)."""

    scheme: str
    n_folds: int
    fold_of_clip: list[int]
    bootstrap_over: str = "clips"

    def to_dict(self) -> dict[str, Any]:
        return {
            "scheme": self.scheme,
            "n_folds": self.n_folds,
            "fold_of_clip": self.fold_of_clip,
            "bootstrap_over": self.bootstrap_over,
        }

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> CVSummary:
        over = r.get(d, "bootstrap_over", where, "str", optional=True)
        if over not in (None, "clips", "subjects"):
            r.fail(f"{where}.bootstrap_over", f"must be 'clips' or 'subjects', got {over!r}")
        return CVSummary(
            r.get(d, "scheme", where, "str"),
            r.get(d, "n_folds", where, "int"),
            r.items(d, "fold_of_clip", where, "int"),
            over or "clips",
        )


def _piece(frames: tuple[int, int] | None) -> dict[str, Any]:
    """A piece of a file's frames as ``classify --json`` gives them (end exclusive); none for
    a whole file."""
    return {} if frames is None else {"start_frame": frames[0], "end_frame": frames[1]}


def _read_piece(r: Reader, d: dict[str, Any], where: str) -> tuple[int, int] | None:
    """The frames :func:`_piece` wrote, or None (a whole file, or a file written before)."""
    start = r.get(d, "start_frame", where, "int", optional=True)
    end = r.get(d, "end_frame", where, "int", optional=True)
    if start is None and end is None:
        return None
    if start is None or end is None or not 0 <= start < end:
        r.fail(f"{where}.start_frame", "and end_frame must be frames 0 <= start < end, together")
    return int(start), int(end)


@dataclass(frozen=True)
class ClipInfo:
    """One clip compared: its name, activity, subject and target value; ``frames`` its
    frames in its file (start, end exclusive) when it is a piece of it."""

    id: str
    label: str
    subject: str | None
    target: str
    frames: tuple[int, int] | None = None

    def to_dict(self) -> dict[str, Any]:
        # "clip" as the explanations below, classify and reps name it; "id" kept (its first name)
        return {
            "id": self.id,
            "clip": self.id,
            **_piece(self.frames),
            "label": self.label,
            "subject": self.subject,
            "target": self.target,
        }

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> ClipInfo:
        return ClipInfo(
            r.get(d, "id", where, "str"),
            r.get(d, "label", where, "str"),
            r.get(d, "subject", where, "str", optional=True),
            r.get(d, "target", where, "str"),
            _read_piece(r, d, where),
        )


@dataclass(frozen=True)
class ExplainedClip:
    """Why a method got one clip wrong, in words (``explanation``: the case-base
    explanation's own record, None for DAD; ``frames``: as :class:`ClipInfo`'s)."""

    clip: str
    subject: str | None
    activity: str
    true: str
    predicted: str
    method: str
    text: str
    explanation: dict[str, Any] | None = None
    frames: tuple[int, int] | None = None

    @property
    def name(self) -> str:
        """The clip for people: a piece of a file named with its frames (end inclusive)."""
        from ..casebase import piece_name

        return piece_name(self.clip, self.frames)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "clip": self.clip,
            **_piece(self.frames),
            "subject": self.subject,
            "activity": self.activity,
            "true": self.true,
            "true_label": self.true,  # as classify names the value checked against
            "predicted": self.predicted,
            "method": self.method,
            "text": self.text,
        }
        if self.explanation is not None:
            out["explanation"] = self.explanation
        return out

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> ExplainedClip:
        return ExplainedClip(
            r.get(d, "clip", where, "str"),
            r.get(d, "subject", where, "str", optional=True),
            r.get(d, "activity", where, "str"),
            r.get(d, "true", where, "str"),
            r.get(d, "predicted", where, "str"),
            r.get(d, "method", where, "str"),
            r.get(d, "text", where, "str"),
            r.get(d, "explanation", where, "dict", optional=True),
            _read_piece(r, d, where),
        )


@dataclass(frozen=True)
class Prevalence:
    """Feature prevalence per activity in the initial and the trimmed case base (paper fig.
    4): ``initial`` and ``trimmed`` are ``(activities, features)``."""

    method: str
    trim: float
    activities: list[str]
    features: list[str]
    initial: list[list[float]]
    trimmed: list[list[float]]
    cases_initial: list[int]
    cases_trimmed: list[int]

    def to_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "trim": self.trim,
            "activities": list(self.activities),
            "features": list(self.features),
            "initial": [list(r) for r in self.initial],
            "trimmed": [list(r) for r in self.trimmed],
            "cases_initial": list(self.cases_initial),
            "cases_trimmed": list(self.cases_trimmed),
        }

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> Prevalence:
        def table(key: str) -> list[list[float]]:
            rows = r.items(d, key, where, "list")
            return [
                [r.value(x, f"{where}.{key}[{i}][{j}]", "num") for j, x in enumerate(row)]
                for i, row in enumerate(rows)
            ]

        return Prevalence(
            method=r.get(d, "method", where, "str"),
            trim=r.get(d, "trim", where, "num"),
            activities=r.items(d, "activities", where, "str"),
            features=r.items(d, "features", where, "str"),
            initial=table("initial"),
            trimmed=table("trimmed"),
            cases_initial=r.items(d, "cases_initial", where, "int"),
            cases_trimmed=r.items(d, "cases_trimmed", where, "int"),
        )


@dataclass(frozen=True)
class ConfusionPicture:
    method: str
    file: str


@dataclass(frozen=True)
class TimelinePicture:
    activity: str
    clip: str
    file: str


@dataclass
class Pictures:
    """The pictures of a comparison, as file names relative to the results folder."""

    accuracy: str | None = None
    confusion: list[ConfusionPicture] = field(default_factory=list)
    prevalence: str | None = None
    timelines: list[TimelinePicture] = field(default_factory=list)

    def files(self) -> list[str]:
        """Every picture's file name."""
        out = [self.accuracy, self.prevalence] + [c.file for c in self.confusion]
        return [f for f in out + [t.file for t in self.timelines] if f is not None]

    def under(self, folder: str) -> Pictures:
        """The same pictures named from the folder that holds ``folder`` (a relative name
        inside it, '/'-separated): for a results file there, beside the pictures' folder."""

        def name(file: str) -> str:
            return f"{folder}/{file}"

        return Pictures(
            accuracy=None if self.accuracy is None else name(self.accuracy),
            confusion=[ConfusionPicture(c.method, name(c.file)) for c in self.confusion],
            prevalence=None if self.prevalence is None else name(self.prevalence),
            timelines=[TimelinePicture(t.activity, t.clip, name(t.file)) for t in self.timelines],
        )

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if self.accuracy is not None:
            out["accuracy"] = self.accuracy
        if self.confusion:
            out["confusion"] = [{"method": c.method, "file": c.file} for c in self.confusion]
        if self.prevalence is not None:
            out["prevalence"] = self.prevalence
        if self.timelines:
            out["timelines"] = [
                {"activity": t.activity, "clip": t.clip, "file": t.file} for t in self.timelines
            ]
        return out

    @staticmethod
    def read(r: Reader, d: dict[str, Any], where: str) -> Pictures:
        def confusion(r: Reader, c: dict[str, Any], w: str) -> ConfusionPicture:
            return ConfusionPicture(r.get(c, "method", w, "str"), r.picture(c, "file", w))

        def timeline(r: Reader, t: dict[str, Any], w: str) -> TimelinePicture:
            return TimelinePicture(
                r.get(t, "activity", w, "str"), r.get(t, "clip", w, "str"), r.picture(t, "file", w)
            )

        return Pictures(
            accuracy=r.picture(d, "accuracy", where) if "accuracy" in d else None,
            confusion=r.records(d, "confusion", where, confusion) if "confusion" in d else [],
            prevalence=r.picture(d, "prevalence", where) if "prevalence" in d else None,
            timelines=r.records(d, "timelines", where, timeline) if "timelines" in d else [],
        )


# ---------------------------------------------------------------------------- the whole


def _check_counts(r: Reader, s: Scores, where: str, n_classes: int) -> None:
    """``s``'s clips outside the classes one count per class, and every count of clips at
    least 0."""
    if len(s.unassigned) != n_classes:
        r.fail(f"{where}.unassigned",
               f"must hold one per class ({n_classes}), got {len(s.unassigned)}")  # fmt: skip
    cells = [(f"confusion[{a}][{b}]", n) for a, row in enumerate(s.confusion)
             for b, n in enumerate(row)]  # fmt: skip
    cells += [(f"unassigned[{a}]", n) for a, n in enumerate(s.unassigned)]
    for key, count in cells:
        if count < 0:
            r.fail(f"{where}.{key}", f"is a count of clips, got {count}")


def _check_per_subject(r: Reader, s: Scores, where: str, clips: list[ClipInfo]) -> None:
    """``s``'s accuracy per subject held out against the clips: every subject one of theirs,
    its ``n`` its clips (so the ``n`` add up to the clips) and its accuracy the share of
    them ``correct`` says were right (``correct`` one per clip, checked before)."""
    if not s.per_subject:
        return
    total = sum(rate.n for rate in s.per_subject.values())
    if total != len(clips):
        r.fail(f"{where}.per_subject",
               f"counts {total} clips in all, not the results' {len(clips)}")  # fmt: skip
    for person, rate in s.per_subject.items():
        key = f"{where}.per_subject.{person}"
        right = [ok for c, ok in zip(clips, s.correct, strict=True) if c.subject == person]
        if not right:
            r.fail(key, "names no subject of the results' clips")
        if rate.n != len(right):
            r.fail(f"{key}.n", f"must be the subject's {len(right)} clips, got {rate.n}")
        share = sum(right) / len(right)
        if not math.isclose(rate.value, share, rel_tol=1e-9, abs_tol=1e-12):
            r.fail(f"{key}.accuracy",
                   f"must be the share of the subject's clips correct ({share:g}), got"
                   f" {rate.value:g}")  # fmt: skip


@dataclass
class CompareResults:
    """Everything a comparison found, as written to ``results.json``.

    ``machine``: :func:`cbr.evaluation.machine.machine_info`; ``settings``:
    :meth:`CompareSettings.to_dict`; ``explanations``, ``pictures`` and ``prevalence`` are
    filled in after the folds ran.
    """

    created_utc: str
    machine: dict[str, Any]
    dataset: DatasetSummary
    settings: dict[str, Any]
    cv: CVSummary
    notes: list[str]
    clips: list[ClipInfo]
    methods: list[MethodResult]
    best: str | None
    best_interpretable: str | None
    explanations: list[ExplainedClip] = field(default_factory=list)
    pictures: Pictures = field(default_factory=Pictures)
    prevalence: Prevalence | None = None

    def scored(self) -> list[tuple[MethodResult, Scores]]:
        """The methods that ran, with their scores."""
        return [(m, m.scores) for m in self.methods if m.scores is not None]

    def method(self, name: str) -> MethodResult | None:
        return next((m for m in self.methods if m.name == name), None)

    def best_cbr(self) -> tuple[MethodResult, Scores] | None:
        """The most accurate case-base configuration that ran (ties: higher macro-F1)."""
        cbr = [(m, s) for m, s in self.scored() if m.kind == "cbr"]
        return max(cbr, key=lambda ms: (ms[1].accuracy, ms[1].macro_f1)) if cbr else None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": KIND,
            "created_utc": self.created_utc,
            "machine": self.machine,
            "dataset": self.dataset.to_dict(),
            "settings": self.settings,
            "cv": self.cv.to_dict(),
            "notes": list(self.notes),
            "clips": [c.to_dict() for c in self.clips],
            "methods": [m.to_dict() for m in self.methods],
            "best": self.best,
            "best_interpretable": self.best_interpretable,
            "explanations": [e.to_dict() for e in self.explanations],
            "pictures": self.pictures.to_dict(),
        }
        if self.prevalence is not None:
            out["prevalence"] = self.prevalence.to_dict()
        return out

    @staticmethod
    def from_dict(doc: Any, source: str = "results") -> CompareResults:
        """Read a results document (as ``json.load`` gives it), checking every key and type;
        raises :class:`~features.errors.DataError` naming ``source`` and the key."""
        if not isinstance(doc, dict) or doc.get("kind") != KIND:
            raise DataError("not a `posecbr compare` results file", source)
        r = Reader(source)
        machine = r.get(doc, "machine", "", "dict")
        for key, kind in (("python", "str"), ("platform", "str")):
            r.get(machine, key, "machine", kind)
        r.get(machine, "cpu_count", "machine", "int", optional=True)
        settings = r.get(doc, "settings", "", "dict")
        r.get(settings, "target", "settings", "str")
        r.get(settings, "within", "settings", "str", optional=True)
        prevalence = r.get(doc, "prevalence", "", "dict", optional=True)
        results = CompareResults(
            created_utc=r.get(doc, "created_utc", "", "str"),
            machine=machine,
            dataset=DatasetSummary.read(r, r.get(doc, "dataset", "", "dict"), "dataset"),
            settings=settings,
            cv=CVSummary.read(r, r.get(doc, "cv", "", "dict"), "cv"),
            notes=r.items(doc, "notes", "", "str"),
            clips=r.records(doc, "clips", "", ClipInfo.read),
            methods=r.records(doc, "methods", "", MethodResult.read),
            best=r.get(doc, "best", "", "str", optional=True),
            best_interpretable=r.get(doc, "best_interpretable", "", "str", optional=True),
            explanations=r.records(doc, "explanations", "", ExplainedClip.read),
            pictures=Pictures.read(r, r.get(doc, "pictures", "", "dict"), "pictures"),
            prevalence=None if prevalence is None else Prevalence.read(r, prevalence, "prevalence"),
        )
        results.check(r)
        return results

    def check(self, r: Reader) -> None:
        """What the keys say of each other: methods to report, the best ones among them,
        each method's confusion matrix and predictions the size of the classes and clips,
        and Wilcoxon's people no more than the subjects held out."""
        if not self.methods:
            r.fail("methods", "lists no method: nothing to report")
        names = [m.name for m in self.methods]
        for key, name in (("best", self.best), ("best_interpretable", self.best_interpretable)):
            if name is not None and name not in names:
                r.fail(key, f"names no method of the results, got {name!r}")
        n_classes, n_clips = len(self.dataset.classes), len(self.clips)
        for i, s in enumerate(m.scores for m in self.methods):
            if s is None:
                continue
            where = f"methods[{i}]"
            if len(s.confusion) != n_classes or any(len(row) != n_classes for row in s.confusion):
                shape = f"{len(s.confusion)} rows of " + "/".join(
                    sorted({str(len(row)) for row in s.confusion}) or ["0"]
                )
                r.fail(f"{where}.confusion",
                       f"must be {n_classes} x {n_classes} (the classes), got {shape}")  # fmt: skip
            _check_counts(r, s, where, n_classes)
            for key, values in (("predictions", s.predictions), ("correct", s.correct)):
                if len(values) != n_clips:
                    r.fail(
                        f"{where}.{key}", f"must hold one per clip ({n_clips}), got {len(values)}"
                    )
            _check_per_subject(r, s, where, self.clips)
            # a file written before per_subject was has none to count against
            if s.wilcoxon is not None and s.per_subject and s.wilcoxon.n > len(s.per_subject):
                r.fail(f"{where}.wilcoxon_n",
                       f"counts {s.wilcoxon.n} subjects whose accuracies differ, more than the"
                       f" {len(s.per_subject)} in per_subject")  # fmt: skip
