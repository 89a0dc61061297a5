"""User-facing errors.

Every problem caused by the user's input (a file, a parameter, a command-line
value) is raised as :class:`InputError`.  The command-line interface turns it
into one line on stderr and exit status 2; library callers can catch it.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["InputError"]


class InputError(ValueError):
    """Bad user input, reported as ``<source>: <problem>``.

    Parameters
    ----------
    source : str or path-like or None
        The file (or option) the problem was found in.
    problem : str
        What is wrong, in one line.
    """

    def __init__(self, source: str | Path | None, problem: str):
        self.source = None if source is None else str(source)
        self.problem = " ".join(str(problem).split())
        super().__init__(self.one_line())

    def one_line(self) -> str:
        """The message as printed by the CLI (a single line)."""
        if self.source:
            return f"{self.source}: {self.problem}"
        return self.problem
