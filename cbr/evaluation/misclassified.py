"""Misclassified clips explained in words: by the best case-base configuration (refitted on
the clip's training fold) and by DAD (what it saw, QMP by QMP)."""

from __future__ import annotations

import numpy as np

from features.progress import progress

from .compare import CompareRun
from .methods import Method, make_estimator
from .results import ExplainedClip, Scores


def pick_wrong(data_y: np.ndarray, correct: list[bool], n: int) -> list[int]:
    """Up to ``n`` clips that were got wrong: one per true class first (in dataset order),
    then any."""
    wrong = [i for i, ok in enumerate(correct) if not ok]
    picked: list[int] = []
    seen: set[str] = set()
    for i in wrong:
        if str(data_y[i]) not in seen:
            picked.append(i)
            seen.add(str(data_y[i]))
    return (picked + [i for i in wrong if i not in picked])[: max(0, n)]


def _training_clips(run: CompareRun, i: int) -> np.ndarray:
    """The clips clip ``i``'s model was trained on: its fold's others (in its group)."""
    data, folds = run.data, run.folds
    train = np.flatnonzero(folds != folds[i])
    if data.within is not None:
        train = train[data.within[train] == data.within[i]]
    return train


def explain_errors(run: CompareRun, n: int) -> list[ExplainedClip]:
    """Explanations of up to ``n`` clips the best case-base configuration got wrong (one per
    true class first), from a model refitted on that clip's training fold."""
    best = run.results.best_cbr()
    if best is None or n <= 0:
        return []
    m, scores = best
    data = run.data
    method = Method(m.name, m.kind, True, m.params)
    picked = pick_wrong(data.y, scores.correct, n)
    out = []
    for i in progress(picked, "explanations", total=len(picked), unit="clip"):
        train = _training_clips(run, i)
        if len(set(data.y[train])) < 2:
            continue
        est = make_estimator(method).fit([data.seqs[j] for j in train], data.y[train])
        # the column it predicts names the labels' words (a correct / an incorrect repetition)
        est.target_ = str(run.results.settings["target"])
        exp = est.explain([data.seqs[i]])[0]
        out.append(_entry(run, i, scores, m.name, exp.text, exp.to_dict()))
    return out


def _entry(
    run: CompareRun,
    i: int,
    scores: Scores,
    method: str,
    text: str,
    explanation: dict[str, object] | None = None,
) -> ExplainedClip:
    data = run.data
    return ExplainedClip(
        clip=data.ids[i],
        subject=data.subjects[i],
        activity=str(data.labels[i]),
        true=str(data.y[i]),
        predicted=scores.predictions[i],
        method=method,
        text=text,
        explanation=explanation,
        frames=data.frames_of(i),
    )


def explain_dad_errors(run: CompareRun, n: int) -> list[ExplainedClip]:
    """For up to ``n`` clips DAD got wrong (one per true class first): what DAD saw for the
    activity it chose and for the true one, QMP by QMP, from :func:`cbr.dad.detect`."""
    dad = next((ms for ms in run.results.scored() if ms[0].kind == "dad"), None)
    if dad is None or n <= 0:
        return []
    from features.qmp.add import load_add

    from ..dad import detect

    data = run.data
    add = load_add()
    picked = pick_wrong(data.y, dad[1].correct, n)
    out = []
    for i in progress(picked, "DAD explanations", total=len(picked), unit="clip"):
        res = detect(data.seqs[i], add)
        true, pred = str(data.y[i]), dad[1].predictions[i]
        if res.status != "ok":
            text = f"DAD could not judge the clip: {res.message}"
        else:
            chosen, wanted = res.activity_for(pred), res.activity_for(true)
            if chosen is not None and np.isfinite(chosen.score):
                text = f"DAD chose {chosen.in_words()}."
            else:  # no class had an activity scored: DADClassifier answers the first class
                best = res.best
                text = (
                    "DAD scored no activity standing for a class compared"
                    + (f" (its best match, {best.words}, stands for none)" if best else "")
                    + f", so it answered the first class, {pred}."
                )
            text += (
                f"\nThe true activity: {wanted.in_words()}."
                if wanted
                else f"\nThe ADD has no activity for {true}."
            )
        out.append(_entry(run, i, dad[1], "dad", text))
    return out
