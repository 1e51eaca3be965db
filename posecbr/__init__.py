"""posecbr: interpretable human activity recognition with qualitative posture features and CBR."""

from features.version import __version__

__all__ = ["__version__"]
