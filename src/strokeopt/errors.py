"""The exceptions strokeopt raises on purpose.

Every error a user can cause says where (file and field) and what to change.
The command line turns these into one line on stderr and exit code 2; anything
else escaping is a bug in strokeopt.
"""

from __future__ import annotations


class StrokeoptError(Exception):
    """Base class of the errors a user can cause or act on."""


class ProblemError(StrokeoptError, ValueError):
    """Bad input: a problem file, a catalogue file, an option or a `--set` override.

    ``str(err)`` is ``"<file>: <field>: <message>"``.
    """

    def __init__(self, file: str, field: str, message: str):
        self.file = str(file)
        self.field = field
        self.message = message
        super().__init__(f"{self.file}: {field}: {message}" if field else f"{self.file}: {message}")


class SolverError(StrokeoptError, RuntimeError):
    """A solve or an integration that did not succeed.

    ``reason`` says which constraint or limit is to blame; ``partial`` carries
    whatever result was reached (or None).
    """

    def __init__(self, reason: str, partial=None):
        self.reason = reason
        self.partial = partial
        super().__init__(reason)


class LimitError(SolverError):
    """A design that cannot meet a limit: ``reason`` names it and by how much (one line per limit);
    ``excess`` is the worst limit's relative excess (0.1: 10 % over) and ``short`` its one-line form --
    what a catalogue search ranks and names its motors by."""

    def __init__(self, reason: str, excess: float, short: str, partial=None):
        super().__init__(reason, partial)
        self.excess = float(excess)
        self.short = short


class AccuracyUnreachable(LimitError):
    """The most accurate stroke a design finds (``min_handover_error``) still breaks the handover accuracy:
    ``least_error`` [m] is its error (the design's exact term at its solution)."""

    def __init__(self, reason: str, excess: float, short: str, least_error: float):
        super().__init__(reason, excess, short)
        self.least_error = float(least_error)
