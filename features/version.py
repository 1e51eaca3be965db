"""The version of posecbr: the one place it is written (``pyproject.toml`` reads it from here).

It is stored with every case base (the code that built it), so it changes with every release
that changes what is computed; see CHANGELOG.md.
"""

__version__ = "0.2.0"
