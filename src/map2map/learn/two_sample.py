"""A classifier two-sample test of realism (issue #33): can a small CNN, shown a plan and a
SLAM map of it, tell a generated map from a simulated one on plans it never saw?

Per plan there are two maps, ``a`` (simulated, label 0) and ``b`` (label 1: generated, or
for the floor another simulated run). The plans are split into ``folds`` groups; for each
group a fresh CNN is trained on the other groups' plans and scores this group's maps
(cross-fitting: every map is scored by a network that never saw its plan). Training
shows both maps of a plan at the same random crop (``crop`` px; same flips and quarter
turns), so the network can only use how the map renders the plan, not which plans are in
which class. A map's score is the mean logit over a fixed grid of crops that hold plan
walls. The result is the ROC AUC over all maps (0.5: indistinguishable; 1: always told
apart) and the paired share of plans whose ``b`` scores above their ``a``.

The same test on two simulated runs (run 3 against run 2) is its floor: a generator
passes when its AUC is at most the floor + 0.05 (issue #33).

One seed's AUC is noisy: the seed draws the folds, the crops and the networks' weights.
On the 640 plans of the seed-20261201 set (600 steps), three seeds gave 0.681, 0.668 and
0.710 for one generator and 0.742, 0.745 and 0.665 for another, so one seed ranked them
the other way round; on 160 plans four seeds of one generator spread over 0.653-0.722
(docs/synthesize.md, "how far 160 plans go"). :func:`repeated_auc` runs several seeds and
reports their mean and standard deviation; compare generators by it. 600 steps is far
short of convergence: with 2000 the same two generators scored 0.869 and 0.841 (floor
0.499), and one seed of the first gave 0.681 / 0.778 / 0.839 / 0.934 at 600 / 1000 / 2000
/ 4000 steps while the floor stayed at 0.498 / 0.499 / 0.501 (600 / 2000 / 4000). The AUC
depends on the steps as much as on the maps: keep the steps fixed between the results
compared. Inputs are four channels:
the plan's walls and free space, the map's occupied and free cells (unknown is neither).

Deterministic per seed on CPU (same seed, same AUC): torch's deterministic algorithms,
seeded crops, one seeded network per fold.

Examples
--------
>>> rng = np.random.default_rng(0)
>>> plans = np.full((24, 64, 64), 255, np.uint8); plans[:, :, 30:32] = 0
>>> a = plans.copy(); b = plans.copy()
>>> b[:, :, 33:35] = 0                      # every b map saves the wall twice
>>> r = two_sample_auc(plans, a, b, crop=32, steps=60, seed=0)
>>> r.auc > 0.9
True
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass

import numpy as np

from ..core.grid import FREE, OCCUPIED

__all__ = ["ClassifierResult", "RepeatedAUC", "TellingCrops", "two_sample_auc", "repeated_auc",
           "telling_crops", "encode"]


@dataclass
class ClassifierResult:
    """:func:`two_sample_auc`'s result.

    Attributes
    ----------
    auc : float
        ROC AUC of the cross-fitted scores, every ``a`` map against every ``b`` map.
    paired : float
        Share of plans whose ``b`` map scores above its ``a`` map.
    plans, folds, steps, crop, seed : int
    seconds : float
        Wall time of the whole test.
    trained : tuple of int
        Per fold, the Adam steps of the network that scored it: ``steps`` each, or with
        early stopping (``patience``) the step of the lowest held-out loss.
    """

    auc: float
    paired: float
    plans: int
    folds: int
    steps: int
    crop: int
    seed: int
    seconds: float
    trained: tuple = ()

    def as_dict(self) -> dict:
        return asdict(self)


def encode(plans: np.ndarray, maps: np.ndarray) -> np.ndarray:
    """(N, 4, S, S) float32: plan walls, plan free, map occupied, map free.

    Examples
    --------
    >>> x = encode(np.array([[[0, 255]]], np.uint8), np.array([[[127, 0]]], np.uint8))
    >>> x[0, :, 0].tolist()
    [[1.0, 0.0], [0.0, 1.0], [0.0, 1.0], [0.0, 0.0]]
    """
    plans, maps = np.asarray(plans), np.asarray(maps)
    return np.stack([plans == OCCUPIED, plans == FREE, maps == OCCUPIED, maps == FREE],
                    axis=1).astype(np.float32)


def _net(width: int = 16):
    import torch.nn as nn

    w = width
    return nn.Sequential(
        nn.Conv2d(4, w, 4, stride=2, padding=1), nn.LeakyReLU(0.2),
        nn.Conv2d(w, 2 * w, 4, stride=2, padding=1), nn.LeakyReLU(0.2),
        nn.Conv2d(2 * w, 4 * w, 4, stride=2, padding=1), nn.LeakyReLU(0.2),
        nn.Conv2d(4 * w, 4 * w, 3, padding=1), nn.LeakyReLU(0.2),
        nn.AdaptiveAvgPool2d(1), nn.Flatten(), nn.Linear(4 * w, 1))


def _grid(plans: np.ndarray, crop: int) -> list[np.ndarray]:
    """Per plan: the top-left corners (y, x) of the scoring crops (half-overlapping grid,
    crops that hold a plan wall; the centre one if none does)."""
    s = plans.shape[-1]
    step = max(crop // 2, 1)
    starts = np.arange(0, max(s - crop, 0) + 1, step)
    yy, xx = np.meshgrid(starts, starts, indexing="ij")
    yy, xx = yy.ravel(), xx.ravel()
    walls = (plans == OCCUPIED).astype(np.int64)
    ii = np.pad(walls.cumsum(1).cumsum(2), ((0, 0), (1, 0), (1, 0)))
    n = (ii[:, yy + crop, xx + crop] - ii[:, yy, xx + crop] - ii[:, yy + crop, xx]
         + ii[:, yy, xx])
    out = []
    for row in n:
        keep = row > 0
        if not keep.any():
            c = (s - crop) // 2
            out.append(np.array([[c, c]]))
        else:
            out.append(np.stack([yy[keep], xx[keep]], 1))
    return out


@contextmanager
def _deterministic(threads: int):
    """torch's deterministic algorithms on ``threads`` CPU threads while the block runs
    (both restored after it)."""
    import torch

    prev = torch.are_deterministic_algorithms_enabled(), torch.get_num_threads()
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.use_deterministic_algorithms(prev[0])
        torch.set_num_threads(prev[1])


def _augment(x, k: int, flip: bool):
    import torch

    x = torch.rot90(x, k, dims=(-2, -1))
    return torch.flip(x, dims=(-1,)) if flip else x


def _val_loss(net, xa, xb, corners, idx, crop) -> float:
    """Binary cross-entropy of the map scores (mean logit over the scoring grid) of the
    plans ``idx``: their ``a`` maps labelled 0, their ``b`` maps 1."""
    sa, sb = _score(net, xa, corners, idx, crop), _score(net, xb, corners, idx, crop)
    # -log(1 - sigmoid(s)) = softplus(s); -log(sigmoid(s)) = softplus(-s)
    return float(np.mean(np.r_[np.logaddexp(0.0, sa), np.logaddexp(0.0, -sb)]))


def _train(xa, xb, corners, train_idx, *, crop, steps, batch, lr, seed, val_idx=None,
           patience=0, check_every=200):
    """The fold's network and the steps it was trained. With ``patience`` > 0 the held-out
    plans ``val_idx`` are scored every ``check_every`` steps and training stops after
    ``patience`` checks without a lower loss (or at ``steps``); the network of the lowest
    loss is returned."""
    import copy

    import torch

    torch.manual_seed(seed)
    net = _net()
    opt = torch.optim.Adam(net.parameters(), lr=lr, betas=(0.5, 0.999))
    lossf = torch.nn.BCEWithLogitsLoss()
    rng = np.random.default_rng(seed)
    y = torch.cat([torch.zeros(batch), torch.ones(batch)])
    best, best_step, best_state, waited = math.inf, steps, None, 0
    for step in range(1, steps + 1):
        pick = rng.choice(train_idx, batch)
        cs = []
        for i in pick:
            cy, cx = corners[i][rng.integers(len(corners[i]))]
            cy = int(np.clip(cy + rng.integers(-crop // 4, crop // 4 + 1), 0,
                             xa.shape[-1] - crop))
            cx = int(np.clip(cx + rng.integers(-crop // 4, crop // 4 + 1), 0,
                             xa.shape[-1] - crop))
            cs.append((i, cy, cx, int(rng.integers(4)), bool(rng.integers(2))))
        ba = torch.stack([_augment(xa[i, :, cy:cy + crop, cx:cx + crop], k, f)
                          for i, cy, cx, k, f in cs])
        bb = torch.stack([_augment(xb[i, :, cy:cy + crop, cx:cx + crop], k, f)
                          for i, cy, cx, k, f in cs])
        opt.zero_grad()
        loss = lossf(net(torch.cat([ba, bb])).squeeze(1), y)
        loss.backward()
        opt.step()
        if patience > 0 and (step % check_every == 0 or step == steps):
            net.eval()
            v = _val_loss(net, xa, xb, corners, val_idx, crop)
            net.train()
            if v < best:
                best, best_step, best_state, waited = v, step, copy.deepcopy(
                    net.state_dict()), 0
            else:
                waited += 1
                if waited >= patience:
                    break
    if best_state is not None:
        net.load_state_dict(best_state)
    return net, best_step


def _score(net, x, corners, idx, crop) -> np.ndarray:
    import torch

    out = np.empty(len(idx))
    with torch.no_grad():
        for j, i in enumerate(idx):
            c = torch.stack([x[i, :, cy:cy + crop, cx:cx + crop] for cy, cx in corners[i]])
            out[j] = float(net(c).mean())
    return out


def _auc(neg: np.ndarray, pos: np.ndarray) -> float:
    """ROC AUC by the Mann-Whitney U (ties count one half)."""
    from scipy.stats import rankdata

    r = rankdata(np.r_[neg, pos])
    n0, n1 = len(neg), len(pos)
    return float((r[n0:].sum() - n1 * (n1 + 1) / 2) / (n0 * n1))


def two_sample_auc(plans, a, b, *, folds: int = 2, crop: int = 64, steps: int = 600,
                   batch: int = 32, lr: float = 1e-3, seed: int = 0, threads: int = 1,
                   patience: int = 0, check_every: int = 200, val_share: float = 0.25
                   ) -> ClassifierResult:
    """Cross-fitted classifier two-sample test of maps ``b`` against maps ``a`` (module
    doc).

    Parameters
    ----------
    plans, a, b : (N, S, S) uint8
        Plan ``i``'s two maps are ``a[i]`` (label 0) and ``b[i]`` (label 1).
    folds : int
        Plan groups; each is scored by a network trained on the others.
    crop : int
        Crop side (px), at most ``S``.
    steps, batch, lr : int, int, float
        Adam steps per fold (with ``patience``: at most), plans per step (each gives an
        ``a`` and a ``b`` crop).
    seed : int
    threads : int
        torch CPU threads while it runs (default 1: the small convolutions gain little
        from more, and lose much when the cores are busy).
    patience, check_every, val_share : int, int, float
        Early stopping (``patience`` > 0; 0, the default: ``steps`` steps): each fold
        holds ``val_share`` of its training plans out, scores them every ``check_every``
        steps (cross-entropy of their maps' scores) and stops after ``patience`` checks
        without a lower loss; the network of the lowest loss scores the fold. The
        classifier then trains to convergence rather than for a budget (the module doc:
        the AUC depends on the budget).

    Returns
    -------
    ClassifierResult
    """
    import torch

    t0 = time.perf_counter()
    plans, a, b = (np.asarray(x) for x in (plans, a, b))
    n = len(plans)
    if not (len(a) == len(b) == n) or n < 2 * folds:
        raise ValueError(f"need as many a as b maps as plans, at least {2 * folds}: "
                         f"{len(a)}, {len(b)}, {n}")
    crop = min(crop, plans.shape[-1])
    with _deterministic(threads):
        xa, xb = torch.from_numpy(encode(plans, a)), torch.from_numpy(encode(plans, b))
        corners = _grid(plans, crop)
        group = np.random.default_rng(seed).permutation(n) % folds
        sa, sb = np.empty(n), np.empty(n)
        trained = []
        for f in range(folds):
            test, train = np.flatnonzero(group == f), np.flatnonzero(group != f)
            val = None
            if patience > 0:
                train = np.random.default_rng(seed * 1000 + f).permutation(train)
                k = max(1, int(round(val_share * len(train))))
                val, train = np.sort(train[:k]), np.sort(train[k:])
            net, used = _train(xa, xb, corners, train, crop=crop, steps=steps, batch=batch,
                               lr=lr, seed=seed * 1000 + f, val_idx=val, patience=patience,
                               check_every=check_every)
            trained.append(int(used))
            net.eval()
            sa[test] = _score(net, xa, corners, test, crop)
            sb[test] = _score(net, xb, corners, test, crop)
    auc = _auc(sa, sb)
    paired = float(np.mean(sb > sa)) if n else math.nan
    return ClassifierResult(auc, paired, n, folds, steps, crop, seed,
                            time.perf_counter() - t0, tuple(trained))


@dataclass
class RepeatedAUC:
    """:func:`repeated_auc`'s result: one :func:`two_sample_auc` per seed.

    Attributes
    ----------
    auc, sd : float
        Mean and standard deviation (``ddof=1``; 0 for one seed) of the seeds' AUCs.
    paired : float
        Mean of their paired shares.
    runs : list of ClassifierResult
        One per seed, in order.
    """

    auc: float
    sd: float
    paired: float
    runs: list

    def as_dict(self) -> dict:
        """``auc``, ``sd``, ``paired``, ``aucs`` (per seed), ``seeds``, ``plans``,
        ``folds``, ``steps``, ``crop`` and ``seconds`` (all seeds) as plain values."""
        r0 = self.runs[0]
        return {"auc": self.auc, "sd": self.sd, "paired": self.paired,
                "aucs": [r.auc for r in self.runs], "seeds": [r.seed for r in self.runs],
                "plans": r0.plans, "folds": r0.folds, "steps": r0.steps, "crop": r0.crop,
                "trained": [list(r.trained) for r in self.runs],
                "seconds": float(sum(r.seconds for r in self.runs))}

    def __str__(self) -> str:
        """``AUC mean +- sd (each seed's)``, as the benchmarks print it.

        Examples
        --------
        >>> r0 = ClassifierResult(0.7, 0.8, 10, 2, 60, 32, 0, 1.0)
        >>> str(RepeatedAUC(0.7, 0.0, 0.8, [r0]))
        'AUC 0.700 +- 0.000 (0.700)'
        """
        each = " ".join(f"{r.auc:.3f}" for r in self.runs)
        return f"AUC {self.auc:.3f} +- {self.sd:.3f} ({each})"


def repeated_auc(plans, a, b, seeds=(0, 1, 2), **kwargs) -> RepeatedAUC:
    """:func:`two_sample_auc` of ``b`` against ``a`` once per seed in ``seeds``, with the
    mean and standard deviation of the AUCs (module doc: one seed's AUC is noisy).

    Parameters
    ----------
    plans, a, b : (N, S, S) uint8
        As :func:`two_sample_auc`.
    seeds : sequence of int
        At least one.
    **kwargs
        :func:`two_sample_auc`'s other options (``folds``, ``crop``, ``steps``, ...).

    Returns
    -------
    RepeatedAUC

    Examples
    --------
    >>> plans = np.full((16, 48, 48), 255, np.uint8); plans[:, :, 22:24] = 0
    >>> b = plans.copy(); b[:, :, 25:27] = 0
    >>> r = repeated_auc(plans, plans, b, seeds=(0, 1), crop=32, steps=40)
    >>> [x.seed for x in r.runs], r.auc == float(np.mean([x.auc for x in r.runs]))
    ([0, 1], True)
    """
    seeds = [int(v) for v in seeds]
    if not seeds:
        raise ValueError("repeated_auc needs at least one seed")
    runs = [two_sample_auc(plans, a, b, seed=sd, **kwargs) for sd in seeds]
    aucs = np.array([r.auc for r in runs])
    sd = float(aucs.std(ddof=1)) if len(aucs) > 1 else 0.0
    return RepeatedAUC(float(aucs.mean()), sd, float(np.mean([r.paired for r in runs])), runs)


@dataclass
class TellingCrops:
    """:func:`telling_crops`'s result.

    Attributes
    ----------
    auc : float
        The network's ROC AUC on the held-out plans (map scores as :func:`two_sample_auc`).
    test : (T,) int array
        The held-out plans.
    crops : (K, 5) float array
        Every scoring crop of the held-out plans, most telling first: plan index, top-left
        row and column, the logit of its ``b`` crop minus its ``a`` crop's, and the ``b``
        crop's logit.
    saliency : (k, crop, crop) float32 array
        For the first ``top`` crops: the absolute gradient of the ``b`` crop's logit with
        respect to its map channels (occupied and free, summed): where the network looks.
    steps : int
        The steps the network was trained (early stopping).
    """

    auc: float
    test: np.ndarray
    crops: np.ndarray
    saliency: np.ndarray
    steps: int


def telling_crops(plans, a, b, *, crop: int = 64, steps: int = 12000, patience: int = 5,
                  test_share: float = 0.25, val_share: float = 0.2, top: int = 8,
                  seed: int = 0, threads: int = 1) -> TellingCrops:
    """What tells maps ``b`` from maps ``a`` (issue #33): one network of
    :func:`two_sample_auc`, trained on the plans outside a held-out ``test_share`` (early
    stopping on ``val_share`` of them), scores every scoring crop of the held-out plans'
    two maps; the crops where ``b`` scores most above ``a`` show what gives ``b`` away.

    Examples
    --------
    >>> plans = np.full((24, 64, 64), 255, np.uint8); plans[:, :, 30:32] = 0
    >>> b = plans.copy(); b[:, :, 33:35] = 0                # every b wall saved twice
    >>> t = telling_crops(plans, plans, b, crop=32, steps=60, patience=0, top=2)
    >>> t.auc > 0.9, t.crops.shape[1], t.saliency.shape
    (True, 5, (2, 32, 32))
    >>> bool(t.crops[0, 3] >= t.crops[-1, 3])
    True
    """
    import torch

    plans, a, b = (np.asarray(x) for x in (plans, a, b))
    n = len(plans)
    order = np.random.default_rng(seed).permutation(n)
    k_test = max(2, int(round(test_share * n)))
    test, rest = np.sort(order[:k_test]), order[k_test:]
    k_val = max(1, int(round(val_share * len(rest)))) if patience > 0 else 0
    val, train = np.sort(rest[:k_val]), np.sort(rest[k_val:])
    if len(train) < 1:
        raise ValueError(f"too few plans to train on: {n}")
    crop = min(crop, plans.shape[-1])
    with _deterministic(threads):
        xa, xb = torch.from_numpy(encode(plans, a)), torch.from_numpy(encode(plans, b))
        corners = _grid(plans, crop)
        net, used = _train(xa, xb, corners, train, crop=crop, steps=steps, batch=32, lr=1e-3,
                           seed=seed, val_idx=val if patience > 0 else None,
                           patience=patience)
        net.eval()
        rows, sa, sb = [], np.empty(len(test)), np.empty(len(test))
        with torch.no_grad():           # each crop scored once: the map scores are their means
            for j, i in enumerate(test):
                ca = torch.stack([xa[i, :, y:y + crop, x:x + crop] for y, x in corners[i]])
                cb = torch.stack([xb[i, :, y:y + crop, x:x + crop] for y, x in corners[i]])
                la, lb = net(ca), net(cb)
                sa[j], sb[j] = float(la.mean()), float(lb.mean())    # as _score scores them
                la, lb = la[:, 0].numpy(), lb[:, 0].numpy()
                for (y, x), va, vb in zip(corners[i], la, lb, strict=True):
                    rows.append((i, y, x, vb - va, vb))
        auc = _auc(sa, sb)
        crops = np.array(rows, float).reshape(-1, 5)
        crops = crops[np.argsort(-crops[:, 3], kind="stable")]
        sal = []
        for i, y, x in crops[:top, :3].astype(int):
            c = xb[i:i + 1, :, y:y + crop, x:x + crop].clone().requires_grad_(True)
            net(c).sum().backward()
            sal.append(c.grad[0, 2:].abs().sum(0).numpy())
    return TellingCrops(float(auc), test, crops,
                        np.asarray(sal, np.float32).reshape(-1, crop, crop), int(used))
