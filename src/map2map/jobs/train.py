"""``map2map train ba`` and ``map2map train ab`` as jobs: a packed dataset in, a training
run folder out (:func:`map2map.learn.ba.train.train_ba`,
:func:`map2map.learn.ab.train.train_ab`).

The settings are the fields of the model's config dataclass
(:class:`~map2map.learn.ba.config.BAConfig`, :class:`~map2map.learn.ab.config.ABConfig`);
a setting left ``None`` takes the dataclass's default, so the defaults are written once.
The run folder is resumable exactly (``resume=True``).

Examples
--------
>>> import tempfile, pathlib, numpy as np
>>> from map2map.datasets.packed import PackedPairs
>>> a = np.random.default_rng(0).choice(np.array([0, 127, 255], np.uint8), (4, 32, 32))
>>> pairs = PackedPairs(a, a[:, :, ::-1], np.arange(4).astype(str), np.array(["train"] * 4))
>>> out = pathlib.Path(tempfile.mkdtemp()) / "run"
>>> run = train(TrainSpec("ba", pairs, out, {"size": 16, "epochs": 1, "batch": 2,
...     "g_channels": 8, "d_channels": 8, "d_layers": 2}, progress=False))
>>> run.result.epochs_done, run.summary().startswith("trained 1 epochs at")
(1, True)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from ..core.errors import InputError

__all__ = ["TrainSpec", "TrainRun", "train", "MODELS", "rate_text", "train_pose_error_job"]

#: The trainable models: name -> what it learns.
MODELS = {"ba": "Model_BA: SLAM map -> CAD plan", "ab": "Model_AB: CAD plan -> SLAM map"}


@dataclass
class TrainSpec:
    """What ``map2map train MODEL`` is asked to do.

    Parameters
    ----------
    model : {"ba", "ab"}
        Which model.
    data : path-like, list of them, or PackedPairs
        A dataset folder (``packed.npz`` inside), a packed ``.npz``, several of them (their
        pairs merged, :func:`~map2map.datasets.packed.merge_packed`) or the pairs.
    out : path-like
        The run folder.
    settings : dict
        Fields of the model's config dataclass; ``None`` values take its defaults. For
        ``ab``, ``schedule`` may be the text ``"RES:EPOCHS,..."``.
    resume : bool
        Continue the run in ``out`` exactly; ``settings["epochs"]`` (if given) extends it.
    progress : bool
        Progress bar.
    """

    model: str
    data: Any
    out: str | os.PathLike
    settings: dict = field(default_factory=dict)
    resume: bool = False
    progress: bool = True


@dataclass
class TrainRun:
    """The run folder and :class:`~map2map.learn.training.loop.TrainResult`; ``main`` is
    False on the other ranks of a distributed run (they report nothing)."""

    out: Path
    result: Any
    model: str
    main: bool = True

    def summary(self) -> str:
        """The one line the command prints."""
        res = self.result
        last = res.history[-1] if res.history else {}
        steps = f" ({last['step']} steps)" if "step" in last else ""
        stage = (f" (now {last.get('resolution', '?')} px, alpha "
                 f"{last.get('alpha', float('nan')):.2f})" if self.model == "ab" else "")
        return (f"trained {res.epochs_done} epochs{stage} at {rate_text(res.images_per_s)}"
                f"{steps}; loss G {last.get('loss_G', float('nan')):.4f} D "
                f"{last.get('loss_D', float('nan')):.4f}; run in {res.run}")


def rate_text(images_per_s: float) -> str:
    """A training rate for people: whole images per second from 10 on, one decimal
    below (a run of a few pairs printed "0 img/s"), two significant digits under 0.1.

    Examples
    --------
    >>> rate_text(2403.4), rate_text(46.2), rate_text(0.4), rate_text(0.012)
    ('2403 img/s', '46 img/s', '0.4 img/s', '0.012 img/s')
    >>> rate_text(float("nan"))
    'an unmeasured rate'
    """
    r = images_per_s
    if not (r == r and 0 < r < float("inf")):
        return "an unmeasured rate"
    if r >= 10:
        return f"{r:.0f} img/s"
    return f"{r:.1f} img/s" if r >= 0.1 else f"{r:.2g} img/s"


def _config(spec: TrainSpec):
    """The model's config from ``spec.settings`` (checked; parameter names in errors)."""
    given = {k: v for k, v in spec.settings.items() if v is not None}
    for name in ("epochs", "batch", "save_every"):
        if name in given and given[name] < 1:
            raise InputError(name, f"must be >= 1, got {given[name]}")
    if spec.model == "ba":
        from ..learn.ba.config import BAConfig

        cls = BAConfig
        size = given.get("size", BAConfig.size)
        if size < 4 or size & (size - 1):
            raise InputError("size", f"must be a power of two >= 4, got {size}")
    else:
        from ..learn.ab.config import ABConfig, parse_schedule

        cls = ABConfig
        if given.get("fade_batches", 0) < 0:
            raise InputError("fade_batches", f"must be positive, got {given['fade_batches']}")
        if isinstance(given.get("schedule"), str):
            try:
                given["schedule"] = parse_schedule(given["schedule"])
            except ValueError as exc:
                raise InputError("schedule", str(exc)) from None
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(given) - names)
    if unknown:
        raise InputError(None, f"not a setting of {cls.__name__}: {', '.join(unknown)}")
    try:
        return cls(**given)
    except ValueError as exc:
        raise InputError("schedule" if spec.model == "ab" else None, str(exc)) from None


def train(spec: TrainSpec) -> TrainRun:
    """Train (or resume) the model of ``spec`` (module docstring)."""
    if spec.model not in MODELS:
        raise InputError("model", f"one of {', '.join(MODELS)}, not {spec.model!r}")
    try:
        if spec.model == "ba":
            from ..learn.ba.train import train_ba as fit
        else:
            from ..learn.ab.train import train_ab as fit
    except ImportError as exc:
        raise InputError("train", f"needs PyTorch: pip install 'map2map[learn]' ({exc})"
                         ) from None
    cfg = _config(spec)
    epochs = spec.settings.get("epochs")
    res = fit(spec.data, spec.out, cfg, resume=spec.resume,
              epochs=epochs if spec.resume else None, progress=spec.progress)
    main = int(os.environ.get("RANK", "0")) == 0  # torchrun: one report, from rank 0
    return TrainRun(Path(spec.out), res, spec.model, main)


def train_pose_error_job(out: str | os.PathLike, *, runs: int = 400, seed: int = 20270101,
                         epochs: int = 30, duration: float = 420.0,
                         workers: int | None = None, command: str = "",
                         progress: bool = True) -> dict:
    """``map2map train pose-error``: explore ``runs`` generated plans of ``seed`` on the
    ``rbpf`` particle filter's map, fit the learned pose-error model
    (:mod:`map2map.learn.ab.pose_error`) to the filter's errors, and write ``out``
    (safetensors, the configuration in its header), ``out``'s ``.json``, ``-losses.png``
    (log-likelihood per epoch) and ``-samples.png`` (recorded errors beside drawn ones)
    beside it. Returns the configuration written."""
    out = Path(out)
    if out.suffix != ".safetensors":
        raise InputError(str(out), "the pose-error model is one .safetensors file")
    if runs < 2 or epochs < 1:
        raise InputError("runs" if runs < 2 else "epochs",
                         f"must be at least {2 if runs < 2 else 1}")
    import importlib.util
    import time

    if importlib.util.find_spec("torch") is None:
        raise InputError("train", "needs PyTorch: pip install 'map2map[learn]'")
    from ..learn.ab.pose_error_train import collect_runs, train_pose_error

    t0 = time.perf_counter()
    recorded = collect_runs(runs, seed, duration=duration, workers=workers,
                            progress=progress)
    t1 = time.perf_counter()
    model, hist = train_pose_error(recorded, epochs=epochs, seed=0, progress=progress)
    model.config.update({
        "command": command, "plans": {"source": "generated", "seed": int(seed),
                                      "count": int(runs), "duration_s": float(duration),
                                      "mapper": "rbpf"},
        "machine": _machine(),
        "explore_s": round(t1 - t0, 1), "train_s": round(time.perf_counter() - t1, 1),
        "history": {k: [round(v, 4) for v in vs] for k, vs in hist.items()},
    })
    out.parent.mkdir(parents=True, exist_ok=True)
    model.save(out)
    _loss_figure(hist, out.with_name(out.stem + "-losses.png"))
    _sample_figure(model, recorded, out.with_name(out.stem + "-samples.png"))
    return model.config


def _sample_figure(model, recorded: list, path: Path, n: int = 3) -> None:
    """The filter's error along ``n`` recorded runs beside errors the model draws along
    the same runs (the error's x, y and heading over time)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from ..core._io import atomic_path

    fig, axes = plt.subplots(n, 2, figsize=(10, 2.4 * n), squeeze=False, sharey="row")
    rng = np.random.default_rng(0)
    for r, (P, E, t, geo) in enumerate(recorded[-n:]):
        for c, (what, err) in enumerate((("the rbpf filter", E),
                                         ("drawn by the model", model.sample(P, t, geo, rng)))):
            ax = axes[r, c]
            ax.plot(t, err[:, 0], label="x [m]")
            ax.plot(t, err[:, 1], label="y [m]")
            ax.plot(t, np.degrees(err[:, 2]) / 10, label="heading [10 deg]")
            ax.set_title(f"run {len(recorded) - n + r}: {what}", fontsize=9)
            if r == n - 1:
                ax.set_xlabel("seconds")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=80)
    plt.close(fig)


def _machine() -> str:
    """The CPU's model name (Linux: ``/proc/cpuinfo``), its architecture and cores."""
    import platform

    name = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{name or platform.machine()} ({platform.machine()}), {os.cpu_count()} cores"


def _loss_figure(hist: dict, path: Path) -> None:
    """The training and held-out log-likelihood per epoch."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..core._io import atomic_path

    fig, ax = plt.subplots(figsize=(5, 3.2))
    for k, v in hist.items():
        ax.plot(range(1, len(v) + 1), v, label=k)
    ax.set_xlabel("epoch")
    ax.set_ylabel("log-likelihood per step")
    ax.set_title("learned pose error")
    ax.legend()
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)
