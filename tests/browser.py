"""Render an HTML report in a real headless browser, the way a person would open it.

Debian's ``chromium`` (CI installs it in ``.ci/run``) loads the page from ``file://``,
runs its scripts and lets its images decode (``--virtual-time-budget``: the page's
clock runs until it is idle or 10 s of page time have passed), then prints the DOM as
it stands (``--dump-dom``) or saves a screenshot (``--screenshot``). The reports of
:mod:`map2map.reports.document` record on ``load`` how many of their images decoded
(``<body data-figures="ok/total">``), so the dumped DOM says whether every figure
loaded. Each call gets its own throw-away profile (``--user-data-dir``) so that
parallel test workers do not share one.

Checked with Debian bookworm's chromium 156 (``--headless`` is the new headless mode;
``--no-sandbox`` because CI runs as root; ``--disable-dev-shm-usage`` for containers
with a small ``/dev/shm``).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-extensions",
    "--hide-scrollbars",
    "--virtual-time-budget=10000",
]


def find_chromium() -> str | None:
    """Path of a Chromium-family browser on the PATH, or None."""
    for name in NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


@dataclass
class Rendered:
    """What the browser made of a page: its DOM after load, and a screenshot."""

    dom: str
    screenshot: Path

    @property
    def figures(self) -> str | None:
        """``"ok/total"`` as the page's own check recorded it (None if the script did not run)."""
        m = re.search(r'<body[^>]*\sdata-figures="([^"]*)"', self.dom)
        return m.group(1) if m else None

    @property
    def text(self) -> str:
        """The visible text of the DOM, tags dropped, whitespace collapsed."""
        body = re.sub(r"(?is)<(script|style)\b.*?</\1>", " ", self.dom)
        body = re.sub(r"(?s)<[^>]+>", " ", body)
        import html

        return " ".join(html.unescape(body).split())


def _run(browser: str, args: list[str], profile: Path, timeout: float) -> str:
    cmd = [browser, *FLAGS, f"--user-data-dir={profile}", *args]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    if done.returncode != 0:
        tail = "\n".join(done.stderr.splitlines()[-15:])
        raise RuntimeError(f"{Path(browser).name} exited with {done.returncode}:\n{tail}")
    return done.stdout


def render(
    html: Path,
    out_dir: Path,
    *,
    browser: str | None = None,
    window: tuple[int, int] = (1280, 2400),
    timeout: float = 120.0,
) -> Rendered:
    """Load ``html`` in headless Chromium; return its DOM after load and a screenshot.

    Parameters
    ----------
    html : Path
        The page (opened as ``file://``).
    out_dir : Path
        Where the screenshot (``<page>.png``) and the throw-away profile go.
    browser : str, optional
        The browser executable (:func:`find_chromium` by default).
    window : (int, int)
        Window size of the screenshot, pixels.
    timeout : float
        Seconds allowed per browser run.
    """
    browser = browser or find_chromium()
    if browser is None:
        raise RuntimeError("no chromium found on the PATH")
    url = Path(html).resolve().as_uri()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    shot = out_dir / (Path(html).stem + ".png")
    with tempfile.TemporaryDirectory(prefix="profile-", dir=out_dir) as profile:
        dom = _run(browser, ["--dump-dom", url], Path(profile), timeout)
        _run(
            browser,
            [f"--window-size={window[0]},{window[1]}", f"--screenshot={shot}", url],
            Path(profile),
            timeout,
        )
    if not shot.is_file():
        raise RuntimeError(f"{Path(browser).name} wrote no screenshot {shot}")
    return Rendered(dom, shot)
