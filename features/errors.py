"""Errors a user can cause: every layer raises them, the `posecbr` command prints them as one
line naming the file and exits non-zero."""

from __future__ import annotations

from pathlib import Path


class PosecbrError(Exception):
    """A problem with the user's input or environment, reported as one clear line.

    ``source`` names the file (or database, or parameter) the problem is about.
    """

    def __init__(self, message: str, source: str | Path | None = None) -> None:
        self.message = message
        self.source = str(source) if source is not None else None
        super().__init__(f"{self.source}: {message}" if self.source else message)

    def named(self, source: str | Path) -> None:
        """Name ``source`` instead (the file a hidden temporary named was written for)."""
        self.source = str(source)
        self.args = (f"{self.source}: {self.message}",)

    def add(self, more: str) -> None:
        """Say ``more`` after the message (what the command had done before the error)."""
        self.message = f"{self.message}; {more}"
        self.args = (f"{self.source}: {self.message}" if self.source else self.message,)


class PoseFileError(PosecbrError):
    """A pose file is missing, truncated, malformed or of an unknown skeleton."""


class DataError(PosecbrError):
    """Input data (a dataset folder, a labels CSV, a motion capture file) cannot be used."""


class ConfigError(PosecbrError):
    """A configuration or data table (thresholds, ADD) is malformed."""


class ParameterError(ConfigError, ValueError):
    """A parameter of an estimator it cannot use (``k=0``, ``trim=2``, an unknown
    similarity): a :class:`ConfigError` for the command line, and the ``ValueError``
    scikit-learn's estimators raise for one, which its users catch."""


class InputError(DataError, ValueError):
    """Arguments of a Python call (an estimator's ``X`` or ``y``) of the wrong kind: a
    :class:`DataError` for the command line, and the ``ValueError`` scikit-learn users catch."""
