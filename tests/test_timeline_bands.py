"""The activity bands drawn above a timeline (features.timeline): each text stays within its
band, measured on the rendered figure."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from features.timeline import Band, _draw_bands, fit_texts  # noqa: E402


def test_band_texts_are_wrapped_or_hidden_to_stay_within_their_bands() -> None:
    """An 80-s strip 11 inches wide at 110 dpi (about 12 px a second): a 20-s band keeps its
    text on one line; a 3.5-s band (about 42 px) cannot hold "unknown x2" at 7 pt on one line
    and holds it on two; a 0.5-s band (6 px) is narrower than any of its words, so its text
    is hidden. Every text left visible lies within its band's pixels."""
    fig, ax = plt.subplots(figsize=(11, 1), dpi=110)
    try:
        ax.set_xlim(0, 80)
        bands = [Band(0, 20, "nobody in view x0"), Band(48.7, 52.2, "unknown x2", "a"),
                 Band(79.5, 80, "KneeRaise x2", "b")]  # fmt: skip
        placed = _draw_bands(ax, bands, "activity")
        fig.tight_layout()
        renderer = fig.canvas.get_renderer()
        one_line = [t.get_window_extent(renderer).width for t, _ in placed]
        fit_texts(ax, placed)
        wide, short, narrow = (t for t, _ in placed)
        assert wide.get_text() == "nobody in view x0" and wide.get_visible()
        band_px = [ax.transData.transform([(b.start_s, 0), (b.end_s, 0)])[:, 0] for b in bands]
        assert one_line[1] > band_px[1][1] - band_px[1][0]  # too wide on one line, so
        assert short.get_text() == "unknown\nx2" and short.get_visible()
        assert not narrow.get_visible()
        for (text, _), (left, right) in zip(placed, band_px, strict=True):
            if text.get_visible():
                box = text.get_window_extent(renderer)
                assert left - 0.5 <= box.x0 and box.x1 <= right + 0.5
    finally:
        plt.close(fig)
