"""QMP feature vectors for the case base: ADD criteria (binary) and the parameters they read."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from features.poses import PoseSequence

from .add import ADD, evaluate_criteria, feature_columns, feature_name, load_add
from .fit import NOT_ENOUGH_DATA, QMPConfig, fit_signals


@dataclass(frozen=True)
class QMPFeatures:
    """A clip's QMP description.

    names ``(n,)``: the binary criteria first (their ADD words, e.g. "knees bending and
    straightening in rhythm"), then the continuous parameters as ``signal.quantity_unit``
    (e.g. "left_knee.amplitude_rad", "left_knee.period_s"); values ``(n,)`` float64: 1.0/0.0
    for the criteria, the fitted parameter otherwise (NaN = not observable in this clip: a
    criterion in no window, a parameter in no fit);
    binary ``(n_binary,)`` bool with binary_names; criteria ``(n_binary,)`` the ADD names;
    status: "ok" or "not enough data".
    """

    names: tuple[str, ...]
    values: np.ndarray
    binary: np.ndarray
    binary_names: tuple[str, ...]
    criteria: tuple[str, ...]
    status: str

    def as_dict(self) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}


def qmp_features(
    seq: PoseSequence,
    add: ADD | str | Path | None = None,
    config: QMPConfig | None = None,
    window_s: float | None = None,
    step_s: float = 1.0,
) -> QMPFeatures:
    """QMP feature vector of ``seq`` (positions ``(frames, joints, 3)``).

    By default the whole clip is one window (a segmented repetition). With ``window_s``, QMPs
    are fitted over sliding windows: a criterion counts as met if it holds in any window, and
    each parameter is the median over the windows where it is defined.
    """
    from features.fluents import state_signals

    db = add if isinstance(add, ADD) else load_add(add)
    signals = state_signals(seq)
    values = signals.values[:, [signals.names.index(s) for s in db.signals]]
    return qmp_from_signals(values, seq.fps, db, config, window_s, step_s)


def qmp_from_signals(
    values: np.ndarray,
    fps: float,
    add: ADD,
    config: QMPConfig | None = None,
    window_s: float | None = None,
    step_s: float = 1.0,
    frame_block: int | None = None,
) -> QMPFeatures:
    """:func:`qmp_features` from the state signals the ADD reads, ``values``
    ``(frames, len(add.signals))`` (a long clip's computed a piece at a time); frame_block:
    frames of the fit's basis evaluated at once (:func:`features.qmp.fit.frame_blocks`)."""
    used = add.signals
    fits = fit_signals(
        values, fps, used, config=config, window_s=window_s, step_s=step_s, frame_block=frame_block
    )
    crit = evaluate_criteria(add, fits)
    binary = (crit.met & crit.observable).any(axis=0)
    seen = crit.observable.any(axis=0)  # a criterion no window could test is unknown, not unmet
    pairs = feature_columns(add)
    cont = np.full(len(pairs), np.nan)
    for i, (signal, quantity) in enumerate(pairs):
        v = fits.quantity(quantity)[:, fits.index(signal)]
        v = v[np.isfinite(v)]
        if len(v):
            cont[i] = float(np.median(v))
    binary_names = tuple(add.criteria[n].words for n in crit.names)
    names = binary_names + tuple(feature_name(s, q) for s, q in pairs)
    status = "not enough data" if (fits.status == NOT_ENOUGH_DATA).all() else "ok"
    return QMPFeatures(
        names=names,
        values=np.concatenate([np.where(seen, binary.astype(np.float64), np.nan), cont]),
        binary=binary,
        binary_names=binary_names,
        criteria=crit.names,
        status=status,
    )
