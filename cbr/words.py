"""The words a case base's description is said in (what its solutions are called, how a
mirrored case and a dropped case are marked, what each case is), in a module that imports
nothing: ``posecbr casebase list`` and ``info`` say them without loading the classifier,
its search index or SciPy. :mod:`cbr.explain`, :mod:`cbr.maintenance` and :mod:`cbr.stored`
re-export them where they were defined before."""

from __future__ import annotations

MIRRORED = " (mirrored)"
"""How a case that is another's mirror image is marked after its label."""

DROPPED = ": dropped"
"""How the maintenance log's entry of each case a trim dropped ends (after the editor's name);
the trim itself is one entry more."""

CASE_KINDS = {"clips": "clip", "repetitions": "repetition", "windows": "window"}
"""What one case is, by ``train --split``: the plural stored, the singular said."""


def class_noun(target: str | None, n: int = 1) -> str:
    """What a case base's solutions are called, ``n`` of them: activities when it predicts the
    activity label (``target`` "label" or None), classes when it predicts another column
    (``correct``: correct and incorrect repetitions are no activities)."""
    if target in (None, "label"):
        return "activity" if n == 1 else "activities"
    return "class" if n == 1 else "classes"
