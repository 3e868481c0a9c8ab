"""map2map.reports.document: the self-contained HTML page and its Markdown twin."""

from __future__ import annotations

import base64
import datetime as dt
import re

import cv2
import numpy as np
import pytest

from map2map.reports import Report


def _report() -> Report:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    when = dt.datetime(2026, 1, 2, 3, 4, tzinfo=dt.UTC)
    r = Report("Floor <2>", "as-built & planned", created=when)
    r.warn("The alignment is <ambiguous>.")
    r.warn("The alignment is <ambiguous>.")  # said once
    s = r.section("Key numbers")
    s.numbers({"mean error": "1.2 cm", "p95 error": "3.4 cm"})
    s.text("First <b>paragraph</b>.\n\nSecond paragraph.")
    s.note("skipped: ../shared/data absent")
    t = r.section("Walls | table")
    t.table(["id", "length (m)", "status"], [[1, 2.5, "pass"], [2, 3.25, "fail"]], caption="Walls")
    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, 1])
    f = r.section("Figures")
    f.figure(fig, "a line", alt="a diagonal line")
    plt.close(fig)
    grey = np.tile(np.arange(32, dtype=np.uint8) * 8, (16, 1))
    f.figure(grey, "a grey ramp")
    rgb = np.zeros((8, 12, 3), np.uint8)
    rgb[..., 0] = 255
    f.figure(rgb, "red")
    return r


def test_html_is_self_contained_escaped_and_checks_its_figures(tmp_path):
    html_path, md_path = _report().write(tmp_path / "rep.html")
    assert (html_path.name, md_path.name) == ("rep.html", "rep.md")
    page = html_path.read_text(encoding="utf-8")
    # nothing external: no src/href to anything but data: URIs and in-page anchors
    for ref in re.findall(r'(?:src|href)="([^"]*)"', page):
        assert ref.startswith(("data:image/png;base64,", "#")), ref
    assert "<link" not in page and "@import" not in page
    assert "&lt;b&gt;paragraph&lt;/b&gt;" in page and "<b>paragraph" not in page
    assert "Floor &lt;2&gt;" in page
    assert page.count("The alignment is &lt;ambiguous&gt;.") == 1
    assert page.index('class="warnings"') < page.index('id="key-numbers"')
    assert re.findall(r'<section id="([^"]+)"', page) == ["key-numbers", "walls-table", "figures"]
    assert page.count("<figure><img") == 3 and page.count("<figcaption>") == 3
    assert 'alt="a diagonal line"' in page
    assert "document.body.dataset.figures" in page and "naturalWidth" in page
    assert "@media print" in page and "break-inside:avoid" in page
    assert "2026-01-02 03:04 UTC" in page and "map2map" in page.split("<footer>")[1]
    # every embedded image decodes to the picture it was given
    data = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", page)
    imgs = [base64.b64decode(d) for d in data]
    decoded = [cv2.imdecode(np.frombuffer(b, np.uint8), cv2.IMREAD_UNCHANGED) for b in imgs]
    assert all(d is not None for d in decoded)
    assert decoded[1].shape == (16, 32) and decoded[1][0, 5] == 40
    assert decoded[2].shape == (8, 12, 3) and tuple(decoded[2][0, 0]) == (0, 0, 255)  # BGR red


def test_markdown_twin_has_same_content_and_linked_pngs(tmp_path):
    r = _report()
    _, md_path = r.write(tmp_path / "rep")
    md = md_path.read_text(encoding="utf-8")
    assert md.startswith("# Floor <2>\n\nas-built & planned\n")
    assert "> **Warning:** The alignment is <ambiguous>." in md
    assert "| id | length (m) | status |\n|---:|---:|---|\n| 1 | 2.5 | pass |" in md
    assert "## Walls | table" in md
    assert "| mean error | **1.2 cm** |" in md and "*skipped: ../shared/data absent*" in md
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    assert links == [f"rep_files/figure-0{i}.png" for i in (1, 2, 3)]
    for link in links:
        assert (tmp_path / link).read_bytes().startswith(b"\x89PNG")
    assert "2026" not in md  # no date in the twin: diffs stay clean
    # deterministic: a second report of the same content gives the same bytes
    _, md2 = _report().write(tmp_path / "again")
    assert md2.read_text().replace("again_files", "rep_files") == md
    for i in (1, 2, 3):
        name = f"figure-0{i}.png"
        again = (tmp_path / "again_files" / name).read_bytes()
        assert again == (tmp_path / "rep_files" / name).read_bytes()


def test_write_is_atomic_and_replaces_old_figures(tmp_path):
    r = _report()
    r.write(tmp_path / "rep")
    (tmp_path / "rep_files" / "stale.png").write_bytes(b"x")
    r.write(tmp_path / "rep")
    assert sorted(p.name for p in (tmp_path / "rep_files").iterdir()) == [
        "figure-01.png",
        "figure-02.png",
        "figure-03.png",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep.html", "rep.md", "rep_files"]


def test_bad_inputs_are_refused():
    s = Report("x").section("s")
    with pytest.raises(ValueError, match="row 0 has 1 cells, expected 2"):
        s.table(["a", "b"], [[1]])
    with pytest.raises(ValueError, match="not a PNG"):
        s.figure(b"GIF89a", "x")
    with pytest.raises(ValueError, match="uint8"):
        s.figure(np.zeros((4, 4)), "x")
    with pytest.raises(TypeError, match="matplotlib Figure"):
        s.figure("picture.png", "x")


def test_numbers_formatted_as_strings_are_right_aligned():
    r = Report("x")
    r.section("s").table(
        ["id", "dev (cm)", "seen", "status"],
        [[1, "12.50", "83%", "pass"], [2, "-", "100%", "not observed"]],
    )
    md = r.to_markdown()[0]
    assert "|---:|---:|---:|---|" in md
    assert '<td class="num">12.50</td>' in r.to_html()


def test_anchors_are_unique():
    r = Report("x")
    assert [r.section(t).anchor for t in ("Walls", "walls", "", "Été 2")] == [
        "walls",
        "walls-2",
        "section",
        "t-2",
    ]
