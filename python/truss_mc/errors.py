"""The exceptions truss_mc raises: each carries the message the command-line tools print
(after ``BINARY: error:``) and the exit code they exit with, so a script can treat a failure
the same way whichever it called."""

from __future__ import annotations

from typing import Optional

__all__ = [
    "TrussError",
    "UsageError",
    "InvalidInputError",
    "TrussIOError",
    "VerificationError",
    "SolveFailedError",
]


class TrussError(Exception):
    """Base of every truss_mc error."""

    #: The exit code of the same failure in the command-line tools (crate truss-exit).
    exit_code: int = 1
    #: For an invalid job or prism: the JSON path of the fault (``cases[0].length_errors.x``).
    json_path: Optional[str] = None


class UsageError(TrussError, ValueError):
    """A case, sample, range, member or thread count that does not exist (exit code 2)."""

    exit_code = 2


class InvalidInputError(TrussError, ValueError):
    """An invalid job, prism or model file (exit code 3); ``json_path`` names the fault."""

    exit_code = 3


class TrussIOError(TrussError, OSError):
    """A file that could not be read (exit code 4)."""

    exit_code = 4


class VerificationError(TrussError):
    """Shard files that do not verify: damaged, incomplete, of two jobs, or overlapping
    with different lines (exit code 6)."""

    exit_code = 6


class SolveFailedError(TrussError):
    """A solve that did not converge (exit code 7)."""

    exit_code = 7
