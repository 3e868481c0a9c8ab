"""The Model_BA networks of thesis sec. 3.1 (Fig. 3.1): a U-Net generator and two
multi-scale patch discriminators, for single-channel maps.

* :class:`UNetGenerator` -- ``G`` of eq. 3.2, a U-Net [48] built from one block per
  resolution (``from_map``/``down``/``up``/``to_map`` keyed by resolution), so the
  progressive growing of issue #15 (Model_prog, blocks added coarse to fine with a fade-in)
  only has to pick the blocks of the current resolution and pass ``alpha``: the forward
  pass already runs at whatever resolution its input has and blends the new finest block
  with the previous resolution's path when given ``alpha`` (a tensor, so a compiled graph
  is not rebuilt as it changes).
* :class:`PatchDiscriminator` -- a fully convolutional PatchGAN with spectral
  normalisation [50] on every layer (``torch.nn.utils.parametrizations.spectral_norm``);
  it returns every layer's activation, the intermediate ones feeding the feature
  matching (eq. 3.5) and input-consistency (eq. 3.6) losses.
* :class:`MultiScaleDiscriminator` -- ``D_k``, ``k = 1..3`` (the sums of eq. 3.2): the
  same patch discriminator at full, half and quarter resolution. The lower scales are
  made by **area averaging** (an exact box filter, antialiased), never by nearest
  neighbour, so one-pixel walls still darken the 1/4 image instead of vanishing.
  ``D_r`` (real/fake, eq. 3.4) sees one map; ``D_d`` (domain, eq. 3.3) sees the
  (input, output) pair stacked as two channels.

Maps enter the networks as floats in [-1, 1] (:func:`to_unit`: occupied -1, unknown ~0,
free 1) and leave through :func:`from_unit`.

Examples
--------
>>> import torch
>>> g = UNetGenerator(size=32, channels=8)
>>> x = torch.zeros(2, 1, 32, 32)
>>> g(x).shape
torch.Size([2, 1, 32, 32])
>>> d = MultiScaleDiscriminator(in_channels=2, channels=8)
>>> [f[-1].shape[-1] for f in d(torch.zeros(2, 2, 32, 32))]     # patch logits per scale
[4, 2, 1]
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn
from torch.nn.utils.parametrizations import spectral_norm

__all__ = [
    "to_unit",
    "from_unit",
    "area_downsample",
    "UNetGenerator",
    "PatchDiscriminator",
    "MultiScaleDiscriminator",
    "count_parameters",
]


def to_unit(maps: torch.Tensor) -> torch.Tensor:
    """uint8 maps (..., H, W) in {0, 127, 255} (or grey) -> float32 in [-1, 1].

    Examples
    --------
    >>> to_unit(torch.tensor([0, 255], dtype=torch.uint8)).tolist()
    [-1.0, 1.0]
    """
    return maps.float() / 127.5 - 1.0


def from_unit(t: torch.Tensor) -> np.ndarray:
    """Float maps in [-1, 1] -> float32 numpy grey values in [0, 255] (not yet snapped).

    Examples
    --------
    >>> from_unit(torch.tensor([-1.0, 0.0, 1.0])).tolist()
    [0.0, 127.5, 255.0]
    """
    return ((t.detach().float().clamp(-1, 1) + 1.0) * 127.5).cpu().numpy()


def area_downsample(x: torch.Tensor, size: int) -> torch.Tensor:
    """Area-average (N, C, H, W) down to ``size x size`` (box filter, exact for integer
    factors); returns ``x`` itself when it already has that size.

    Examples
    --------
    >>> x = torch.zeros(1, 1, 8, 8); x[..., 3] = 1.0           # a one-pixel wall
    >>> area_downsample(x, 2)[0, 0].tolist()
    [[0.25, 0.0], [0.25, 0.0]]
    """
    if x.shape[-1] == size and x.shape[-2] == size:
        return x
    return F.adaptive_avg_pool2d(x, size)


def count_parameters(module: nn.Module) -> int:
    """Number of trainable parameters.

    Examples
    --------
    >>> count_parameters(nn.Conv2d(1, 2, 3))
    20
    """
    return sum(p.numel() for p in module.parameters() if p.requires_grad)


def _norm(ch: int) -> nn.GroupNorm:
    # GroupNorm: per sample, so it works at batch 1, on a 1x1 bottleneck and under DDP
    # (no running statistics to synchronise), unlike BatchNorm/InstanceNorm.
    return nn.GroupNorm(min(8, ch), ch)


def upsample2x(h: torch.Tensor) -> torch.Tensor:
    """Bilinear x2 upsampling (``align_corners=False``) of the U-Net decoder.

    The same values as ``F.interpolate(h, scale_factor=2, mode="bilinear")``; only the
    memory layout handed to PyTorch's CUDA kernel changes (:func:`_channels_last_faster`).
    The CPU path is unchanged, bit for bit.

    Examples
    --------
    >>> upsample2x(torch.arange(4.0).reshape(1, 1, 2, 2)).shape
    torch.Size([1, 1, 4, 4])
    """
    if _channels_last_faster(h):
        h = h.contiguous(memory_format=torch.channels_last)
    return F.interpolate(h, scale_factor=2, mode="bilinear", align_corners=False)


def _channels_last_faster(h: torch.Tensor) -> bool:
    """Whether ``upsample2x`` should hand a CUDA tensor over in channels-last layout.

    PyTorch's NCHW bilinear kernel runs one thread per *output pixel*, looping over
    batch x channels; its channels-last kernel (taken from 16 channels up) runs one thread
    per output element. With few output pixels the NCHW kernel leaves the GPU nearly idle:
    on an H200 (2026-11-26, bf16) a (1024, 256, 4, 4) input took 60.0 ms NCHW against
    0.15 ms channels-last, (1024, 64, 16, 16) 24.7 against 0.60 ms, (256, 64, 32, 32) 6.3
    against 0.67 ms (copy included), and that upsampling was 75 % of a Model_32 training
    step at batch 1024. With many output pixels NCHW wins: (64, 32, 128, 128) 0.84 ms
    against 1.34 ms with the copy (1.19 without). Hence channels-last below 128 x 128
    output pixels: the NCHW kernel's ~0.4 us per loop step and thread puts the break-even
    near there for the batches used here; every Model_32/64 decoder level is below it.
    """
    n, c, hh, ww = h.shape
    return h.is_cuda and c >= 16 and 4 * hh * ww < 128 * 128


class _Block(nn.Sequential):
    """conv3x3 (stride ``stride``) - GroupNorm - LeakyReLU - conv3x3 - GroupNorm - LeakyReLU."""

    def __init__(self, cin: int, cout: int, stride: int = 1):
        super().__init__(
            nn.Conv2d(cin, cout, 3, stride, 1),
            _norm(cout),
            nn.LeakyReLU(0.2, inplace=True),
            nn.Conv2d(cout, cout, 3, 1, 1),
            _norm(cout),
            nn.LeakyReLU(0.2, inplace=True),
        )


class UNetGenerator(nn.Module):
    """U-Net generator ``G`` (thesis sec. 3.1, [48]) for single-channel maps.

    Parameters
    ----------
    size : int
        Largest resolution it runs at (a power of two, >= ``bottleneck``).
    channels : int
        Feature channels at ``size``; doubled at each halving up to ``max_channels``.
    max_channels : int
        Channel cap.
    bottleneck : int
        Resolution of the deepest level (4: the 32 model goes 32-16-8-4 and back).
    min_size : int, optional
        Smallest resolution it may run at (progressive growing starts there); blocks
        exist for every power of two from ``min_size`` to ``size``. Default ``size``.

    Notes
    -----
    ``forward(x, alpha=None)`` runs at ``r = x.shape[-1]``. With ``alpha`` (a scalar
    tensor in [0, 1]) the block of resolution ``r`` fades in (ProGAN): on the way down the
    features are ``alpha * down_r(from_map_r(x)) + (1 - alpha) * from_map_{r/2}(x_{r/2})``
    and the output is ``alpha * to_map_r(.) + (1 - alpha) * up2(to_map_{r/2}(.))``. The
    output head (1x1 conv + tanh) always runs in float32, also under bf16 autocast.
    """

    def __init__(
        self,
        size: int = 32,
        channels: int = 32,
        max_channels: int = 256,
        bottleneck: int = 4,
        min_size: int | None = None,
    ):
        super().__init__()
        min_size = size if min_size is None else min_size
        for v, name in ((size, "size"), (bottleneck, "bottleneck"), (min_size, "min_size")):
            if v < 1 or v & (v - 1):
                raise ValueError(f"{name} must be a power of two, got {v}")
        if not bottleneck <= min_size <= size:
            raise ValueError("need bottleneck <= min_size <= size")
        self.size, self.bottleneck, self.min_size = size, bottleneck, min_size
        self.config = dict(size=size, channels=channels, max_channels=max_channels,
                           bottleneck=bottleneck, min_size=min_size)
        levels = [bottleneck * 2**i for i in range(int(math.log2(size // bottleneck)) + 1)]
        self.ch = {r: min(max_channels, channels * 2 ** int(math.log2(size // r))) for r in levels}
        ch = self.ch
        self.from_map = nn.ModuleDict()
        self.to_map = nn.ModuleDict()
        self.down = nn.ModuleDict()
        self.up = nn.ModuleDict()
        for r in levels:
            if r >= min_size:
                self.from_map[str(r)] = nn.Sequential(nn.Conv2d(1, ch[r], 1),
                                                      nn.LeakyReLU(0.2, inplace=True))
                self.to_map[str(r)] = nn.Conv2d(ch[r], 1, 1)
            if r > bottleneck:
                self.down[str(r)] = _Block(ch[r], ch[r // 2], stride=2)
                self.up[str(r)] = _Block(ch[r // 2] + ch[r], ch[r])
        self.middle = _Block(ch[bottleneck], ch[bottleneck])

    def _head(self, h: torch.Tensor, r: int) -> torch.Tensor:
        with torch.autocast(h.device.type, enabled=False):
            return self.to_map[str(r)](h.float())

    def forward(self, x: torch.Tensor, alpha: torch.Tensor | None = None) -> torch.Tensor:
        r = x.shape[-1]
        if str(r) not in self.from_map or x.shape[-2] != r:
            raise ValueError(f"input must be square with side in {list(self.from_map)}, "
                             f"got {tuple(x.shape[-2:])}")
        fade = alpha is not None and r > self.min_size
        h = self.from_map[str(r)](x)
        skips = []
        if fade:
            skips.append(h)
            h = self.down[str(r)](h)
            old = self.from_map[str(r // 2)](area_downsample(x, r // 2))
            h = alpha * h + (1 - alpha) * old
            r //= 2
        while r > self.bottleneck:
            skips.append(h)
            h = self.down[str(r)](h)
            r //= 2
        h = self.middle(h)
        return self._decode(h, skips, r, x.shape[-1], alpha if fade else None)

    def _decode(self, h: torch.Tensor, skips: list[torch.Tensor], r: int, top: int,
                alpha: torch.Tensor | None) -> torch.Tensor:
        """Decoder from the bottleneck (side ``r``) up to side ``top``, skips popped.

        With ``alpha`` the ``top`` block fades in against the upsampled output of the
        level below (the progressive fade-in of thesis 3.1).
        """
        old = None
        while r < top:
            if alpha is not None and r * 2 == top:
                old = upsample2x(self._head(h, r))
            h = upsample2x(h)
            r *= 2
            h = self.up[str(r)](torch.cat([h, skips.pop()], 1))
        out = self._head(h, r)
        if old is not None:
            out = alpha * out + (1 - alpha) * old
        return torch.tanh(out)


class PatchDiscriminator(nn.Module):
    """Spectral-normalised PatchGAN [51]: ``n_layers`` stride-2 4x4 convs, then two 3x3.

    ``forward`` returns the list of every layer's activation; the last entry is the
    patch logits (one per receptive field), in float32.
    """

    def __init__(self, in_channels: int = 1, channels: int = 32, n_layers: int = 3,
                 max_channels: int = 256):
        super().__init__()
        self.n_layers = n_layers
        layers = []
        cin = in_channels
        for i in range(n_layers):
            cout = min(max_channels, channels * 2**i)
            layers.append(nn.Sequential(spectral_norm(nn.Conv2d(cin, cout, 4, 2, 1)),
                                        nn.LeakyReLU(0.2, inplace=True)))
            cin = cout
        cout = min(max_channels, cin * 2)
        layers.append(nn.Sequential(spectral_norm(nn.Conv2d(cin, cout, 3, 1, 1)),
                                    nn.LeakyReLU(0.2, inplace=True)))
        layers.append(spectral_norm(nn.Conv2d(cout, 1, 3, 1, 1)))
        self.layers = nn.ModuleList(layers)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:
        if min(x.shape[-2:]) < 2**self.n_layers:
            raise ValueError(f"patch discriminator needs inputs >= {2**self.n_layers} px, "
                             f"got {tuple(x.shape[-2:])}")
        feats = []
        for layer in self.layers:
            x = layer(x)
            feats.append(x)
        feats[-1] = feats[-1].float()
        return feats


class MultiScaleDiscriminator(nn.Module):
    """``D_1, D_2, D_3`` of eq. 3.2: patch discriminators at scales 1, 1/2, 1/4 (area).

    ``forward`` returns one feature list per scale (see :class:`PatchDiscriminator`).
    """

    def __init__(self, in_channels: int = 1, channels: int = 32, n_layers: int = 3,
                 scales: int = 3, max_channels: int = 256):
        super().__init__()
        self.config = dict(in_channels=in_channels, channels=channels, n_layers=n_layers,
                           scales=scales, max_channels=max_channels)
        self.discs = nn.ModuleList(
            PatchDiscriminator(in_channels, channels, n_layers, max_channels)
            for _ in range(scales)
        )

    def forward(self, x: torch.Tensor) -> list[list[torch.Tensor]]:
        out = []
        for k, d in enumerate(self.discs):
            out.append(d(x if k == 0 else F.avg_pool2d(x, 2**k)))
        return out
