"""hunt32g: the maintenance editors and a case's mirror image (``--mirror augment``).

Each editor judged a case with its own mirror image among its neighbours (the same movement
on the other side, near and of its activity): a case looked redundant, covered or not noisy
because of its reflection; and a case could be dropped while its image was kept. Now each
case is judged without its image, and a case and its image are kept or dropped together.

The tiny case bases are one feature on a line (Euclidean distance = the difference), each
clip ``x.npz`` frames 0-10 and its image ``x.npz (mirrored)``, so every distance is read off
the positions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cbr.casebase import CaseBase
from cbr.maintenance import cnn, icf, mirror_twins, novelty_benefit, renn, trim_novelty_benefit
from cbr.problem import FeatureConfig
from cbr.similarity import Euclidean

DEMO = Path(__file__).resolve().parents[1] / "posecbr" / "demo_data" / "uiprmd"


def _cb(cases: list[tuple[str, float, str]]) -> CaseBase:
    """``(clip name, position, label)`` per case; a name ending ' (mirrored)' is an image."""
    names = tuple(n for n, _, _ in cases)
    return CaseBase(
        FeatureConfig(),
        Euclidean(exact=True),
        np.array([[x] for _, x, _ in cases], dtype=float),
        np.array([lab for _, _, lab in cases], dtype=object),
        ("x",),
        ("x",),
        sources=names,
        frames=((0, 10),) * len(cases),
    )


def _pair(name: str, x: float, image: float, label: str) -> list[tuple[str, float, str]]:
    return [(f"{name}.npz", x, label), (f"{name}.npz (mirrored)", image, label)]


# ---- novelty-benefit ---------------------------------------------------------------------


def _three_clips() -> CaseBase:
    # clip A far from the others (its image 0.2 away); clips B and C 1 apart
    return _cb(
        _pair("A", 0.0, 0.2, "a") + _pair("B", 10.0, 12.0, "a") + _pair("C", 11.0, 13.0, "a")
    )


def test_novelty_and_benefit_are_judged_without_the_case_s_own_image() -> None:
    cb = _three_clips()
    nov, ben = novelty_benefit(cb, k=1)
    # nearest case of the activity, the image aside: A 10 (B), A' 9.8 (B), B 1 (C),
    # B' 1 (C or C'), C 1 (B), C' 1 (B'); median 1. (With the image: A and A' 0.2.)
    np.testing.assert_allclose(nov, [10.0, 9.8, 1.0, 1.0, 1.0, 1.0])
    # each case's nearest, the image aside (ties: the earlier case): A -> B, A' -> B,
    # B -> C, B' -> C (1, before C'), C -> B (1, before B'), C' -> B'. Coverage: B 3, C 2,
    # B' 1. (With the image, A and A' covered each other: 1 each.)
    np.testing.assert_allclose(ben, [0, 0, 3, 1, 2, 0])


def test_novelty_benefit_keeps_the_far_clip_and_keeps_pairs_together() -> None:
    cb = _three_clips()
    r = trim_novelty_benefit(cb, keep=0.5, k=1)
    # combined ranks (novelty rank + benefit rank, ascending, ties mean):
    # A 6+2=8, A' 5+2=7, B 2.5+6=8.5, B' 2.5+4=6.5, C 2.5+5=7.5, C' 2.5+2=4.5;
    # pairs: A 7.5, B 7.5, C 6; ceil(0.5 x 3) = 2 pairs kept: A and B. Before, A and A'
    # (0.2 apart) looked least novel and went, with C': the one clip far from the others was
    # lost, and B's image kept without C's.
    np.testing.assert_array_equal(r.kept, [True, True, True, True, False, False])
    assert r.size_after == 4


# ---- RENN and ICF -------------------------------------------------------------------------


def _mislabelled(label: str = "a") -> CaseBase:
    # activity a at 0-1.1, activity b at 10-10.3; clip N (10.7, image 10.8) among b's
    return _cb(
        _pair("A1", 0.0, 0.1, "a")
        + _pair("A2", 1.0, 1.1, "a")
        + _pair("B1", 10.0, 10.1, "b")
        + _pair("B2", 10.2, 10.3, "b")
        + _pair("N", 10.7, 10.8, label)
    )


def test_renn_drops_a_case_its_own_image_alone_voted_for() -> None:
    # 1-NN, the image aside: N -> B2' (0.4), N' -> B2' (0.5), both b: wrong, the pair goes.
    # Every other case's nearest other clip is of its activity (B1 -> B2 0.2, B2' -> B1'
    # 0.2, A1 -> A2 1, ...). Before, N's nearest was N' (0.1) and N' N's: both "right", kept.
    r = renn(_mislabelled(), k=1)
    np.testing.assert_array_equal(r.kept, [True] * 8 + [False, False])
    assert r.summary().startswith("RENN: 10 -> 8 cases")


def test_icf_drops_the_noisy_pair_too() -> None:
    r = icf(_mislabelled(), k=1)
    assert not r.kept[8:].any()  # ICF begins with the ENN pass: N and N' go
    twins = mirror_twins(r.before) if r.before is not None else None
    assert twins is not None
    assert not (twins & (r.kept[:, None] != r.kept[None, :])).any()


def test_an_activity_lost_whole_keeps_its_medoid_with_its_image() -> None:
    # N, N' the only cases of c: RENN drops both; one of them (N, the first of equal sums)
    # is kept, and its image with it
    r = renn(_mislabelled("c"), k=1)
    np.testing.assert_array_equal(r.kept, [True] * 10)
    assert r.kept_alone == ("c",)
    assert r.summary().endswith(
        "; one case (and its mirror image) kept of 'c', every case of which the editor dropped"
    )


# ---- CNN ----------------------------------------------------------------------------------


def test_cnn_adds_a_case_with_its_image() -> None:
    cb = _cb(_pair("A", 0.0, 0.1, "a") + _pair("C", 4.0, 4.1, "a") + _pair("B", 10.0, 10.1, "b"))
    r = cnn(cb)
    # the first case of each activity starts the subset, and with it its image: A, A', B, B';
    # C (4 from A, 6 from B) and C' are then classified right and not added. Before: A and B
    # alone, their images dropped.
    np.testing.assert_array_equal(r.kept, [True, True, False, False, True, True])


# ---- without images nothing changes ---------------------------------------------------------


def test_a_case_base_without_images_is_edited_as_before() -> None:
    cb = _cb(
        [("A.npz", 0.0, "a"), ("A2.npz", 0.2, "a"), ("B.npz", 10.0, "a"), ("C.npz", 11.0, "a")]
    )
    nov, ben = novelty_benefit(cb, k=1)
    # nearest: 0.2, 0.2, 1, 1 (median 0.6); A -> A2, A2 -> A, B -> C, C -> B
    np.testing.assert_allclose(nov, [0.2 / 0.6, 0.2 / 0.6, 1 / 0.6, 1 / 0.6])
    np.testing.assert_allclose(ben, [1, 1, 1, 1])
    r = trim_novelty_benefit(cb, keep=0.5, k=1)
    np.testing.assert_array_equal(r.kept, [False, False, True, True])


# ---- real clips ---------------------------------------------------------------------------


def test_real_case_base_editors_keep_pairs_and_ignore_images(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from cbr import maintenance
    from cbr.estimator import CaseBaseClassifier
    from features.datasets import load_clip

    monkeypatch.setenv("POSECBR_NO_PROGRESS", "1")
    files = [f"m{m}_s0{s}_e0{e}.npz" for m in ("01", "07") for s in (1, 2) for e in (1, 2)]
    seqs = [load_clip(DEMO / f) for f in files]
    labels = ["squat" if f.startswith("m01") else "abduction" for f in files]
    clf = CaseBaseClassifier(k=1, mirror="augment").fit(seqs, labels)
    cb = clf.case_base_
    twins = mirror_twins(cb)
    assert len(cb) == 16 and twins.sum() == 16  # 8 clips, each with its image
    dist = maintenance.pairwise_distances(cb)
    # novelty: distance to the nearest case of the activity, its own image aside
    d = np.where(twins, np.inf, dist)
    np.fill_diagonal(d, np.inf)
    lab = cb.labels.astype(str)
    nearest = np.where(lab[:, None] == lab[None, :], d, np.inf).min(axis=1)
    want = np.empty(len(cb))
    for a in np.unique(lab):
        want[lab == a] = nearest[lab == a] / np.median(nearest[lab == a])
    nov, _ = novelty_benefit(cb, 1, dist)
    np.testing.assert_allclose(nov, want)
    for report in (
        trim_novelty_benefit(cb, 0.5, 1),
        cnn(cb),
        renn(cb, k=1),
        icf(cb, k=1),
    ):
        split = twins & (report.kept[:, None] != report.kept[None, :])
        assert not split.any(), report.method
