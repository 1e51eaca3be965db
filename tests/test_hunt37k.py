"""Hunt 37k: the overlays' activity in its colour of ``segment --plot`` (unknown grey), and
every word inside a narrow frame."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

ACTIVITIES = ["glute_bridge", "incline_pushup", "jumping_jack", "squat"]
LONG = "standing_shoulder_internal_external_rotation"  # UI-PRMD's m09, 44 letters


def _tab10(i: int) -> tuple[int, int, int]:
    """matplotlib's tab10 colour i as RGB 0-255, worked out from matplotlib's own table."""
    import matplotlib

    r, g, b = matplotlib.colormaps["tab10"].colors[i]  # type: ignore[attr-defined]
    return round(255 * r), round(255 * g), round(255 * b)


GREY = (204, 204, 204)  # segment --plot's unknown bands: "0.8"


def _away() -> np.ndarray:
    """Landmarks of a person all off the frame: no bone drawn, no "no person" said."""
    lm = np.zeros((33, 5))
    lm[:, :2] = -1000.0
    lm[:, 3:] = 1.0
    return lm


def _label_box(frame: np.ndarray) -> tuple[tuple[int, int, int], np.ndarray]:
    """The commonest colour (RGB) in the middle of the first line's first letters in
    ``frame`` (BGR), and the rectangle of ``frame`` that colour spans around them (the box),
    which a black line surrounds."""
    h, w = frame.shape[:2]
    scale = max(0.6, min(h, w) / 600)
    core = frame[int(12 * scale) : int(26 * scale), 14:44]  # within "squat" or "unknown"
    colours, counts = np.unique(core.reshape(-1, 3), axis=0, return_counts=True)
    mode = colours[np.argmax(counts)]
    b, g, r = (int(v) for v in mode)
    assert (r, g, b) != tuple(int(v) for v in frame[0, -1]), "no box: the frame's own colour"
    line = frame[: int(40 * scale)]
    rows, cols = np.nonzero((line == mode).all(axis=2))
    top, bottom, left, right = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
    edge = np.concatenate([line[top - 1, left:right], line[bottom, left:right],
                           line[top:bottom, left - 1], line[top:bottom, right]])  # fmt: skip
    assert (edge == 0).all()  # edged in black: a light box keeps its shape on a light frame
    return (r, g, b), line[top:bottom, left:right]


def _contrast(a: tuple[int, int, int], b: tuple[int, int, int]) -> float:
    """WCAG's contrast ratio of two sRGB colours."""

    def lum(rgb: tuple[int, int, int]) -> float:
        c = np.asarray(rgb) / 255.0
        c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
        return float(c @ [0.2126, 0.7152, 0.0722])

    hi, lo = sorted((lum(a), lum(b)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def _segmented(labels: list[str | None]) -> object:
    """A segment result of 2-s segments at 10 fps labelled ``labels`` (None: unknown)."""
    segments = [
        SimpleNamespace(
            start_frame=20 * i, end_frame=20 * (i + 1), label=label,
            explanation="unlike every activity", repetitions=[],
        )
        for i, label in enumerate(labels)
    ]  # fmt: skip
    return SimpleNamespace(fps=10.0, segments=segments, n_frames=20 * len(labels))


def _assert_boxed(frame_of: object, expected: tuple[int, int, int]) -> None:
    """The label drawn by ``frame_of(background)`` lies on a box of ``expected`` on a dark
    and a light frame alike, its letters standing out from it (contrast at least 4.5)."""
    drawn = []
    for background in (15, 240):
        frame = frame_of(background)  # type: ignore[operator]
        colour, line = _label_box(frame)
        assert colour == expected, (background, colour, expected)
        drawn.append(line)
        ink = [tuple(int(v) for v in px[::-1]) for px in line.reshape(-1, 3)]
        assert max(_contrast(c, expected) for c in ink) >= 4.5
    assert np.array_equal(drawn[0], drawn[1])  # the box hides the frame: legible on both


def test_segment_overlay_boxes_each_activity_in_its_plot_colour() -> None:
    """``segment --overlay`` wrote every activity in white: an unknown stretch looked like
    any other. Now the activity lies on a box of its ``segment --plot`` colour, by its place
    among the case base's activities (jumping_jack third: tab10's green, squat fourth:
    tab10's red), unknown the plot's light grey, on a dark frame as on a light one."""
    from features.pose_estimation.overlay import draw_pose
    from posecbr.commands.segment import frame_words

    words = frame_words(_segmented(["jumping_jack", None, "squat"]), activities=ACTIVITIES)
    assert [words[f][0] for f in (5, 25, 45)] == ["jumping_jack", "unknown", "squat"]
    for f, expected in ((5, _tab10(2)), (25, GREY), (45, _tab10(3))):

        def frame_of(background: int, f: int = f) -> np.ndarray:
            frame = np.full((480, 640, 3), background, dtype=np.uint8)
            return draw_pose(frame, _away(), words[f])

        _assert_boxed(frame_of, expected)


def test_watch_out_boxes_the_activity_in_its_plot_colour(tmp_path: Path) -> None:
    """``watch --out`` (and ``--show``) draw the live label so too: squat, fourth of the case
    base's activities, on tab10's red; unknown on light grey."""
    from posecbr.commands.watch import Watcher

    clf = SimpleNamespace(classes_=np.array(ACTIVITIES))
    args = SimpleNamespace(out=tmp_path / "seen.mp4", show=False)
    watcher = Watcher(clf, None, args, 10.0)  # type: ignore[arg-type]
    written: list[np.ndarray] = []
    watcher._write = written.append  # type: ignore[method-assign]
    watcher._fluents = lambda top=3: []  # type: ignore[method-assign]
    for label, expected in (("squat", _tab10(3)), (None, GREY)):
        watcher.live = SimpleNamespace(
            current=lambda: SimpleNamespace(repetitions=2), label=label,
            nobody_in_view=False, nobody_reason="nobody in view",
        )  # fmt: skip

        def frame_of(background: int) -> np.ndarray:
            rgb = np.full((480, 640, 3), background, dtype=np.uint8)
            watcher._draw(SimpleNamespace(rgb=rgb, pose=SimpleNamespace(image=_away())))
            return written[-1]

        _assert_boxed(frame_of, expected)


@pytest.mark.parametrize(("width", "height"), [(160, 120), (240, 320), (48, 64)])
@pytest.mark.parametrize("boxed", [True, False])
def test_every_word_stays_inside_a_narrow_frame(
    width: int, height: int, boxed: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """UI-PRMD's 44-letter activity ran past the right edge of frames narrower than about
    260 pixels (at 240x320 the last letters of "rotation" were cut off). Now a word too wide
    is broken after its underscores (and spaces), and a piece still too wide written
    smaller: on a known background no pixel changes in the frame's last columns or rows,
    and the pieces drawn are the whole name, then the count; at 48 pixels a piece is cut
    short with "…". A line that would run past the foot of the frame is left out whole."""
    from features.pose_estimation import overlay
    from features.pose_estimation.overlay import draw_pose

    texts: list[str] = []
    real = overlay._write

    def recording(bgr: np.ndarray, text: str, org: tuple[int, int], scale: float) -> None:
        texts.append(text)
        real(bgr, text, org, scale)

    monkeypatch.setattr(overlay, "_write", recording)
    name = LONG
    if boxed:  # as segment --overlay and watch --out write the activity
        name = overlay.Label(LONG, _tab10(0))
    fluents = ["left arm raised sideways", "torso upright", "head tilted forward"]
    frame = np.full((height, width, 3), 90, dtype=np.uint8)
    draw_pose(frame, _away(), [name, "repetitions: 3", *fluents])
    changed = (frame != 90).any(axis=2)
    rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
    assert cols.max() < width - 2 and rows.max() < height - 1, (cols.max(), rows.max())
    if width >= 160:
        k = texts.index("repetitions: 3")
        assert "".join(texts[:k]) == LONG and k >= 2  # broken into lines, every letter drawn
        assert texts[k + 1 :] == fluents[: len(texts) - k - 1]
        assert all(isinstance(t, overlay.Label) == boxed for t in texts[:k])
    else:
        assert texts and all(t.endswith("…") or len(t) <= 9 for t in texts)
