"""What a comparison runs: ``CompareSettings``, checked when made, with the names it accepts."""

from __future__ import annotations

import dataclasses
import importlib.util
from dataclasses import dataclass, field
from typing import Any

from features.errors import ConfigError, ParameterError
from features.text import did_you_mean

SIMILARITIES = ("euclidean", "dtw", "signature")
FEATURE_LEVELS = ("fluents", "qmp")
PEERS = ("dtw-knn", "minirocket")
CV_SCHEMES = ("loso", "kfold")
# Set by the comparison itself for every case-base configuration, so not a --param: each
# with the argument that sets it.
_SET_PER_METHOD = {"features": "features", "similarity": "similarities", "k": "k", "trim": "trim"}


@dataclass(frozen=True)
class CompareSettings:
    """What ``compare`` runs.

    target: ``"label"`` or a metadata column; cv: ``"loso"`` (leave one subject out, asked for
    by name: refused, with ConfigError naming ``cv``, on clips of one subject or without one,
    also when the clips a comparison leaves out leave one subject), ``"kfold"`` (stratified
    k-fold over clips), or None (the default: leave one subject out, falling back to
    stratified k-fold with a note when that is impossible; ``"loso"`` in :meth:`to_dict`);
    within: train one model per value of this column (``"label"`` by default when the target
    is not the label; ``None``: one model for all).
    k: neighbours of the case-base classifiers; trim: fraction of cases kept by novelty/benefit
    trimming (None: keep all); cbr_params: further ``CaseBaseClassifier`` parameters given to
    every case-base configuration (e.g. ``{"states": "all", "length": 48}``); peer_length:
    frames the peers' angle series are resampled to; jobs: worker processes for the folds;
    scheduler: run the folds on a Dask cluster instead (``local:N`` or a scheduler address);
    bootstrap: resamples for the F1 interval; explain: misclassified clips to explain.
    A value it cannot run is refused when made, with ParameterError (a ConfigError and a
    ValueError) naming the field ("folds: must be at least 2, got 1"); ``compare`` says it of
    its option ("--folds: ...").
    """

    target: str = "label"
    cv: str | None = None
    folds: int = 5
    similarities: tuple[str, ...] = SIMILARITIES
    features: tuple[str, ...] = FEATURE_LEVELS
    dad: bool = True
    peers: tuple[str, ...] = PEERS
    k: int = 5
    trim: float | None = None
    cbr_params: dict[str, Any] = field(default_factory=dict)
    within: str | None = "auto"
    peer_length: int = 64
    jobs: int = 1
    scheduler: str | None = None
    seed: int = 0
    bootstrap: int = 1000
    explain: int = 5

    def __post_init__(self) -> None:
        self._check_choices()
        self._check_numbers()
        self._check_cbr_params()

    def _check_choices(self) -> None:
        if self.cv is not None and self.cv not in CV_SCHEMES:
            raise ParameterError(
                f"must be one of {', '.join(CV_SCHEMES)}, got {self.cv!r}"
                f"{did_you_mean(str(self.cv), CV_SCHEMES)}",
                "cv",
            )
        for argument, given, known, what in (
            ("similarities", self.similarities, SIMILARITIES, "similarity"),
            ("features", self.features, FEATURE_LEVELS, "feature level"),
            ("peers", self.peers, PEERS, "peer"),
        ):
            if not given and argument != "peers":  # no peers is a choice ("none")
                raise ParameterError(f"no {what} given", argument)
            for i, name in enumerate(given):
                if name not in known:
                    raise ParameterError(
                        f"unknown {what} {name!r} (choose from {', '.join(known)})"
                        f"{did_you_mean(str(name), known)}",
                        argument,
                    )
                if name in given[:i]:  # its rows, pictures and results would be there twice
                    raise ParameterError(f"{what} {name!r} given twice", argument)
        self._check_levels_compared()

    def _check_levels_compared(self) -> None:
        """Some feature level asked for is compared by a similarity asked for: QMP vectors
        are one per clip, which the sequence measures (dtw, signature) do not compare."""
        from ..similarity import get_measure

        if set(self.features) == {"qmp"} and all(
            get_measure(s).compares_sequences for s in self.similarities
        ):
            raise ParameterError(
                "qmp features are one vector per clip, compared by euclidean only, which"
                " the similarities compared leave out: nothing would compare them (add"
                " euclidean)",
                "features",
            )

    def _check_numbers(self) -> None:
        if int(self.folds) < 2:
            raise ParameterError(f"must be at least 2, got {self.folds}", "folds")
        if int(self.k) < 1:
            raise ParameterError(f"must be a positive integer, got {self.k}", "k")
        if self.trim is not None and not 0.0 < float(self.trim) <= 1.0:
            raise ParameterError(f"must be in (0, 1], got {self.trim}", "trim")
        if int(self.jobs) < 1:
            raise ParameterError(f"must be at least 1, got {self.jobs}", "jobs")
        if int(self.jobs) > 1 and self.scheduler is not None:
            raise ParameterError(
                f"goes with worker processes of this machine; the folds run on the Dask"
                f" scheduler {self.scheduler} (its workers are the cluster's: local:N for N)",
                "jobs",
            )
        if int(self.peer_length) < 9:
            raise ParameterError(
                f"must be at least 9 frames, got {self.peer_length}", "peer_length"
            )
        if int(self.bootstrap) < 1:
            raise ParameterError(f"must be at least 1, got {self.bootstrap}", "bootstrap")
        if int(self.explain) < 0:
            raise ParameterError(f"must be 0 or more, got {self.explain}", "explain")
        if not 0 <= int(self.seed) < 2**32:  # numpy's seeds
            raise ParameterError(f"must be in 0 to 2**32 - 1, got {self.seed}", "seed")

    def _check_cbr_params(self) -> None:
        from cbr.estimator import CaseBaseClassifier

        for key, argument in _SET_PER_METHOD.items():
            if key in self.cbr_params:  # before: "unknown case-base parameter(s) k"
                raise ParameterError(
                    f"{key} is set for every case-base configuration by `{argument}` (give"
                    f" `{argument}={self.cbr_params[key]!r}`), not by a parameter",
                    "cbr_params",
                )
        known = set(CaseBaseClassifier().get_params()) - set(_SET_PER_METHOD)
        bad = sorted(set(self.cbr_params) - known)
        if bad:
            raise ParameterError(
                f"unknown case-base parameter(s) {', '.join(bad)} "
                f"(known: {', '.join(sorted(known))})"
                f"{did_you_mean(bad[0], known) or similarity_words(bad[0])}",
                "cbr_params",
            )

    @property
    def within_column(self) -> str | None:
        """The column one model is trained per value of (None: one model for all clips)."""
        if self.within == "auto":
            return None if self.target == "label" else "label"
        return self.within or None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready settings, ``cv`` and ``within`` resolved."""
        d = dataclasses.asdict(self)
        d["cv"] = self.cv or "loso"
        d["within"] = self.within_column
        return d


def similarity_words(key: str) -> str:
    """For a ``compare --param KEY=...`` that no case-base parameter is but a similarity
    measure's is (``band``, which ``train --param`` sets): how compare takes it, " (band is a
    parameter of the dtw similarity, as train --param takes it; here --param
    similarity_params='{"band": VALUE}' with --similarities dtw)"; empty when no measure has
    it. One option name, two meanings: compare's ``--param`` sets the classifier's
    parameters, of every similarity compared, train's the one similarity's."""
    from cbr.similarity import available_measures, get_measure

    owners = []
    for name in available_measures():
        try:
            fields = {f.name for f in dataclasses.fields(get_measure(name))}
        except ConfigError:  # a registered measure that cannot be made without parameters
            continue
        if key in fields:
            owners.append(name)
    if not owners:
        return ""
    return (
        f" ({key} is a parameter of the {' and '.join(owners)} similarit"
        f"{'y' if len(owners) == 1 else 'ies'}, as train --param takes it; here --param"
        f" similarity_params='{{\"{key}\": VALUE}}' with --similarities {','.join(owners)})"
    )


def minirocket_backend() -> str | None:
    """``"sktime"`` or ``"aeon"`` when one of them is installed, else None (found, not
    imported: asking costs no import of either)."""
    for name in ("sktime", "aeon"):
        if importlib.util.find_spec(name) is not None:
            return name
    return None
