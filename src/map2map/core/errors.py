"""Errors that reach the user as one clear line.

Library functions raise :class:`InputError` for bad input (a file that is missing,
corrupt or inconsistent, a parameter out of range). The command line prints
``map2map: error: <file>: <problem>`` and exits with status 2, without a traceback
(``--debug`` shows it).

Messages name the library's parameters, not command-line options: a parameter is
written in backquotes, `` `resolution` ``, or with a value, `` `max_pixels=4000000` ``;
the command line prints it as its option (``--resolution``, ``--max-pixels 4000000``).
"""

from __future__ import annotations

import contextlib
import os
import warnings

__all__ = ["InputError", "MapWarning", "EXIT_BAD_INPUT", "warnings_unless_error"]

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


class MapWarning(UserWarning):
    """A result the program is not sure of (e.g. a degenerate map read from a file).

    Library functions issue it with :func:`warnings.warn`; the command line prints
    it as one line ``map2map: warning: <file>: <problem>`` on stderr.
    """


@contextlib.contextmanager
def warnings_unless_error():
    """Hold the warnings issued inside the block; issue them only if it succeeds.

    Reading a map and then refusing it would otherwise say two things (a warning
    that the map looks degenerate, then the error): the error alone is the one line.

    Examples
    --------
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     try:
    ...         with warnings_unless_error():
    ...             warnings.warn("odd map", MapWarning)
    ...             raise InputError("m.png", "no free space")
    ...     except InputError:
    ...         pass
    >>> len(seen)
    0
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
