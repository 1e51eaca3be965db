"""Hunt 37g: what a person sees in the pictures and overlays of the long-recording commands
(``segment --plot``, ``reps --plot``, ``segment --overlay``, ``watch --out``, ``extract
--overlay``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.moves import clip


@pytest.mark.parametrize(("width", "height"), [(640, 480), (1920, 1080), (720, 1280)])
def test_overlay_text_outline_lies_around_its_letters(width: int, height: int) -> None:
    """The overlays wrote a word twice with OpenCV's font, a black outline 4 pixels thick and
    the white letters 1 pixel thick over it; that font advances its letters further the
    thicker the stroke, so the white letters fell behind the outline letter by letter:
    "repetitions: 1" read as a smudge, the white "1" some 17 pixels short of its outline at
    1920x1080. Now the outline is drawn around the letters: on the line of "repetitions: 1"
    the black reaches only a few pixels beyond the white on either side."""
    from features.pose_estimation.overlay import draw_pose

    frame = np.full((height, width, 3), 128, dtype=np.uint8)
    draw_pose(frame, np.full((33, 5), np.nan), ["repetitions: 1"])  # "no person" first
    scale = max(0.6, min(width, height) / 600)
    base1, base2 = 30 * scale, 60 * scale  # the baselines of the two lines
    rows = slice(int(base1 + 0.4 * (base2 - base1)), int(base2 + 0.35 * (base2 - base1)))
    line = frame[rows].astype(int).sum(axis=2)
    dark = np.flatnonzero((line < 3 * 40).any(axis=0))
    light = np.flatnonzero((line > 3 * 215).any(axis=0))
    assert dark.size and light.size
    stroke = max(1, round(19 * scale / 10))  # the outline's width
    assert 0 <= dark.max() - light.max() <= stroke + 2, (dark.max(), light.max())
    assert 0 <= light.min() - dark.min() <= stroke + 2, (dark.min(), light.min())
    assert frame[:, :, 0].shape == (height, width)  # drawn in place, nothing outside


def _band_colours(monkeypatch: pytest.MonkeyPatch, draw: object) -> list[list[tuple]]:
    """Calls ``draw()`` and gives, per band strip drawn, each band's (text, RGB) in order."""
    import features.timeline as timeline

    strips: list[list[tuple]] = []
    real = timeline._draw_bands

    def recording(ax: object, bands: object, *args: object) -> object:
        placed = real(ax, bands, *args)  # type: ignore[arg-type]
        spans = [p for p in ax.patches]  # type: ignore[attr-defined]
        strips.append(
            [(b.text, tuple(round(c, 3) for c in s.get_facecolor()[:3])) for s, (_, b) in
             zip(spans, placed, strict=True)]
        )  # fmt: skip
        return placed

    monkeypatch.setattr(timeline, "_draw_bands", recording)
    draw()  # type: ignore[operator]
    return strips


def _segmented(labels: list[str | None], fps: float = 10.0) -> object:
    """A segment result of 2-s segments labelled ``labels`` (None: unknown), one repetition
    each, as ``segment --plot`` reads it."""
    from types import SimpleNamespace

    segments = [
        SimpleNamespace(
            start_frame=20 * i, end_frame=20 * (i + 1), label=label,
            explanation="unlike every activity", repetitions=[object()],
        )
        for i, label in enumerate(labels)
    ]  # fmt: skip
    return SimpleNamespace(fps=fps, segments=segments, n_frames=20 * len(labels))


def test_an_activity_has_one_colour_in_every_timeline_of_a_case_base(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``segment --plot`` numbered the activities of each picture among themselves: of two
    recordings segmented by one case base, jumping jacks were tab10's first colour beside
    squats and its second beside incline push-ups. Now each activity takes its place among
    the case base's activities: jumping_jack, third of four, is tab10's third colour in
    both pictures, squat the fourth, and unknown stays light grey."""
    from posecbr.commands import segment

    rec = clip("squat", seconds=8.0, fps=10.0)
    activities = ["glute_bridge", "incline_pushup", "jumping_jack", "squat"]
    first = _segmented(["jumping_jack", "squat", None, "squat"])
    second = _segmented(["incline_pushup", "jumping_jack", "jumping_jack", None])
    strips = _band_colours(
        monkeypatch,
        lambda: [
            segment._plot(rec, first, tmp_path / "a.png", Path("a"), activities),
            segment._plot(rec, second, tmp_path / "b.png", Path("b"), activities),
        ],
    )
    tab10 = [tuple(round(c, 3) for c in TAB10[i]) for i in range(4)]
    grey = (0.8, 0.8, 0.8)
    assert [c for _, c in strips[0]] == [tab10[2], tab10[3], grey, tab10[3]]
    assert [c for _, c in strips[1]] == [tab10[1], tab10[2], tab10[2], grey]
    assert [t for t, _ in strips[1]] == ["incline_pushup x1", "jumping_jack x1",
                                         "jumping_jack x1", "unknown x1"]  # fmt: skip


def test_no_activity_is_drawn_in_the_grey_of_unknown(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The eighth activity of a picture took tab10's eighth colour, a mid grey, next to the
    light grey of unknown stretches: twelve activities (CMU's exercises) in one timeline,
    and none of their bands is grey (red, green and blue within 0.05 of one another); the
    twelve are twelve colours."""
    from features.timeline import Band, plot_timeline

    rec = clip("squat", seconds=12.0, fps=10.0)
    names = [f"activity {k:02d}" for k in range(12)]
    bands = [Band(k, k + 1, name, name) for k, name in enumerate(names)]
    strips = _band_colours(monkeypatch, lambda: plot_timeline(rec, tmp_path / "t.png", bands=bands))
    colours = [c for _, c in strips[0]]
    assert all(max(c) - min(c) > 0.05 for c in colours), colours
    assert len(set(colours)) == 12


TAB10 = [
    (0.12156862745098039, 0.4666666666666667, 0.7058823529411765),
    (1.0, 0.4980392156862745, 0.054901960784313725),
    (0.17254901960784313, 0.6274509803921569, 0.17254901960784313),
    (0.8392156862745098, 0.15294117647058825, 0.1568627450980392),
]
"""matplotlib's tab10, its first four colours (#1f77b4, #ff7f0e, #2ca02c, #d62728)."""


@pytest.mark.parametrize("with_bands", [True, False])
def test_a_long_title_stays_within_the_picture(tmp_path: Path, with_bands: bool) -> None:
    """``segment --plot`` titles a picture with the recording's name and what it shows; a
    name of 70-odd characters ran the title off the right edge ("...(grey = u"). Now the
    title is broken into lines: no dark pixel lies within 8 pixels of the picture's left or
    right edge, where before the title's letters ran to it."""
    from PIL import Image

    from features.timeline import Band, plot_timeline

    rec = clip("squat", seconds=4.0, fps=10.0)
    name = "subject13_trial31_warmup_session_recorded_in_the_lab_on_a_tuesday_morning.npz"
    title = f"{name}: activities and repetition counts over the fluent timeline (grey = unknown)"
    bands = [Band(0.0, 2.0, "squat x1", "squat"), Band(2.0, 4.0, "unknown x1")]
    path = plot_timeline(rec, tmp_path / "t.png", title=title, bands=bands if with_bands else ())
    image = np.asarray(Image.open(path).convert("L"), dtype=int)
    edges = np.concatenate([image[:, :8], image[:, -8:]], axis=1)
    assert edges.min() > 200, np.argwhere(edges <= 200)[:5]


def _drawn_title(monkeypatch: pytest.MonkeyPatch, draw: object) -> tuple[str, list[str]]:
    """Calls ``draw()`` (one timeline picture) and gives its title, on one line, and the
    colours of its row labels, as the figure is saved."""
    import matplotlib.colors as mcolors
    from matplotlib.figure import Figure

    seen: list[tuple[str, list[str]]] = []
    real = Figure.savefig

    def saving(fig: Figure, *args: object, **kwargs: object) -> object:
        titles = [a.get_title() for a in fig.axes if a.get_title()]
        colours = [mcolors.to_hex(t.get_color()) for a in fig.axes for t in a.get_yticklabels()]
        seen.append((titles[0].replace("\n", " "), colours))
        return real(fig, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Figure, "savefig", saving)
    draw()  # type: ignore[operator]
    return seen[0]


def test_a_titled_timeline_says_what_its_orange_labels_and_grey_mean(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``reps --plot`` (and ``describe --plot``, titled with the clip's name) drew the rows of
    motion states with orange labels and unknown stretches grey, and only the untitled
    picture said what orange and grey mean. The squat's timeline, titled as ``reps`` titles
    it, has orange row labels (#b35900), and its title says "orange labels = motion" and
    "grey = unknown"."""
    from posecbr.commands import reps

    rec = clip("squat", seconds=6.0, fps=30.0)
    result = reps._count(rec)
    assert result.count >= 2
    title, colours = _drawn_title(
        monkeypatch, lambda: reps._plot(rec, result, tmp_path / "r.png", Path("squat.npz"))
    )
    assert "#b35900" in colours
    assert title.startswith("squat.npz: ")
    assert "orange labels = motion" in title and "grey = unknown" in title, title


def test_reps_plot_marks_each_far_point_where_reps_json_puts_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``reps`` gives each repetition's start, far point and end, and ``--plot`` drew the
    starts and ends only. Now a triangle marks each far point in the repetitions' strip: one
    per repetition, at ``peak_frame / fps`` of the ``--json`` output, each within its band;
    the title says what the triangle is."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    from posecbr.commands import reps

    rec = clip("squat", seconds=6.0, fps=30.0)
    result = reps._count(rec)
    doc = result.to_dict()["repetitions"]
    assert len(doc) >= 2
    marks: list[np.ndarray] = []
    titles: list[str] = []
    real = Figure.savefig

    def saving(fig: Figure, *args: object, **kwargs: object) -> object:
        for a in fig.axes:
            marks.extend(
                np.asarray(line.get_xdata(), dtype=float)
                for line in a.get_lines()
                if isinstance(line, Line2D) and line.get_marker() == "^"
            )
            titles.append(a.get_title())
        return real(fig, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Figure, "savefig", saving)
    reps._plot(rec, result, tmp_path / "r.png", Path("squat.npz"))
    drawn = np.sort(np.concatenate(marks)) if marks else np.array([])
    expected = np.array([r["peak_frame"] / 30.0 for r in doc])
    np.testing.assert_allclose(drawn, expected)
    for x, r in zip(drawn, doc, strict=True):
        assert r["start_frame"] / 30.0 <= x < r["end_frame"] / 30.0
    assert any("\u25b2 far point" in t for t in titles), titles


def _strip_drawn(monkeypatch: pytest.MonkeyPatch) -> dict[str, object]:
    """What the next picture saved draws in its top axes, filled in as it is saved: its
    legend's (text, swatch colour) pairs (None without one), its bands' colours and how many
    of its texts are hidden."""
    import matplotlib.colors as mcolors
    from matplotlib.figure import Figure

    seen: dict[str, object] = {}
    real = Figure.savefig

    def saving(fig: Figure, *args: object, **kwargs: object) -> object:
        top = fig.axes[0]
        legend = top.get_legend()
        seen["legend"] = (
            None
            if legend is None
            else [
                (t.get_text(), mcolors.to_hex(h.get_facecolor(), keep_alpha=False))
                for t, h in zip(legend.get_texts(), legend.legend_handles, strict=True)
            ]
        )
        seen["bands"] = [mcolors.to_hex(p.get_facecolor(), keep_alpha=False) for p in top.patches]
        seen["hidden"] = sum(not t.get_visible() for t in top.texts)
        return real(fig, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Figure, "savefig", saving)
    return seen


def test_a_long_recordings_timeline_names_the_colours_its_bands_cannot(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``segment --plot`` of a long recording: each segment's band too narrow for its name
    (2 s of 120), so the strip was bands of colour with nothing saying which activity a
    colour is. Now a legend beside the strip names each activity drawn, in the case base's
    order, its swatch the colour of that activity's bands; unknown (grey) is not in it."""
    from posecbr.commands import segment

    rec = clip("squat", seconds=120.0, fps=10.0)
    activities = ["glute_bridge", "incline_pushup", "jumping_jack", "squat"]
    drawn = ["squat", "jumping_jack", None, "incline_pushup"] * 15
    seen = _strip_drawn(monkeypatch)
    segment._plot(rec, _segmented(drawn), tmp_path / "t.png", Path("long.npz"), activities)
    assert seen["hidden"] == 60  # 2 s of 120 in about 900 pixels: no name fits
    colour_of = dict(zip(drawn, seen["bands"], strict=True))  # type: ignore[call-overload]
    assert seen["legend"] == [
        (name, colour_of[name]) for name in ("incline_pushup", "jumping_jack", "squat")
    ]


def test_reps_plot_of_alternating_sides_names_the_side_of_each_colour(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``reps`` of jogging: the repetitions alternate sides, and ``--plot`` coloured each
    band by its side, blue and orange, without saying which is which. Now a legend names
    them: "left" and "right", each swatch the colour of the bands of the repetitions
    ``reps --json`` gives that side."""
    from posecbr.commands import reps

    rec = clip("jog", seconds=8.0, fps=30.0)
    result = reps._count(rec)
    sides = [r["side"] for r in result.to_dict()["repetitions"]]
    assert set(sides) == {"left", "right"}
    seen = _strip_drawn(monkeypatch)
    reps._plot(rec, result, tmp_path / "r.png", Path("jog.npz"))
    colour_of = dict(zip(sides, seen["bands"], strict=True))  # type: ignore[call-overload]
    assert colour_of["left"] != colour_of["right"]
    assert seen["legend"] == [("left", colour_of["left"]), ("right", colour_of["right"])]
