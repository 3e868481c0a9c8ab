"""map2map reproduce: the report's structure, end to end (the real --quick) and when a
section fails."""

from __future__ import annotations

import base64
import json
import math
import os
import re
import subprocess
import sys
from html import escape as html_escape
from pathlib import Path

import cv2
import numpy as np
import pytest

from map2map.reports.reproduce import EXIT_SECTION_FAILED, SECTIONS, reproduce
from map2map.reports.reproduce import table2 as table2_module

ROOT = Path(__file__).resolve().parents[1]


def _titles() -> list[str]:
    from importlib import import_module

    return [import_module(f"map2map.reports.reproduce.{m}").TITLE for m in SECTIONS.values()]


def _check_report(out: Path, expect_sections: list[str]) -> dict:
    """Every section present, every image embedded and decodable, every number finite."""
    html = (out / "report.html").read_text(encoding="utf-8")
    md = (out / "report.md").read_text(encoding="utf-8")
    for title in expect_sections:
        assert title in md, title
        assert html_escape(title) in html, title
    assert "Summary: thesis vs map2map" in md and "About this run" in md
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert images, "no figure embedded"
    assert len(re.findall(r"<img\s", html)) == len(images)  # no external image
    for b64 in images:
        img = cv2.imdecode(np.frombuffer(base64.b64decode(b64), np.uint8), cv2.IMREAD_COLOR)
        assert img is not None and img.shape[0] > 10 and img.shape[1] > 10
    linked = re.findall(r"\]\((report_files/[^)]+\.png)\)", md)
    assert len(linked) == len(images)
    for rel in linked:
        assert cv2.imread(str(out / rel)) is not None, rel

    def no_nan(text):
        raise AssertionError(f"non-finite number in results.json: {text}")

    results = json.loads((out / "results.json").read_text(), parse_constant=no_nan)

    def walk(v):
        if isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, list):
            for x in v:
                walk(x)
        elif isinstance(v, float):
            assert math.isfinite(v)

    walk(results)
    return results


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory) -> tuple[Path, subprocess.CompletedProcess]:
    """The real ``map2map reproduce --quick``, once, through the command line."""
    out = tmp_path_factory.mktemp("reproduce") / "report"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "OMP_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-m", "map2map", "reproduce", "--out", str(out),
                           "--quick"], capture_output=True, text=True, env=env, timeout=900,
                          cwd=ROOT)  # fmt: skip
    return out, proc


@pytest.mark.slow
def test_quick_end_to_end(quick_report):
    out, proc = quick_report
    assert proc.returncode == 0, proc.stdout + proc.stderr
    # progress: one line per section on stderr, the summary on stdout
    assert proc.stderr.count("] ok in") + proc.stderr.count("] skipped in") == len(SECTIONS)
    assert "wrote" in proc.stdout
    results = _check_report(out, _titles())
    assert results["mode"] == "quick"
    assert set(results["sections"]) == set(SECTIONS)
    for key, sec in results["sections"].items():
        assert sec["status"] in ("ok", "skipped"), (key, sec["message"])
    # the numbers the report is about are there and plausible
    pt = results["sections"]["parametric_time"]["results"]["run_time"]
    assert {"ekf_64", "ekf_256", "additive_256", "additive_1600"} <= set(pt)
    t2 = results["sections"]["table2"]["results"]
    assert len(t2["cases"]) == 6
    assert t2["worst_abs_max_px"] < 3.0  # the metric finds the known errors
    ds = results["sections"]["dataset"]["results"]
    assert ds["pairs"] >= 1 and ds["pairs_per_hour_per_core"] > 0


@pytest.mark.slow
def test_quick_report_in_a_browser(quick_report, request, tmp_path):
    """Rendered by a real headless chromium: every figure loaded, key numbers visible."""
    browser = pytest.importorskip("browser", reason="tests/browser.py not available")
    try:
        chromium = request.getfixturevalue("chromium")  # skips (or fails in CI) without it
    except pytest.FixtureLookupError:
        pytest.skip("no chromium fixture (tests/conftest.py)")
    out, proc = quick_report
    assert proc.returncode == 0, proc.stderr
    page = browser.render(out / "report.html", tmp_path, browser=chromium)
    total = len(re.findall(r"<img\s", (out / "report.html").read_text()))
    assert total > 0 and page.figures == f"{total}/{total}"
    text = page.text
    for title in _titles():
        assert title in text, title
    results = json.loads((out / "results.json").read_text())
    ekf64 = results["sections"]["parametric_time"]["results"]["run_time"]["ekf_64"]["wall_s"]
    assert f"{ekf64:.2f} s" in text  # a key number of the report is on the page
    assert "15-94 s" in text and "About this run" in text
    assert page.screenshot.stat().st_size > 10_000


def test_failed_section_keeps_the_report(tmp_path, monkeypatch):
    def boom(ctx, out):
        out.text("started")
        raise RuntimeError("the alignment exploded")

    monkeypatch.setattr(table2_module, "run", boom)
    s = reproduce(tmp_path / "r", sections=["fig515", "table2"], tiny=True, progress=False)
    assert s.exit_code == EXIT_SECTION_FAILED == 1
    assert [(r.key, r.status) for r in s.sections] == [("fig515", "ok"), ("table2", "failed")]
    md = (tmp_path / "r" / "report.md").read_text()
    assert "This section failed: RuntimeError: the alignment exploded" in md
    assert "failed: RuntimeError: the alignment exploded" in md.split("## ")[0] or \
        "failed: RuntimeError" in (tmp_path / "r" / "report.html").read_text()
    results = _check_report(tmp_path / "r", [_titles()[1], table2_module.TITLE])
    assert "traceback" in results["sections"]["table2"]["results"]
    assert results["sections"]["fig515"]["results"]["key_poses"] > 0


def test_halmstad_skipped_without_data(tmp_path):
    (tmp_path / "empty").mkdir()
    s = reproduce(tmp_path / "r", sections=["halmstad"], tiny=True, progress=False,
                  data=tmp_path / "empty")  # fmt: skip
    assert s.exit_code == 0 and s.sections[0].status == "skipped"
    assert "skipped: the Halmstad maps" in (tmp_path / "r" / "report.md").read_text()


def test_cli_rejects_unknown_section(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run([sys.executable, "-m", "map2map", "reproduce", "--out",
                           str(tmp_path / "r"), "--only", "table9"], capture_output=True,
                          text=True, env=env)  # fmt: skip
    assert proc.returncode == 2
    assert "unknown section table9" in proc.stderr and "Traceback" not in proc.stderr
    proc = subprocess.run([sys.executable, "-m", "map2map", "reproduce", "--out",
                           str(tmp_path / "r"), "--data", str(tmp_path / "nowhere")],
                          capture_output=True, text=True, env=env)  # fmt: skip
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "nowhere: the real data folder (--data) does not exist" in proc.stderr
    assert not (tmp_path / "r").exists()  # nothing written
