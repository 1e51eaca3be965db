"""The store's refusals: :class:`StoreError` and the kinds of it a caller tells apart."""

from __future__ import annotations

from features.errors import PosecbrError


class StoreError(PosecbrError):
    """The case base store cannot be opened, read or written (names the database)."""


class NotADatabase(StoreError):
    """A file that is no SQLite database; ``looks_like``: what it looks like it is (a pose
    file, a picture, ...), or None. The store does not know where its path came from: the
    command line says which option takes the case base (:meth:`taken_by`)."""

    def __init__(self, looks_like: str | None, where: str) -> None:
        self.looks_like = looks_like
        super().__init__(
            f"not a readable SQLite database ({looks_like or 'corrupt or not a database'})", where
        )

    def taken_by(self, option: str) -> NotADatabase:
        """The same refusal saying that ``option`` takes the case base file (the file given
        to it looks like something else: the two files swapped); itself when it looks like
        nothing known."""
        if self.looks_like is None or self.source is None:
            return self
        said = NotADatabase(f"{self.looks_like}: {option} takes the case base file", self.source)
        said.looks_like = self.looks_like
        return said


class EmptyStore(StoreError):
    """A database without a case base store in it yet (``open_store`` without ``create``): the
    first write creates one."""


class InterruptedWrite(StoreError):
    """A SQLite file whose last writer was killed inside a transaction: its ``-journal``
    holds what to undo, which a command that only reads does not write
    (:func:`casebase_store.journals.roll_back_interrupted` does)."""


class CaseBaseGone(StoreError):
    """The case base read earlier was replaced or deleted by another process since: nothing
    was written into what took its place, and what was written into it is gone with it."""


class StaleCaseError(StoreError):
    """A case read earlier is no longer as it was (deleted, moved to another case base, or
    trimmed by another process): nothing was written; reload and decide again."""
