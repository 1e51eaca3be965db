"""posecbr: interpretable human activity recognition with qualitative posture features and CBR."""

import sys

try:
    import resource
except ImportError:  # not POSIX (Windows): no file size limit
    resource = None  # type: ignore[assignment]

if resource is not None and resource.getrlimit(resource.RLIMIT_FSIZE)[0] != resource.RLIM_INFINITY:
    # Under a file size limit (`ulimit -f`) no module's compiled .pyc is written: Python 3.11
    # writes one in a single write(2) and takes a short one, cut at the limit, for the whole,
    # and every later import of the module, in any process, failed ("marshal data too short")
    sys.dont_write_bytecode = True

from features.version import __version__  # noqa: E402 - after the limit's check

__all__ = ["__version__"]
