"""Hang guard for the fuzz suites: a SIGALRM deadline around one call (main thread, POSIX)."""

import contextlib
import signal


@contextlib.contextmanager
def time_limit(seconds: int, what: str = "the call"):
    """Raise TimeoutError if the body runs longer than ``seconds`` (a hang is a failure)."""

    def _alarm(signum, frame):
        raise TimeoutError(f"{what} did not finish within {seconds} s")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
