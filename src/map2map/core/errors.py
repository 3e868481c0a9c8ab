"""Errors that reach the user as one clear line.

Library functions raise :class:`InputError` for bad input (a file that is missing,
corrupt or inconsistent, a parameter out of range). The command line prints
``map2map: error: <file>: <problem>`` and exits with status 2, without a traceback
(``--debug`` shows it).
"""

from __future__ import annotations

import os

__all__ = ["InputError", "EXIT_BAD_INPUT"]

EXIT_BAD_INPUT = 2


class InputError(ValueError):
    """Bad input: names the file (or argument) and the problem.

    Examples
    --------
    >>> str(InputError("plan.yaml", "resolution must be > 0"))
    'plan.yaml: resolution must be > 0'
    """

    def __init__(self, source: str | os.PathLike | None, problem: str):
        self.source = None if source is None else os.fspath(source)
        self.problem = problem
        super().__init__(problem if self.source is None else f"{self.source}: {problem}")
