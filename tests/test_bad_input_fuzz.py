"""A short, deterministic run of the reader fuzzer (``tools/fuzz_readers.py``; the long runs
are outside the suite): every input is read or refused with one clear line, no traceback."""

from __future__ import annotations

import pytest

from tests.conftest import SHARED_DATA
from tools.fuzz_readers import TARGETS, fuzz


@pytest.mark.parametrize("reader", list(TARGETS))
def test_fuzzed_inputs_give_no_traceback(reader: str) -> None:
    if TARGETS[reader].needs_seeds and not SHARED_DATA.is_dir():
        pytest.skip(f"the {reader} seeds are cut from {SHARED_DATA}, not on this machine")
    stats = fuzz(reader, examples=40)
    assert stats.tried == 40
    assert stats.tracebacks == {}, next(iter(stats.tracebacks.values()))["traceback"]
    assert stats.refused > 0  # the mutations do reach the readers' checks
