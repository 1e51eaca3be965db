"""Qualitative motion primitives (QMPs): SINDy fits of state signals over time windows.

The model as parts (pysindy's layout): :class:`ExplicitTimeLibrary` (the basis),
:class:`STLSQ` (sparse regression), :class:`SavitzkyGolay` (derivatives), :func:`search_period`
(the period search), gathered in :class:`QMPConfig` and run in bulk by :func:`fit_signals`.
"""

from .add import ADD, load_add
from .differentiation import SavitzkyGolay
from .features import QMPFeatures, qmp_features, qmp_from_signals
from .fit import (
    FLAT,
    NOT_ENOUGH_DATA,
    OK,
    QUANTITIES,
    STATUS_WORDS,
    PeriodSearch,
    QMPConfig,
    QMPFits,
    derived_quantities,
    fill_short_gaps,
    fit_signals,
    period_grid,
    quantity_key,
    search_period,
    signal_unit,
    sliding_windows,
)
from .library import COEFFICIENT_KEYS, FEATURE_NAMES, ExplicitTimeLibrary
from .optimizer import STLSQ

__all__ = [
    "ADD",
    "QMPFeatures",
    "load_add",
    "qmp_features",
    "qmp_from_signals",
    "COEFFICIENT_KEYS",
    "FEATURE_NAMES",
    "FLAT",
    "NOT_ENOUGH_DATA",
    "OK",
    "QUANTITIES",
    "STATUS_WORDS",
    "STLSQ",
    "ExplicitTimeLibrary",
    "PeriodSearch",
    "QMPConfig",
    "QMPFits",
    "SavitzkyGolay",
    "derived_quantities",
    "fill_short_gaps",
    "fit_signals",
    "period_grid",
    "quantity_key",
    "search_period",
    "signal_unit",
    "sliding_windows",
]
