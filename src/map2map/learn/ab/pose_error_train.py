"""Training the learned pose error (:mod:`map2map.learn.ab.pose_error`): the ``rbpf``
filter's errors recorded on explorations of generated plans (:func:`collect_runs`) and the
maximum-likelihood fit of the model to them (:func:`train_pose_error`);
``map2map train pose-error`` runs both (:func:`map2map.jobs.train.train_pose_error_job`).

Examples
--------
>>> rng = np.random.default_rng(0)
>>> P = np.column_stack([np.linspace(0.0, 10.0, 100), np.zeros(100), np.zeros(100)])
>>> runs = []
>>> for _ in range(3):
...     E = np.cumsum(rng.normal(0.0, [0.01, 0.01, 0.003], (100, 3)), axis=0)
...     runs.append((P, E - E[0], np.arange(100) * 0.5, np.zeros((100, 4))))
>>> model, hist = train_pose_error(runs, epochs=2, hidden=8, progress=False)
>>> len(hist["val"]), model.config["runs"], model.sample(P, np.arange(100) * 0.5,
...     np.zeros((100, 4)), np.random.default_rng(1)).shape
(2, 3, (100, 3))
"""

from __future__ import annotations

import math

import numpy as np

from ...core.errors import InputError
from .pose_error import (
    COMPONENTS,
    FEATURES,
    MEMORY_M,
    MEMORY_S,
    PER_COMPONENT,
    VIEW_M,
    PoseErrorModel,
    _mixture,
    _wrap,
    scan_geometry,
    training_pairs,
)

__all__ = ["train_pose_error", "recorded_run", "collect_runs"]


def train_pose_error(runs, *, epochs: int = 30, hidden: int = 64, batch: int = 1024,
                     lr: float = 2e-3, val_share: float = 0.2, seed: int = 0,
                     progress: bool = True) -> tuple[PoseErrorModel, dict]:
    """Fit the model to recorded runs by maximum likelihood (teacher forcing).

    Parameters
    ----------
    runs : sequence of (P, E, t, geo)
        Per run: the nodes' true poses, the filter's errors (filter minus true), their
        times and :func:`scan_geometry` rows.
    epochs, hidden, batch, lr : training settings (Adam; the learning rate falls
        linearly to 0 over the last half).
    val_share : float
        Share of the runs held out; the weights of the epoch with the best held-out
        likelihood are kept.
    seed : int
        Seeds the split, the initialisation and the batches (same seed, same model on CPU).

    Returns
    -------
    model, history
        ``history``: per epoch the train and held-out mean log-likelihood per step.
    """
    import torch

    runs = list(runs)
    if len(runs) < 2:
        raise InputError("runs", f"need at least 2 recorded runs, got {len(runs)}")
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(runs))
    n_val = max(1, int(round(val_share * len(runs))))
    parts = {"train": order[n_val:], "val": order[:n_val]}
    data = {}
    for name, idx in parts.items():
        xy = [training_pairs(*runs[i]) for i in idx]
        data[name] = (np.concatenate([a for a, _ in xy]), np.concatenate([b for _, b in xy]))
    X, Y = data["train"]
    mean, std = X.mean(0), X.std(0) + 1e-6
    torch.manual_seed(seed)
    k = COMPONENTS
    net = torch.nn.Sequential(torch.nn.Linear(FEATURES, hidden), torch.nn.SiLU(),
                              torch.nn.Linear(hidden, hidden), torch.nn.SiLU(),
                              torch.nn.Linear(hidden, PER_COMPONENT * k)).double()

    def nll(xb, yb):
        logw, mu, L = _mixture(net(xb), torch)
        r = (yb[:, None, :] - mu)[..., None]
        z = torch.linalg.solve_triangular(L, r, upper=False)[..., 0]
        diag = torch.log(torch.diagonal(L, dim1=-2, dim2=-1)).sum(-1)
        lp = -0.5 * (z * z).sum(-1) - diag - 1.5 * math.log(2 * math.pi) + logw
        return -torch.logsumexp(lp, dim=1).mean()

    def tensors(name):
        a, b = data[name]
        return torch.from_numpy((a - mean) / std), torch.from_numpy(b)

    xt, yt = tensors("train")
    xv, yv = tensors("val")
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    gen = torch.Generator().manual_seed(seed)
    hist = {"train": [], "val": []}
    best, best_state = -math.inf, None
    steps = max(1, math.ceil(len(xt) / batch))
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=epochs, desc="pose error", unit="epoch")
    for ep in range(epochs):
        for g in opt.param_groups:
            g["lr"] = lr * min(1.0, 2.0 * (1.0 - ep / epochs))
        perm = torch.randperm(len(xt), generator=gen)
        tot = 0.0
        for s in range(steps):
            j = perm[s * batch:(s + 1) * batch]
            loss = nll(xt[j], yt[j])
            opt.zero_grad()
            loss.backward()
            opt.step()
            tot += float(loss.detach()) * len(j)
        with torch.no_grad():
            v = -float(nll(xv, yv))
        hist["train"].append(-tot / len(xt))
        hist["val"].append(v)
        if v > best:
            best = v
            best_state = {n: p.detach().clone() for n, p in net.state_dict().items()}
        if bar is not None:
            bar.update(1)
            bar.set_postfix(train=f"{hist['train'][-1]:.3f}", val=f"{v:.3f}")
    if bar is not None:
        bar.close()
    net.load_state_dict(best_state)
    # float32 as saved, so that a model and its file draw the same errors
    sd = {n: p.detach().numpy().astype(np.float32).astype(float)
          for n, p in net.state_dict().items()}
    # contiguous as loaded from the file: the same matrix products, bit for bit
    w = {k: np.ascontiguousarray(v) for k, v in
         {"w0": sd["0.weight"].T, "b0": sd["0.bias"], "w1": sd["2.weight"].T,
          "b1": sd["2.bias"], "w2": sd["4.weight"].T, "b2": sd["4.bias"]}.items()}
    E_all = np.concatenate([_wrap(np.asarray(r[1], float)) for r in runs])
    config = {"step_max": [round(2 * float(v), 3) for v in np.abs(Y).max(0)],
              "error_max": [round(2 * float(v), 4) for v in np.abs(E_all).max(0)],
              "features": FEATURES, "components": k, "hidden": hidden, "epochs": epochs,
              "batch": batch, "lr": lr, "seed": seed, "runs": len(runs),
              "train_steps": int(len(xt)), "val_steps": int(len(xv)),
              "val_loglik": round(best, 4), "memory_s": MEMORY_S, "memory_m": MEMORY_M,
              "view_m": VIEW_M}
    f32 = lambda a: np.asarray(a, np.float32).astype(float)  # noqa: E731
    return PoseErrorModel(w, f32(mean), f32(std), config), hist


def recorded_run(item) -> tuple | None:
    """One training run (a task of :func:`collect_runs`): ``item = (seed, index,
    duration)``; generated plan ``index`` of ``seed`` (as ``map2map dataset build --plans
    generated --seed seed`` draws it) explored by the simulator's robot on its ``rbpf``
    particle filter's map (:func:`~map2map.learn.ab.scans.explore`). Returns ``(P, E, t,
    geo)`` at the scans the filter processed (true poses, filter minus true, seconds,
    :func:`scan_geometry`), or None for a plan the robot cannot explore."""
    from ...datasets.plans import PlanSource, load_plan
    from ...slam.rbpf import prepare_scan
    from .scans import ScanMapParams, explore

    seed, index, duration = item
    _, plan = load_plan(PlanSource("generated"), int(seed), int(index))
    try:
        ex = explore(plan, int(seed), int(index), ScanMapParams(duration=float(duration)))
    except InputError:
        return None
    keep = np.asarray(ex.keep, int)
    if len(keep) < 3:
        return None
    ra = [prepare_scan(ex.scans[i]) for i in keep]
    geo = scan_geometry(np.stack([r for r, _ in ra]), np.stack([a for _, a in ra]))
    P = np.asarray(ex.poses, float)[keep]
    return P, _wrap(ex.filter_poses - P), np.asarray(ex.times, float)[keep], geo


def collect_runs(count: int, seed: int, *, duration: float = 420.0,
                 workers: int | None = None, progress: bool = True) -> list[tuple]:
    """``count`` training runs (:func:`recorded_run` of generated plans ``0 .. count-1`` of
    ``seed``), in ``workers`` processes (default one per core); plans the robot cannot
    explore are left out."""
    from ...core.parallel import process_map

    items = [(int(seed), j, float(duration)) for j in range(int(count))]
    if progress:
        from tqdm import tqdm

        out = []
        chunk = 16
        with tqdm(total=len(items), desc="pose error: exploring", unit="run") as bar:
            for s in range(0, len(items), chunk):
                out += process_map(recorded_run, items[s:s + chunk], workers=workers,
                                   min_items=2)
                bar.update(len(items[s:s + chunk]))
    else:
        out = process_map(recorded_run, items, workers=workers, min_items=2)
    return [r for r in out if r is not None]
