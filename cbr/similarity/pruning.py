"""How well a search's lower bound has been pruning, shared by the queries of one index: whether
the next query should compute it (:mod:`cbr.similarity.euclidean`)."""

from __future__ import annotations

import numpy as np

FALLBACK = 0.5  # candidate share above which the pruned search turns into the plain pass


PROBE_EVERY = 16  # an index that stopped pruning tries the bound again every this many queries


class PruningRecord:
    """How well a bound has been pruning: ``pruning`` = [running share of the cases it let
    through, queries seen], a heuristic shared by the queries of one index (races between
    threads only change a speed decision)."""

    pruning: np.ndarray

    def worth_it(self) -> bool:
        """Whether the next query should compute the bound (see the module docstring)."""
        share, seen = self.pruning
        return bool(seen == 0 or share <= FALLBACK or seen % PROBE_EVERY == 0)

    def record(self, share: float) -> None:
        old, seen = self.pruning
        self.pruning[0] = share if seen == 0 else 0.7 * old + 0.3 * share
        self.pruning[1] = seen + 1

    def skip(self) -> None:
        self.pruning[1] += 1
