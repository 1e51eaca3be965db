"""What counts as a number among the values a caller passes: a real number of Python or
numpy, never a bool (``True`` is 1 to Python, never a length, a fraction or a rate)."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np


def is_number(value: Any) -> bool:
    """Whether ``value`` is a real number (int, float, numpy's), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


__all__ = ["is_number"]
