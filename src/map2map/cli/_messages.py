"""Library messages as the command line says them: a parameter the library names in
backquotes (:mod:`map2map.core.errors`) becomes the command's option."""

from __future__ import annotations

import re

__all__ = ["as_options"]

#: Library parameters whose command-line option has another name.
_OPTION_OF = {"everything": "--all"}

#: A parameter named in a library message: `name` or `name=value` (:mod:`map2map.core.errors`).
_PARAMETER = re.compile(r"`([a-z][a-z0-9_]*)(?:=([^`\s]+))?`")


def as_options(text: str) -> str:
    """A library message as the command line says it: `name` -> --name, `name=v` -> --name v.

    >>> as_options("pass `max_pixels=9` or a coarser `resolution`; `everything`")
    'pass --max-pixels 9 or a coarser --resolution; --all'
    """

    def option(m: re.Match) -> str:
        flag = _OPTION_OF.get(m[1], "--" + m[1].replace("_", "-"))
        return flag if m[2] is None else f"{flag} {m[2]}"

    return _PARAMETER.sub(option, text)
