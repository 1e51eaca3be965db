"""The names of the judges of "unknown" (:mod:`cbr.unknown`), the default first, in a module
that imports nothing: ``posecbr segment`` and ``watch`` offer them as choices without loading
numpy or scikit-learn (the command line starts light)."""

JUDGES = (
    "spread-margin",
    "activity-margin",
    "margin",
    "held-out",
    "activities",
    "margin-distance",
    "spread-far",
)
"""The judges by name, the default first."""
