"""One training step of eq. 3.2 (thesis 3.1, 4.2), shared by both models and by both
ways of running it (:mod:`~map2map.learn.training.loop` eagerly,
:mod:`~map2map.learn.training.static_step` on static buffers / a CUDA graph):
discriminators on real, generated and false-target pairs, then the generator.

Examples
--------
>>> import torch
>>> false_targets(torch.arange(4.0), 1).tolist()
[3.0, 0.0, 1.0, 2.0]
"""

from __future__ import annotations

import torch

from ..nets.losses import discriminator_loss_3_2, generator_loss_3_2

__all__ = ["false_targets", "gan_step", "set_lr"]



def false_targets(y: torch.Tensor, shift: int) -> torch.Tensor:
    """Targets of other inputs: ``y`` rolled by ``shift`` (1 <= shift < B) along the batch.

    Examples
    --------
    >>> false_targets(torch.arange(4.0), 1).tolist()
    [3.0, 0.0, 1.0, 2.0]
    """
    return torch.roll(y, shifts=int(shift), dims=0)


def gan_step(g_run, dd_run, dr_run, opt_g, opt_d, x: torch.Tensor, y: torch.Tensor,
             alpha: torch.Tensor | None, cfg, shift: int, autocast, freeze=(),
             g_input: torch.Tensor | None = None, false_index: torch.Tensor | None = None
             ) -> dict:
    """One step of eq. 3.2: the discriminators (max side, false targets rolled by
    ``shift``), then the generator (min side, eqs. 3.3 + 3.4 non-saturating + 3.5 + 3.6
    + lambda 3.7).

    ``D_d`` sees the associated pairs ``(x, y)`` as real and both the generated pairs
    ``(x, G(x))`` and the false pairs ``(x, y')`` as not associated; ``D_r`` sees ``y``
    as real and ``G(x)`` as fake; each discriminator runs once on the concatenated
    batch. ``alpha`` (None or a 0-d tensor, the fade-in of Model_AB) is passed to every
    network when it is not None. ``x`` is the input at the step's resolution (what
    ``D_d`` sees); the generator reads ``g_input`` when given (decoder growth: the
    full-size input), else ``x``. ``freeze``: the discriminators, whose gradients are
    switched off during the generator's backward pass (single process).
    ``false_index`` (an int64 tensor of the batch's length, the rolled ``arange``): the
    false targets as ``y.index_select(0, false_index)`` instead of ``torch.roll`` by
    ``shift`` -- the same values, but no Python int in the step, which a CUDA graph needs
    (:class:`~map2map.learn.training.static_step.StaticStep`). Returns the logged values as
    tensors.
    """
    a = () if alpha is None else (alpha,)
    k = len(x)
    use_false = cfg.false_targets and k > 1
    with autocast:
        fake = g_run(x if g_input is None else g_input, *a)
        real_pair = torch.cat([x, y], 1)
        groups = [real_pair, torch.cat([x, fake.detach()], 1)]
        if use_false:
            y_false = (false_targets(y, shift % k or 1) if false_index is None
                       else y.index_select(0, false_index))
            groups.append(torch.cat([x, y_false], 1))
        dd_out = _split(dd_run(torch.cat(groups), *a), len(groups))
        dr_out = _split(dr_run(torch.cat([y, fake.detach()]), *a), 2)
    loss_d, d_terms = discriminator_loss_3_2(
        dd_out[0], dd_out[1], dd_out[2] if use_false else None, dr_out[0], dr_out[1])
    opt_d.zero_grad(set_to_none=True)
    loss_d.backward()
    opt_d.step()
    _set_grad(freeze, False)
    with autocast:
        dd_out = _split(dd_run(torch.cat([real_pair, torch.cat([x, fake], 1)]), *a), 2)
        dr_out = _split(dr_run(torch.cat([y, fake]), *a), 2)
    loss_g, g_terms = generator_loss_3_2(
        dd_out[0], dd_out[1], dr_out[0], dr_out[1], fake, y,
        lambda_l1=cfg.lambda_l1, lambda_fm=cfg.lambda_fm, lambda_ic=cfg.lambda_ic)
    opt_g.zero_grad(set_to_none=True)
    loss_g.backward()
    opt_g.step()
    _set_grad(freeze, True)
    return {"loss_G": loss_g, "loss_D": loss_d, **g_terms, **d_terms}


def set_lr(opt: torch.optim.Optimizer, lr: float) -> None:
    """Every group's learning rate to ``lr``: in place (``fill_``) when it is a tensor (a
    captured CUDA graph reads that tensor), else by assignment.

    Examples
    --------
    >>> p = torch.nn.Parameter(torch.zeros(1))
    >>> o = torch.optim.Adam([p], lr=torch.tensor(1e-3), fused=True)
    >>> t = o.param_groups[0]["lr"]; set_lr(o, 5e-4)
    >>> o.param_groups[0]["lr"] is t, round(float(t), 6)
    (True, 0.0005)
    """
    for grp in opt.param_groups:
        if torch.is_tensor(grp["lr"]):
            grp["lr"].fill_(lr)
        else:
            grp["lr"] = lr


def _split(scales: list[list[torch.Tensor]], n: int) -> list[list[list[torch.Tensor]]]:
    """Cut every feature map of a batched discriminator output into ``n`` equal parts."""
    chunks = [[f.chunk(n) for f in feats] for feats in scales]  # one chunk call a map
    return [[[c[i] for c in feats] for feats in chunks] for i in range(n)]


def _set_grad(nets, flag: bool) -> None:
    for n in nets:
        for p in n.parameters():
            p.requires_grad_(flag)
