"""posecbr: interpretable human activity recognition with qualitative posture features and CBR."""

__version__ = "0.1.0"
