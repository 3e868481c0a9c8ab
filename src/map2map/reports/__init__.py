"""Reports people read: self-contained HTML pages with a Markdown twin.

:mod:`map2map.reports.document` builds a report (warnings on top, ordered sections of
paragraphs, key numbers, tables and figures) and writes ``PATH.html`` (one file,
figures embedded, opens offline, prints cleanly to PDF) and ``PATH.md`` (for diffs,
figures as PNG files in ``PATH_files/``). :mod:`map2map.reports.inspection` is the
as-built inspection report of ``map2map evaluate --report``.

The package sits above ``learn`` and below ``demo`` in the data flow: a report may
show the result of any stage.

Examples
--------
>>> from map2map.reports import Report
>>> r = Report("Inspection")
>>> r.section("Summary").numbers({"mean error": "1.2 cm"})
"""

from .document import Report, Section

__all__ = ["Report", "Section"]
