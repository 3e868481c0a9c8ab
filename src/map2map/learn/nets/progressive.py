"""Model_prog (thesis sec. 3.1, Tables 5.1-5.2): the networks of Model_AB (CAD -> SLAM)
grow coarse to fine, and each new resolution block fades in.

**Which growth.** The thesis says "the generator and discriminators progressively grow by
increasing systematically the resolution of the input image" (sec. 3.1, after ProGAN
[53]). That is what is built here: at stage ``r`` the generator *and* both multi-scale
discriminators run on ``r x r`` maps (input plan, output and target SLAM maps all reduced
to ``r``), and a new stage adds, in every network, a ``from_map`` block at ``2r`` and the
stride-2 block that brings ``2r`` down to ``r`` (and in the generator also the up block
and ``to_map`` at ``2r``). anime2clothing's code instead grows only the decoder: its
U-Net always reads the 256 px input and exits early at the current resolution, and its
discriminators are not grown. We follow the thesis's text because (1) the early stages are
then cheap (a 32 px stage costs 1/64 of a 256 px one in every network, which is the
"computation period is shortened" of sec. 3.1; the decoder-only variant pays the full
256 px encoder from epoch 1), and (2) the discriminators' patches at a coarse stage see
the whole map's layout, which is what the coarse stages are for. anime2clothing's fade-in
also never completes (its alpha is divided by samples, not batches); here alpha reaches 1
after a stated number of batches.

**Fade-in (ProGAN).** During the first ``fade_steps`` batches of a new stage ``2r`` the
new blocks are blended with the previous stage's path: ``alpha * new + (1 - alpha) * old``
where *old* feeds the area-averaged ``r`` map through the ``r`` blocks (generator input
and discriminators) or upsamples the ``r`` output (generator output), see
:class:`~map2map.learn.nets.networks.UNetGenerator`. ``alpha = min(1, s / fade_steps)``, ``s``
the number of batches already done in the stage (:func:`fade_alpha`); it is a pure
function of (epoch, batch), so a resumed run continues with the same alpha, and the
trainer keeps it in one 0-d tensor updated in place (``fill_``): a compiled graph sees
the same tensor at every step and is not rebuilt.

**Schedule.** Table 5.2: 15 epochs at 32, 30 at 64, 60 at 128, 100 at 256 (205 epochs;
the thesis's "total epochs" column, 37 / 67 / 127 / 227, also counts 22 earlier epochs at
lower resolutions whose split it does not give -- add them with e.g. ``8:7,16:15,32:15``).
The schedule and its batch sizes are Model_AB's settings
(:mod:`~map2map.learn.ab.config`). Batch size per stage: Table 5.1 times ``batch_rate`` (1 for
Model_AB): 64 at 32, 32 at
64, 16 at 128, 4 at 256. Epochs beyond the schedule's sum stay at its last resolution.

Examples
--------
>>> [fade_alpha(s, 4) for s in range(6)]
[0.0, 0.25, 0.5, 0.75, 1.0, 1.0]
>>> import torch
>>> d = ProgMultiScaleDiscriminator(1, channels=8, n_layers=2, scales=2, size=32, min_size=16)
>>> [f[-1].shape[-1] for f in d(torch.zeros(1, 1, 32, 32), torch.tensor(0.5))]
[4, 2]
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn
from torch.nn.utils.parametrizations import spectral_norm

from ..ab.config import GROWTHS
from .networks import UNetGenerator

__all__ = ["fade_alpha", "StochasticUNet", "ProgPatchDiscriminator",
           "ProgMultiScaleDiscriminator"]



def fade_alpha(step: int, steps: int) -> float:
    """``min(1, step / steps)`` (1 when ``steps`` is 0): ``step`` batches into the fade."""
    if steps <= 0:
        return 1.0
    return min(1.0, step / steps)


class StochasticUNet(UNetGenerator):
    """:class:`~map2map.learn.nets.networks.UNetGenerator` with dropout on the outputs of its
    three coarsest up blocks (pix2pix's noise, [48]). ``stochastic = True`` keeps the
    dropout on in ``eval()`` mode (test-time dropout: distinct hypotheses per seed). The
    state dict is the plain U-Net's (dropout has no weights).

    Examples
    --------
    >>> g = StochasticUNet(size=32, channels=8, min_size=16, dropout=0.5).eval()
    >>> x = torch.zeros(1, 1, 32, 32)
    >>> bool(torch.equal(g(x), g(x)))              # eval: deterministic
    True
    >>> g.stochastic = True
    >>> _ = torch.manual_seed(0); a = g(x); _ = torch.manual_seed(1); b = g(x)
    >>> bool(torch.equal(a, b))
    False
    """

    def __init__(self, *args, dropout: float = 0.5, growth: str = "full", **kwargs):
        super().__init__(*args, **kwargs)
        if growth not in GROWTHS:
            raise ValueError(f"growth must be one of {', '.join(GROWTHS)}, got {growth!r}")
        self.dropout = float(dropout)
        self.stochastic = False
        self.growth = growth
        #: Output resolution of a ``"decoder"`` growth generator (its current stage).
        self.out_size = self.size
        self.config["dropout"] = self.dropout
        self.config["growth"] = growth
        levels = sorted(int(r) for r in self.up)[:3]
        for r in levels:
            self.up[str(r)].register_forward_hook(self._drop)

    def forward(self, x: torch.Tensor, alpha: torch.Tensor | None = None) -> torch.Tensor:
        if self.growth == "full":
            return super().forward(x, alpha)
        return self._forward_decoder(x, alpha, self.out_size)

    def _forward_decoder(self, x: torch.Tensor, alpha: torch.Tensor | None, r_out: int
                         ) -> torch.Tensor:
        """anime2clothing's growth: the encoder always reads the ``size`` input, the
        decoder stops at ``r_out`` (its ``to_map``); with ``alpha`` the ``r_out`` block
        fades in against the upsampled ``r_out / 2`` output."""
        r = x.shape[-1]
        if r != self.size or x.shape[-2] != r:
            raise ValueError(f"a decoder-growth generator reads {self.size} px inputs, got "
                             f"{tuple(x.shape[-2:])}")
        if str(r_out) not in self.to_map:
            raise ValueError(f"output resolution {r_out} not in {list(self.to_map)}")
        h = self.from_map[str(r)](x)
        skips = []
        while r > self.bottleneck:
            skips.append(h)
            h = self.down[str(r)](h)
            r //= 2
        h = self.middle(h)
        fade = alpha is not None and r_out > self.min_size
        return self._decode(h, skips, r, r_out, alpha if fade else None)

    def _drop(self, module, inputs, output):
        if self.dropout <= 0:
            return output
        return F.dropout(output, self.dropout, training=self.training or self.stochastic)


class ProgPatchDiscriminator(nn.Module):
    """A spectral-normalised PatchGAN that grows: a base at ``min_size`` (``n_layers``
    stride-2 4x4 convs then two 3x3, as
    :class:`~map2map.learn.nets.networks.PatchDiscriminator`) and, for every resolution ``r``
    above it, a ``from_map`` (1x1) and a stride-2 4x4 block ``r -> r/2``.

    ``forward(x, alpha=None)`` runs at ``r = x.shape[-1]``; with ``alpha`` the ``r``
    blocks fade in against ``from_map_{r/2}(area(x))``. Returns every layer's activation
    (the last: patch logits in float32).
    """

    def __init__(self, in_channels: int = 1, channels: int = 32, n_layers: int = 3,
                 size: int = 256, min_size: int = 32, max_channels: int = 256):
        super().__init__()
        if min_size < 2**n_layers:
            raise ValueError(f"the coarsest stage ({min_size} px) is smaller than the "
                             f"{2**n_layers} px {n_layers} stride-2 layers need")
        self.size, self.min_size = size, min_size
        levels = [min_size * 2**i for i in range(int(math.log2(size // min_size)) + 1)]
        self.ch = {r: min(max_channels, channels * 2 ** int(math.log2(size // r)))
                   for r in levels + [min_size // 2]}
        lrelu = nn.LeakyReLU(0.2, inplace=True)
        self.from_map = nn.ModuleDict({
            str(r): nn.Sequential(spectral_norm(nn.Conv2d(in_channels, self.ch[r], 1)), lrelu)
            for r in levels})
        self.down = nn.ModuleDict({
            str(r): nn.Sequential(spectral_norm(nn.Conv2d(self.ch[r], self.ch[r // 2], 4, 2, 1)),
                                  lrelu)
            for r in levels if r > min_size})
        base = []
        cin = self.ch[min_size]
        for i in range(n_layers):
            cout = min(max_channels, self.ch[min_size] * 2 ** (i + 1))
            base.append(nn.Sequential(spectral_norm(nn.Conv2d(cin, cout, 4, 2, 1)), lrelu))
            cin = cout
        cout = min(max_channels, cin * 2)
        base.append(nn.Sequential(spectral_norm(nn.Conv2d(cin, cout, 3, 1, 1)), lrelu))
        base.append(spectral_norm(nn.Conv2d(cout, 1, 3, 1, 1)))
        self.base = nn.ModuleList(base)

    def forward(self, x: torch.Tensor, alpha: torch.Tensor | None = None) -> list[torch.Tensor]:
        r = x.shape[-1]
        if str(r) not in self.from_map or x.shape[-2] != r:
            raise ValueError(f"input must be square with side in {list(self.from_map)}, "
                             f"got {tuple(x.shape[-2:])}")
        feats = []
        h = self.from_map[str(r)](x)
        if r > self.min_size:
            h = self.down[str(r)](h)
            if alpha is not None:
                old = self.from_map[str(r // 2)](F.avg_pool2d(x, 2))
                h = alpha * h + (1 - alpha) * old
            feats.append(h)
            r //= 2
        while r > self.min_size:
            h = self.down[str(r)](h)
            feats.append(h)
            r //= 2
        for layer in self.base:
            h = layer(h)
            feats.append(h)
        feats[-1] = feats[-1].float()
        return feats


class ProgMultiScaleDiscriminator(nn.Module):
    """``D_1..D_K`` of eq. 3.2 that grow: scale ``k`` is a
    :class:`ProgPatchDiscriminator` on the area-averaged ``r / 2^k`` map; all fade in
    with the same ``alpha``."""

    def __init__(self, in_channels: int = 1, channels: int = 32, n_layers: int = 3,
                 scales: int = 3, size: int = 256, min_size: int = 32,
                 max_channels: int = 256):
        super().__init__()
        self.config = dict(in_channels=in_channels, channels=channels, n_layers=n_layers,
                           scales=scales, size=size, min_size=min_size,
                           max_channels=max_channels)
        self.discs = nn.ModuleList(
            ProgPatchDiscriminator(in_channels, channels, n_layers, size // 2**k,
                                   min_size // 2**k, max_channels)
            for k in range(scales))

    def forward(self, x: torch.Tensor, alpha: torch.Tensor | None = None
                ) -> list[list[torch.Tensor]]:
        return [d(x if k == 0 else F.avg_pool2d(x, 2**k), alpha)
                for k, d in enumerate(self.discs)]


