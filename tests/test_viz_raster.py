"""Raster figures (map2map.core.viz_raster): geometry lands where the image coordinates say."""

from __future__ import annotations

import sys

import cv2
import numpy as np

from map2map.core.viz_raster import Panel, map_to_rgb, save_panels


def _white(h=40, w=60):
    return np.ones((h, w, 3))


def _red(img):
    return (img[:, :, 0] > 150) & (img[:, :, 1] < 100) & (img[:, :, 2] < 100)


def test_small_images_are_enlarged_by_a_whole_factor_and_lines_follow_pixel_centres():
    p = Panel(_white(), size=540)
    assert p.sx == p.sy == 9  # 540 / 60
    p.line([10.0, 10.0], [5.0, 50.0], colour=(1.0, 0.0, 0.0), width=1)
    rows, cols = np.nonzero(_red(p.finish()))
    # pixel centre of row 10 is at panel y = (10 + 0.5) * 9 = 94.5
    assert rows.min() >= 93 and rows.max() <= 96
    assert abs(cols.min() - 5.5 * 9) <= 2 and abs(cols.max() - 50.5 * 9) <= 2


def test_dashed_lines_have_gaps_and_nan_breaks_a_line():
    p = Panel(_white(), size=540)
    p.line([10.0, 10.0], [5.0, 50.0], colour=(1.0, 0.0, 0.0), width=1, dashed=True)
    on = _red(p.finish())[94]
    span = on[int(5.5 * 9) : int(50.5 * 9)]
    assert 0.4 < span.mean() < 0.9  # dashes and gaps
    q = Panel(_white(), size=540)
    q.line([10.0, 10.0, 10.0, 10.0], [5.0, 20.0, np.nan, 50.0], colour=(1, 0, 0), width=1)
    red = _red(q.finish())
    assert red[:, : int(20.5 * 9) + 2].any() and not red[:, int(21 * 9) :].any()


def test_large_images_are_reduced_and_markers_land_on_their_pixel():
    p = Panel(_white(400, 1200), size=600)
    assert p.image.shape[:2] == (200, 600)
    p.markers([100.0], [300.0], colour=(1.0, 0.0, 0.0), size=8)
    rows, cols = np.nonzero(_red(p.finish()))
    assert abs(rows.mean() - 100.5 / 2) < 1 and abs(cols.mean() - 300.5 / 2) < 1


def test_save_panels_writes_a_png_with_every_panel_scale_bar_and_legend(tmp_path):
    data = np.full((50, 80), 255, np.uint8)
    data[:, :2] = 0
    a = Panel(map_to_rgb(data), title="map", resolution=0.05)
    a.legend([("path", (0.0, 0.6, 0.0), "-"), ("hit", (1.0, 0.0, 0.0), "x")])
    b = Panel(_white(50, 80), title="other")
    path = tmp_path / "f.png"
    save_panels([a, b], path, title="two panels")
    img = cv2.imread(str(path))
    assert img.shape[1] == 12 + 2 * (a.image.shape[1] + 12)
    assert img.shape[0] > a.image.shape[0] + 30  # titles above
    # the scale bar (black, 3 px thick, lower left) and the legend (upper right) are drawn
    panel = a.image
    h = panel.shape[0]
    assert (panel[h - 40 :, 30:200] < 30).all(axis=2).sum() > 100
    assert (np.abs(panel[:60, -150:].astype(int) - 255).sum(axis=2) > 60).sum() > 50
    assert not list(tmp_path.glob(".*"))  # no temporary left


def test_importing_it_does_not_import_matplotlib():
    import os
    import subprocess
    from pathlib import Path

    import map2map

    src = str(Path(map2map.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    code = "import map2map.core.viz_raster, sys; print('matplotlib' in sys.modules)"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    )
    assert out.stdout.strip() == "False"
