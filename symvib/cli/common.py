"""What every ``symvib`` command shares: its exit statuses and its one-line error messages."""
from __future__ import annotations

__all__ = ["EXIT_BAD_INPUT", "EXIT_RUN_FAILED", "EXIT_FAILED_SCENES", "MAX_MESSAGE_LENGTH", "one_line"]

#: Exit status for bad input.
EXIT_BAD_INPUT = 2
#: Exit status of a run that ended with an error status (non_finite, energy_budget_mismatch).
EXIT_RUN_FAILED = 3
#: Exit status of ``symvib sweep`` when some scenes failed (their rows are written, with their
#: status): the status of ``symvib run`` for a failed run, one code for one meaning.
EXIT_FAILED_SCENES = EXIT_RUN_FAILED
#: Longest error message printed, in characters (a message may quote a long user text).
MAX_MESSAGE_LENGTH = 500


def one_line(message) -> str:
    """``message`` as one printable line of at most ``MAX_MESSAGE_LENGTH`` characters
    (control characters and line breaks escaped, the rest cut with ``...``)."""
    text = str(message)
    if not text.isprintable():
        text = "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)
    if len(text) > MAX_MESSAGE_LENGTH:
        text = text[:MAX_MESSAGE_LENGTH - 3] + "..."
    return text
