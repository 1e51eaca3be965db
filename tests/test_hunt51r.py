"""Hunt 51r: a review of the session's changes. A HEIF grid whose layout item holds bytes
after its fields was read as a picture millions of pixels high."""

from __future__ import annotations

from features.pose_estimation.containers import _grid_layout


def test_a_heif_grid_layout_is_read_from_its_fields_alone() -> None:
    """ISO/IEC 23008-12 ImageGrid: version 0, flags (bit 0: 32-bit sizes), rows - 1,
    columns - 1, output width, output height. An iPhone's 4032x3024 photo: 6 rows, 8 columns
    of 512x512 tiles. Bytes after the fields (a writer's padding) are no part of the height:
    two zero bytes more made it 3024 * 65536, and the photo was refused as a part."""
    layout16 = bytes([0, 0, 5, 7]) + (4032).to_bytes(2, "big") + (3024).to_bytes(2, "big")
    layout32 = bytes([0, 1, 5, 7]) + (4032).to_bytes(4, "big") + (3024).to_bytes(4, "big")
    for layout in (layout16, layout32):
        assert _grid_layout(layout) == (6, 8, 4032, 3024)
        assert _grid_layout(layout + b"\0\0") == (6, 8, 4032, 3024)
    assert _grid_layout(layout16[:7]) is None
    assert _grid_layout(layout32[:11]) is None
