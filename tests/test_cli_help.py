"""Every --help of the command line is written for a user: no internal history."""

from __future__ import annotations

import argparse
import re

from map2map.cli.main import build_parser

#: What internal history looks like in a sentence ("the default before session 11").
HISTORY = re.compile(r"\bsession \d|\bissue #?\d|#\d+\b|before session|since 20\d\d-|"
                     r"\bround \d|\bwas the default\b|\bold default\b", re.IGNORECASE)


def _helps(p: argparse.ArgumentParser, name: str = "map2map"):
    yield name, " ".join(p.format_help().split())
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            for sub, sp in a.choices.items():
                yield from _helps(sp, f"{name} {sub}")


def test_no_help_tells_internal_history():
    helps = dict(_helps(build_parser()))
    assert len(helps) > 20  # every command and action
    bad = {name: HISTORY.findall(text) for name, text in helps.items() if HISTORY.search(text)}
    assert not bad, bad


def test_the_history_pattern_catches_what_it_should():
    for text in ("the default before session 11", "fixed in issue #35", "since 2026-11-20",
                 "as of session 4"):
        assert HISTORY.search(text), text
    assert not HISTORY.search("Table 5.3, thesis sec. 4.1, 360 degrees, --count 6400")
