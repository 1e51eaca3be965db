"""Which of a dataset's class names an ADD activity stands for.

An ADD lists, for every activity, the dataset labels it stands for ("squat", "jumping_jack");
datasets spell the same names their own way (CMU's "Squat", "Jumping Jack", "jumping-jack").
A name is matched as a user reads it: ignoring case, spaces, underscores and hyphens
(:func:`label_key`). Two class names of one dataset that read the same, or one activity that
stands for two of its classes, leave DAD no way to tell which class it recognised: refused.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence

from features.errors import InputError
from features.qmp.add import ADD

_SEPARATORS = re.compile(r"[\s_\-]+")

MATCHING = "names are matched ignoring case, spaces, underscores and hyphens"


def label_key(name: object) -> str:
    """``name`` as DAD matches it: casefolded, without spaces, underscores or hyphens
    ("Jumping Jack", "jumping_jack" and "JUMPING-JACK" are all "jumpingjack")."""
    return _SEPARATORS.sub("", str(name)).casefold()


def stands_for(labels: Iterable[str], name: object) -> bool:
    """Whether an activity with these ADD ``labels`` stands for the class ``name``."""
    key = label_key(name)
    return any(label_key(lab) == key for lab in labels)


def class_of_activity(add: ADD, classes: Sequence[object]) -> dict[str, int]:
    """For every ADD activity that stands for one of ``classes``, the index of that class.

    Refused (:class:`InputError`, on ``y``) when two classes read the same to an activity
    ("Squat" and "squat" where the ADD has "squat"), or one activity stands for two classes
    (its labels "jumping_jack" and "jumpingjack" against classes "Jumping Jack" and
    "JumpingJack" read the same; "kickLFront1Reps" and another alias of it would not)."""
    by_key: dict[str, list[int]] = {}
    for i, c in enumerate(classes):
        by_key.setdefault(label_key(c), []).append(i)
    out: dict[str, int] = {}
    for act in add.activities.values():
        hits = sorted({i for lab in act.labels for i in by_key.get(label_key(lab), [])})
        if len(hits) > 1:
            names = " and ".join(repr(str(classes[i])) for i in hits)
            raise InputError(
                f"the classes {names} are one ADD activity to DAD ({act.name}, labels "
                f"{', '.join(act.labels)}; {MATCHING}): it cannot tell them apart",
                "y",
            )
        if hits:
            out[act.name] = hits[0]
    return out
