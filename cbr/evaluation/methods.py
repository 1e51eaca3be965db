"""The rows of a comparison: which methods the settings ask for, why one cannot run here, and
a fresh estimator for each."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from features.errors import ConfigError, InputError, ParameterError

from ..similarity import get_measure
from .settings import CompareSettings, minirocket_backend


@dataclass(frozen=True)
class Method:
    """One row of the comparison: ``kind`` is "cbr", "dad" or "peer"; ``params`` are the
    estimator's parameters."""

    name: str
    kind: str
    interpretable: bool
    params: dict[str, Any] = field(default_factory=dict)


def _cbr_methods(settings: CompareSettings) -> list[Method]:
    return [
        Method(
            f"cbr {level}/{sim}",
            "cbr",
            True,
            {
                "features": level,
                "similarity": sim,
                "k": int(settings.k),
                "trim": settings.trim,
                # as posecbr train: another column than the activity votes class-balanced
                "class_weight": "none" if settings.target == "label" else "balanced",
                **settings.cbr_params,
            },
        )
        for level in settings.features
        for sim in settings.similarities
        # a QMP description is one vector per clip: sequence measures have nothing to align
        if level != "qmp" or not get_measure(sim).compares_sequences
    ]


def check_cbr_params(settings: CompareSettings) -> None:
    """Refuse, before any work, case-base parameters (``cbr_params``) that a configuration
    cannot be built with: every fold of it would fail the same way. ParameterError naming
    ``cbr_params``, the parameter refused and the configuration ("cbr_params: states: must
    be one of ... (cbr fluents/euclidean)"); ``compare`` says it of ``--param``."""
    from ..estimator import CaseBaseClassifier

    for method in _cbr_methods(settings):
        try:
            CaseBaseClassifier(**method.params).describe_plan()  # the measure built too
        except ConfigError as exc:
            said = f"{exc.source}: {exc.message}" if exc.source else exc.message
            raise ParameterError(f"{said} ({method.name})", "cbr_params") from None


def _peer_method(peer: str, settings: CompareSettings) -> Method:
    params: dict[str, Any] = {"length": int(settings.peer_length)}
    if peer == "dtw-knn":
        params["n_neighbors"] = 1
    else:
        params["random_state"] = int(settings.seed)
    return Method(peer, "peer", False, params)


def methods_for(settings: CompareSettings) -> list[Method]:
    """Every configuration ``settings`` asks for, interpretable ones first."""
    out = _cbr_methods(settings)
    if settings.dad:
        out.append(Method("dad", "dad", True, {}))
    out += [_peer_method(p, settings) for p in settings.peers]
    return out


def make_estimator(method: Method) -> Any:
    """A fresh, unfitted estimator for ``method`` (all share fit(X, y)/predict(X))."""
    if method.kind == "cbr":
        from ..estimator import CaseBaseClassifier

        return CaseBaseClassifier(**method.params)
    if method.kind == "dad":
        from ..dad import DADClassifier

        return DADClassifier()
    from .peers import DTWKNNPeer, MiniRocketPeer  # scikit-learn: imported for a peer run only

    if method.name == "dtw-knn":
        return DTWKNNPeer(**method.params)
    if method.name == "minirocket":
        return MiniRocketPeer(**method.params)
    raise ConfigError(f"unknown method {method.name!r}", "compare")


def add_labels() -> set[str]:
    """Every dataset label the shipped ADD has an activity for."""
    from features.qmp.add import load_add

    return {lab for act in load_add().activities.values() for lab in act.labels}


def add_covers(classes: list[str]) -> list[str]:
    """The ``classes`` the shipped ADD has an activity for, names matched as DAD matches them
    (case, spaces, underscores and hyphens ignored: CMU's "Squat" is the ADD's "squat")."""
    from ..dad import label_key

    keys = {label_key(lab) for lab in add_labels()}
    return [c for c in classes if label_key(c) in keys]


def why_unavailable(method: Method, classes: list[str], target: str) -> str | None:
    """Why ``method`` cannot run on a comparison of ``classes`` of ``target`` (None if it
    can)."""
    if method.kind == "dad":
        if target != "label":
            return f"DAD recognises activities from its ADD rules; it does not predict {target!r}"
        if not add_covers(classes):
            return "the ADD describes none of this dataset's activities"
        from features.qmp.add import load_add

        from ..dad import class_of_activity

        try:
            class_of_activity(load_add(), classes)
        except InputError as exc:
            return exc.message
    if method.name == "minirocket" and minirocket_backend() is None:
        return (
            "MiniRocket needs sktime or aeon, neither is installed "
            "(pip install -e '.[compare]' installs sktime)"
        )
    return None
