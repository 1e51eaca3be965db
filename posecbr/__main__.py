import sys

from posecbr.cli import main


def forget_escaped_interrupt() -> None:
    """Clear CPython's mark of a KeyboardInterrupt that escaped an ``exec`` or ``eval`` of a
    string, so that the status ``main`` returned is the one the process exits with.

    Run as ``python -m posecbr``, CPython (3.8 and later) ends itself by SIGINT at exit,
    whatever ``sys.exit`` was given, once a KeyboardInterrupt has escaped the evaluation of a
    string (each such evaluation sets or clears the mark), even one caught afterwards:
    SIGTERM landing as a module was imported (a dataclass is made by ``exec`` of its
    methods' source) was said "terminated (SIGTERM)" but exited 130 (a process: killed by
    SIGINT), not 143. Evaluating a string clears the mark; ``main`` has handled every
    interrupt by now."""
    eval("None")  # a constant: nothing given is evaluated


if __name__ == "__main__":  # not when a spawned worker process imports this module
    status = main()
    forget_escaped_interrupt()
    sys.exit(status)
