"""Checkpoints as safetensors: tensors plus a JSON header, no pickle.

Loading a checkpoint must not run code, so nothing goes through ``torch.save`` /
``torch.load`` (pickle). A checkpoint is one ``.safetensors`` file: every tensor (the
networks' weights and buffers, the optimisers' moment estimates and step counts, the
random generators' states as uint8 tensors) under a dotted name, and a JSON document
(configuration, epoch, position within the epoch, the optimisers' hyper-parameters,
the loss history) in the file's string metadata under ``"map2map"``. It is written to a
temporary name and renamed, so an interrupted write never leaves a broken checkpoint.

Examples
--------
>>> import torch, tempfile, pathlib
>>> net = torch.nn.Linear(2, 1)
>>> opt = torch.optim.Adam(net.parameters())
>>> net(torch.ones(1, 2)).sum().backward(); opt.step()
>>> tensors, groups = optimizer_tensors(opt, "opt")
>>> path = pathlib.Path(tempfile.mkdtemp()) / "ck.safetensors"
>>> save_checkpoint(path, {**module_tensors(net, "net"), **tensors}, {"groups": groups})
>>> back, state = load_checkpoint(path)
>>> opt2 = torch.optim.Adam(torch.nn.Linear(2, 1).parameters())
>>> load_optimizer(opt2, back, "opt", state["groups"])
>>> a, b = (o.state_dict()["state"][0]["exp_avg"] for o in (opt, opt2))
>>> bool(torch.equal(a, b))
True
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import torch
from safetensors import SafetensorError, safe_open
from safetensors.torch import save_file

from ...core._io import atomic_path
from ...core.errors import InputError

__all__ = ["read_model_file", "save_checkpoint", "load_checkpoint", "module_tensors", "load_module",
           "optimizer_tensors", "load_optimizer", "export_generator"]

_META_KEY = "map2map"


def shipped_weights(package: str, name: str) -> Path:
    """Path of a weights file shipped in a model's package (``<package>/weights/NAME``).

    Examples
    --------
    >>> shipped_weights("map2map.learn.ba", "model_ba.safetensors").name
    'model_ba.safetensors'
    """
    from importlib import resources

    return Path(str(resources.files(package) / "weights" / name))


def save_checkpoint(path: str | os.PathLike, tensors: dict[str, torch.Tensor],
                    state: dict) -> None:
    """Write ``tensors`` and the JSON-serialisable ``state`` atomically to ``path``."""
    clean = {k: v.detach().to("cpu").contiguous().clone() for k, v in tensors.items()}
    with atomic_path(path) as tmp:
        save_file(clean, str(tmp), metadata={_META_KEY: json.dumps(state, sort_keys=True)})


def load_checkpoint(path: str | os.PathLike, device: str | torch.device = "cpu"
                    ) -> tuple[dict[str, torch.Tensor], dict]:
    """Read a file written by :func:`save_checkpoint`: (tensors, state)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "checkpoint not found")
    try:
        with safe_open(str(path), framework="pt", device=str(device)) as f:
            meta = f.metadata() or {}
            tensors = {k: f.get_tensor(k) for k in f.keys()}
    except (SafetensorError, OSError, ValueError) as exc:
        raise InputError(path, f"not a readable safetensors checkpoint ({exc})") from None
    try:
        state = json.loads(meta.get(_META_KEY, "{}"))
    except json.JSONDecodeError as exc:
        raise InputError(path, f"checkpoint header is not valid JSON ({exc})") from None
    return tensors, state


def module_tensors(module: torch.nn.Module, prefix: str) -> dict[str, torch.Tensor]:
    """A module's state dict (parameters and buffers) under ``prefix.``."""
    return {f"{prefix}.{k}": v for k, v in module.state_dict().items()}


def load_module(module: torch.nn.Module, tensors: dict[str, torch.Tensor], prefix: str,
                source: str | os.PathLike | None = None) -> None:
    """Load the ``prefix.`` entries of ``tensors`` into ``module`` (strict)."""
    n = len(prefix) + 1
    sd = {k[n:]: v for k, v in tensors.items() if k.startswith(prefix + ".")}
    try:
        module.load_state_dict(sd, strict=True)
    except RuntimeError as exc:
        first = str(exc).splitlines()[0]
        raise InputError(source, f"weights do not fit the network {prefix!r} ({first})") from None


def optimizer_tensors(opt: torch.optim.Optimizer, prefix: str) -> tuple[dict, list]:
    """(tensors of the optimiser's per-parameter state, its param groups as JSON data).

    The groups are stored in the plain (eager) form whatever ran: a tensor learning rate
    (CUDA-graph training, :func:`~map2map.learn.training.static_step.make_capturable`) as a float,
    ``capturable``/``foreach``/``fused`` at Adam's defaults -- they say how a step is
    computed, not what the optimiser holds, and a resumed run sets its own.
    """
    sd = opt.state_dict()
    tensors = {}
    for idx, st in sd["state"].items():
        for k, v in st.items():
            t = v if torch.is_tensor(v) else torch.tensor(v)
            tensors[f"{prefix}.{idx}.{k}"] = t
    groups = []
    for g in sd["param_groups"]:
        g = {k: (float(v) if torch.is_tensor(v) else v) for k, v in g.items()}
        for k, plain in (("capturable", False), ("foreach", None), ("fused", None)):
            if k in g:
                g[k] = plain
        groups.append(g)
    return tensors, groups


def load_optimizer(opt: torch.optim.Optimizer, tensors: dict[str, torch.Tensor], prefix: str,
                   groups: list) -> None:
    """Inverse of :func:`optimizer_tensors`."""
    state: dict[int, dict] = {}
    n = len(prefix) + 1
    for k, v in tensors.items():
        if k.startswith(prefix + "."):
            idx, name = k[n:].split(".", 1)
            state.setdefault(int(idx), {})[name] = v
    for g in groups:  # JSON turned the betas tuple into a list
        if "betas" in g:
            g["betas"] = tuple(g["betas"])
    opt.load_state_dict({"state": state, "param_groups": groups})


def read_model_file(model, pretrained: Path, fmt: str, name: str, *, no_pretrained: str,
                    missing: str, wrong: str) -> tuple[Path, dict, dict[str, torch.Tensor]]:
    """Find and read a shipped-model file: ``(path, header, float32 tensors)``.

    ``model`` is ``"pretrained"``/``None`` (the file ``pretrained``), a training run
    folder (its ``model.safetensors``) or a ``.safetensors`` file; its ``map2map``
    header must say ``format == fmt``. ``name`` ("Model_BA") and the three messages
    (no shipped file; no such file here; a file of another format) make the one-line
    errors.
    Safetensors only: nothing runs on load.
    """
    if model is None or str(model) == "pretrained":
        path = pretrained
        if not path.is_file():
            raise InputError("model", no_pretrained)
    else:
        path = Path(model)
        if path.is_dir():
            path = path / "model.safetensors"
        if not path.is_file():
            raise InputError(model, missing)
    try:
        with safe_open(str(path), framework="pt", device="cpu") as f:
            header = json.loads((f.metadata() or {}).get("map2map", "{}"))
            tensors = {k: f.get_tensor(k).float() for k in f.keys()}
    except (SafetensorError, OSError, ValueError) as exc:
        raise InputError(path, f"not readable {name} weights ({exc})") from None
    if header.get("format") != fmt:
        raise InputError(path, wrong)
    return path, header, tensors


def export_generator(run: str | os.PathLike, dest: str | os.PathLike, read_header, *,
                     note: str = "") -> Path:
    """Copy a run's generator to ``dest`` in float16 with its header (plus ``note``) and a
    readable ``.json`` of that header beside it: how the shipped weights are made.

    ``run`` is a training run folder (its ``model.safetensors``) or such a file;
    ``read_header(path)`` loads it as its model (checking its format, one-line errors)
    and returns its header: ``export_model`` (Model_BA) and ``export_ab_model``
    (Model_AB) are this with their loaders.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> save_checkpoint(d / "model.safetensors", {"w": torch.ones(2)}, {"format": "x"})
    >>> p = export_generator(d, d / "out.safetensors", lambda p: load_checkpoint(p)[1],
    ...                      note="copy")
    >>> back, header = load_checkpoint(p)
    >>> back["w"].dtype, header["note"], p.with_suffix(".json").is_file()
    (torch.float16, 'copy', True)
    """
    src = Path(run)
    if src.is_dir():
        src = src / "model.safetensors"
    header = dict(read_header(src))
    if note:
        header["note"] = note
    with safe_open(str(src), framework="pt", device="cpu") as f:
        tensors = {k: f.get_tensor(k).to(torch.float16).contiguous() for k in f.keys()}
    dest = Path(dest)
    save_checkpoint(dest, tensors, header)
    with atomic_path(dest.with_suffix(".json")) as tmp:
        tmp.write_text(json.dumps(header, indent=2, sort_keys=True))
    return dest


def load_generator(net: torch.nn.Module, tensors: dict[str, torch.Tensor], path,
                   device: str | torch.device = "cpu") -> torch.device:
    """Put ``tensors`` (from :func:`read_model_file`) into ``net`` (strictly: every
    weight, no extra), move it to ``device`` in eval mode; the device. Weights that do not
    fit the network are one :class:`InputError` naming ``path``."""
    try:
        net.load_state_dict(tensors, strict=True)
    except RuntimeError as exc:
        raise InputError(path, f"weights do not fit the network ({str(exc).splitlines()[0]})"
                         ) from None
    dev = torch.device(device)
    net.to(dev).eval()
    return dev

