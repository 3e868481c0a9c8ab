"""Generated (CAD, SLAM) pairs for tests and the provisional weights.

Until ``map2map dataset build`` provides the real datasets (simulated exploration with a
SLAM backend, thesis sec. 4.1), :func:`make_pairs` makes aligned pairs in seconds from
the project's own pieces: ``A`` a generated floor plan (:func:`map2map.maps.generate_floorplan`,
apartments and offices), ``B`` the parametric model's SLAM map of it
(:func:`map2map.parametric.pipeline.deform`, additive method, a random tour through the
plan: odometry drift, lidar noise, unobserved areas unknown). Both are cropped to the
plan's content with the same window and preprocessed the thesis's way
(:func:`map2map.maps.preprocess`: square, resize, plan walls thickened), so they stay
aligned pixel for pixel; each plan is in one split only.

Examples
--------
>>> pairs = make_pairs(3, size=64, seed=0, progress=False)
>>> pairs.a.shape, sorted(set(pairs.split.tolist())), pairs.meta["generator"]
((3, 64, 64), ['test', 'train', 'val'], 'map2map.learn.training.synthetic.make_pairs')
"""

from __future__ import annotations

import numpy as np
from tqdm.auto import tqdm

from ...datasets.packed import PackedPairs
from ...maps.floorplan import generate_floorplan
from ...maps.preprocess import preprocess

__all__ = ["make_pairs", "make_pair"]


def make_pair(seed: int, size: int = 256, thicken: int = 1, tour: int = 5,
              kind: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One aligned (plan, SLAM-model) pair of ``size x size`` uint8 maps from ``seed``.

    Examples
    --------
    >>> a, b = make_pair(1, size=32)
    >>> a.shape == b.shape == (32, 32)
    True
    """
    from ...parametric.params import ParametricParams
    from ...parametric.pipeline import deform, make_trajectory

    rng = np.random.default_rng(seed)
    kind = kind or ("office" if rng.random() < 0.25 else "apartment")
    plan = generate_floorplan(int(rng.integers(2**31)), kind=kind)
    params = ParametricParams()
    traj, _ = make_trajectory(plan, params, rng, tour=tour)
    slam = deform(plan, traj, rng=rng).map
    r0, r1, c0, c1 = plan.content_bbox()
    m = 4
    window = (r0 - m, r1 + m, c0 - m, c1 + m)
    a = preprocess(plan.crop(*window), size, thicken=thicken)
    b = preprocess(slam.crop(*window), size)
    return a.data, b.data


def make_pairs(n: int, size: int = 256, seed: int = 0, *, thicken: int = 1,
               fractions: tuple[float, float] = (0.1, 0.1), progress: bool = True
               ) -> PackedPairs:
    """``n`` pairs from ``n`` plans (seeds ``seed .. seed + n - 1``), split by plan.

    ``fractions`` are the (val, test) shares (at least one plan each when ``n >= 3``);
    ``meta`` records the call so the dataset can be rebuilt exactly.
    """
    a = np.empty((n, size, size), np.uint8)
    b = np.empty_like(a)
    for i in tqdm(range(n), desc="pairs", disable=not progress):
        a[i], b[i] = make_pair(seed + i, size, thicken)
    n_val = max(1 if n >= 3 else 0, round(fractions[0] * n))
    n_test = max(1 if n >= 3 else 0, round(fractions[1] * n))
    split = np.array(["train"] * (n - n_val - n_test) + ["val"] * n_val + ["test"] * n_test)
    order = np.random.default_rng(seed).permutation(n)
    split = split[np.argsort(order)]
    plan_id = np.array([f"synthetic-{seed + i}" for i in range(n)])
    meta = {"generator": "map2map.learn.training.synthetic.make_pairs", "n": n, "size": size,
            "seed": seed, "thicken": thicken}
    return PackedPairs(a, b, plan_id, split, meta)
