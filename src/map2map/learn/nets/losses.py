"""The objective of Model_BA, thesis eq. 3.2, one function per term (eqs. 3.3-3.7).

Eq. 3.2::

    min_G max_{D_d, D_r}  sum_k L_GAN_domain(G, D_d_k) + sum_k L_GAN_real/fake(G, D_r_k)
                        + sum_k L_FM_domain(G, D_d_k) + sum_k L_input_real/fake(G, D_r_k)
                        + lambda L_L1(G)

``k = 1..3`` runs over the scales of a
:class:`~map2map.learn.nets.networks.MultiScaleDiscriminator`;
every function below takes the discriminator's output (one feature list per scale, the
last entry of each list being the patch logits) and already sums over ``k``.

* The log-likelihood GAN objectives (eqs. 3.3, 3.4) are evaluated as binary
  cross-entropy on the logits (``log sigmoid``, numerically stable), averaged over the
  patches: the discriminator *minimises* ``-[log D(real) + log(1 - D(fake))]``, the
  generator uses the usual non-saturating form ``-log D(fake)``.
* False-target augmentation (sec. 3.1, [51]): for ``D_d`` the "not associated" pairs are
  the generated pairs ``(x, G(x))`` and the false pairs ``(x, y')`` (a target of another
  input); the second expectation of eq. 3.3 is taken over both, i.e. ``0.5 * (fake + false)``.
* Eqs. 3.5 and 3.6 weight each layer's L1 distance by ``N_i``, the number of elements of
  layer ``i``; read as pix2pixHD's normaliser (``1 / N_i`` times the summed absolute
  difference) this is the **mean** absolute difference per layer, summed over the
  intermediate layers (the final logits excluded) and the scales. The real side is a
  constant for the generator (detached).
* Eq. 3.6 compares ``D_r``'s features of the target ``y`` with those of ``G(x)``, as the
  thesis writes it (anime2clothing's code compares with the *input* ``x`` instead, which
  for SLAM -> CAD would pull the output towards the noisy SLAM map).
* Everything is computed in float32, also under bf16 autocast.

Examples
--------
>>> import torch
>>> logits = [[torch.zeros(1, 1, 2, 2)]]          # one scale, logits 0 -> D = 0.5
>>> round(float(gan_real_fake_3_4(logits, logits, side="d")), 4)    # 2 log 2
1.3863
>>> round(float(l1_3_7(torch.zeros(1, 1, 2, 2), torch.ones(1, 1, 2, 2))), 4)
1.0
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

__all__ = [
    "gan_domain_3_3",
    "gan_real_fake_3_4",
    "feature_matching_3_5",
    "input_consistency_3_6",
    "l1_3_7",
    "generator_loss_3_2",
    "discriminator_loss_3_2",
]

Scales = list[list[torch.Tensor]]


def _log_likelihood(scales: Scales, real: bool) -> torch.Tensor:
    """``-mean log D`` (real) or ``-mean log(1 - D)`` (fake) of the patch logits, summed
    over the scales."""
    total = None  # the first term itself, not 0 + it: the same value, two calls fewer
    for feats in scales:
        logits = feats[-1].float()
        target = torch.ones_like(logits) if real else torch.zeros_like(logits)
        term = F.binary_cross_entropy_with_logits(logits, target)
        total = term if total is None else total + term
    return total


def _feature_l1(real: Scales, fake: Scales) -> torch.Tensor:
    """Sum over scales and intermediate layers of the mean |D^(i)(real) - D^(i)(fake)|."""
    total = None
    for fr, ff in zip(real, fake, strict=True):
        for a, b in zip(fr[:-1], ff[:-1], strict=True):
            term = (a.detach().float() - b.float()).abs().mean()
            total = term if total is None else total + term
    return total if total is not None else torch.zeros((), device=fake[0][-1].device)


def gan_domain_3_3(real_pair: Scales | None, fake_pair: Scales, false_pair: Scales | None = None,
                   *, side: str) -> torch.Tensor:
    """Eq. 3.3, the domain GAN loss of ``D_d`` on (input, output) pairs.

    Parameters
    ----------
    real_pair, fake_pair, false_pair : list of feature lists
        ``D_d(x, y)``, ``D_d(x, G(x))`` and ``D_d(x, y')`` (false targets; optional).
    side : {"d", "g"}
        ``"d"``: the discriminator's loss ``-log D(x,y) - log(1 - D(x,.))`` with the
        negatives averaged over generated and false pairs; ``"g"``: the generator's
        non-saturating loss ``-log D(x, G(x))`` (``real_pair``/``false_pair`` unused).

    Examples
    --------
    >>> z = [[torch.zeros(1, 1, 1, 1)]]
    >>> round(float(gan_domain_3_3(None, z, side="g")), 4)        # -log(0.5)
    0.6931
    """
    if side == "g":
        return _log_likelihood(fake_pair, True)
    if side != "d":
        raise ValueError("side must be 'd' or 'g'")
    negative = _log_likelihood(fake_pair, False)
    if false_pair is not None:
        negative = 0.5 * (negative + _log_likelihood(false_pair, False))
    return _log_likelihood(real_pair, True) + negative


def gan_real_fake_3_4(real: Scales | None, fake: Scales, *, side: str) -> torch.Tensor:
    """Eq. 3.4, the real/fake GAN loss of ``D_r`` on single maps (see
    :func:`gan_domain_3_3` for ``side``).

    Examples
    --------
    >>> real = [[torch.full((1, 1, 1, 1), 2.0)]]
    >>> fake = [[torch.full((1, 1, 1, 1), -2.0)]]
    >>> round(float(gan_real_fake_3_4(real, fake, side="d")), 4)   # 2 * log(1 + e^-2)
    0.2539
    """
    if side == "g":
        return _log_likelihood(fake, True)
    if side != "d":
        raise ValueError("side must be 'd' or 'g'")
    return _log_likelihood(real, True) + _log_likelihood(fake, False)


def feature_matching_3_5(real_pair: Scales, fake_pair: Scales) -> torch.Tensor:
    """Eq. 3.5: L1 between ``D_d``'s intermediate features of ``(x, y)`` and ``(x, G(x))``.

    Examples
    --------
    >>> a = [[torch.zeros(1, 2, 2, 2), torch.zeros(1, 1, 1, 1)]]
    >>> b = [[torch.ones(1, 2, 2, 2), torch.zeros(1, 1, 1, 1)]]
    >>> float(feature_matching_3_5(a, b))        # logits (last entry) are not matched
    1.0
    """
    return _feature_l1(real_pair, fake_pair)


def input_consistency_3_6(real: Scales, fake: Scales) -> torch.Tensor:
    """Eq. 3.6: L1 between ``D_r``'s intermediate features of ``y`` and ``G(x)``.

    Examples
    --------
    >>> a = [[torch.zeros(1, 1, 2, 2), torch.zeros(1, 1, 1, 1)]] * 2   # two scales
    >>> b = [[torch.full((1, 1, 2, 2), 0.5), torch.zeros(1, 1, 1, 1)]] * 2
    >>> float(input_consistency_3_6(a, b))
    1.0
    """
    return _feature_l1(real, fake)


def l1_3_7(fake: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Eq. 3.7: mean absolute difference between ``G(x)`` and ``y`` (in [-1, 1] units).

    Examples
    --------
    >>> float(l1_3_7(torch.tensor([0.0, 1.0]), torch.tensor([1.0, 1.0])))
    0.5
    """
    return (fake.float() - target.float()).abs().mean()


def generator_loss_3_2(dd_real: Scales, dd_fake: Scales, dr_real: Scales, dr_fake: Scales,
                       fake: torch.Tensor, target: torch.Tensor, *, lambda_l1: float = 100.0,
                       lambda_fm: float = 1.0, lambda_ic: float = 1.0
                       ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
    """The generator's side of eq. 3.2: total and each term (named by its equation).

    ``lambda_fm`` and ``lambda_ic`` are 1 in eq. 3.2; they are exposed for experiments.

    Examples
    --------
    >>> s = [[torch.zeros(1, 1, 2, 2), torch.zeros(1, 1, 1, 1)]]
    >>> total, terms = generator_loss_3_2(s, s, s, s, torch.zeros(1), torch.ones(1),
    ...                                   lambda_l1=10.0)
    >>> sorted(terms), round(float(total), 4)           # 2 log 2 + 10
    (['fm_3_5', 'gan_domain_3_3', 'gan_real_fake_3_4', 'ic_3_6', 'l1_3_7'], 11.3863)
    """
    terms = {
        "gan_domain_3_3": gan_domain_3_3(None, dd_fake, side="g"),
        "gan_real_fake_3_4": gan_real_fake_3_4(None, dr_fake, side="g"),
        "fm_3_5": feature_matching_3_5(dd_real, dd_fake),
        "ic_3_6": input_consistency_3_6(dr_real, dr_fake),
        "l1_3_7": l1_3_7(fake, target),
    }
    total = (terms["gan_domain_3_3"] + terms["gan_real_fake_3_4"]
             + lambda_fm * terms["fm_3_5"] + lambda_ic * terms["ic_3_6"]
             + lambda_l1 * terms["l1_3_7"])
    return total, terms


def discriminator_loss_3_2(dd_real: Scales, dd_fake: Scales, dd_false: Scales | None,
                           dr_real: Scales, dr_fake: Scales
                           ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
    """The discriminators' side of eq. 3.2 (eqs. 3.3 + 3.4); ``dd_false`` may be None.

    Examples
    --------
    >>> s = [[torch.zeros(1, 1, 1, 1)]]
    >>> total, terms = discriminator_loss_3_2(s, s, s, s, s)
    >>> round(float(total), 4)                           # 4 log 2
    2.7726
    """
    terms = {
        "d_domain_3_3": gan_domain_3_3(dd_real, dd_fake, dd_false, side="d"),
        "d_real_fake_3_4": gan_real_fake_3_4(dr_real, dr_fake, side="d"),
    }
    return terms["d_domain_3_3"] + terms["d_real_fake_3_4"], terms
