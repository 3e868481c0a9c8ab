"""Model_AB's settings (:class:`ABConfig`) and Table 5.2's schedule of the growing
networks (thesis sec. 3.1, Tables 5.1-5.2): which stage an epoch is in and how long a
new resolution fades in (:mod:`~map2map.learn.nets.progressive` has the networks).

Examples
--------
>>> cfg = ABConfig()
>>> [stage_of(e, cfg.schedule)[1] for e in (0, 14, 15, 44, 45, 104, 105, 204)]
[32, 32, 64, 64, 128, 128, 256, 256]
>>> [cfg.stage_batch(r) for r, _ in cfg.schedule]          # Table 5.1, batch_rate 1
[64, 32, 16, 4]
"""

from __future__ import annotations

from dataclasses import dataclass

from ..training.config import TrainConfig, batch_size

__all__ = ["ABConfig", "TABLE_5_2", "GROWTHS", "POSE_ERRORS", "parse_schedule", "stage_of",
           "fade_steps"]

#: Generator growths: the thesis's reading (everything at the stage's resolution) and
#: anime2clothing's (full-size input, the decoder exits early).
GROWTHS = ("full", "decoder")

#: Where ``synthesize --model scans``' pose error comes from
#: (:class:`~map2map.learn.ab.scans.ScanMapParams` ``pose_error``): the exploring particle
#: filter's own estimate, drawn by hand, or drawn by the learned model.
POSE_ERRORS = ("filter", "drawn", "learned")


#: Table 5.2: (current resolution, epochs at it).
TABLE_5_2 = ((32, 15), (64, 30), (128, 60), (256, 100))


def parse_schedule(text: str) -> tuple[tuple[int, int], ...]:
    """``"32:15,64:30"`` -> ((32, 15), (64, 30)); resolutions powers of two, increasing.

    Examples
    --------
    >>> parse_schedule("16:2, 32:3")
    ((16, 2), (32, 3))
    """
    out = []
    for part in str(text).split(","):
        try:
            r, e = (int(v) for v in part.strip().split(":"))
        except ValueError:
            raise ValueError(f"schedule entries are RES:EPOCHS, got {part.strip()!r}") from None
        out.append((r, e))
    return _check_schedule(out)


def _check_schedule(sched) -> tuple[tuple[int, int], ...]:
    sched = tuple((int(r), int(e)) for r, e in sched)
    if not sched:
        raise ValueError("empty schedule")
    for i, (r, e) in enumerate(sched):
        if r < 4 or r & (r - 1):
            raise ValueError(f"schedule resolution {r} is not a power of two >= 4")
        if e < 1:
            raise ValueError(f"schedule stage {r} needs >= 1 epoch, got {e}")
        if i and r != 2 * sched[i - 1][0]:
            raise ValueError("schedule resolutions must double from one stage to the next "
                             f"(got {sched[i - 1][0]} then {r})")
    return sched


@dataclass
class ABConfig(TrainConfig):
    """Every setting of a Model_AB (Model_prog) run: :class:`TrainConfig`'s plus the growth.

    Parameters
    ----------
    schedule : tuple of (int, int)
        (resolution, epochs) per stage, coarse to fine (default Table 5.2). ``size`` is
        set to the last stage's resolution; ``epochs`` defaults to the schedule's sum
        (more epochs stay at the last resolution, fewer stop early).
    batch_rate : float
        1 for Model_AB (thesis 5.1); batch per stage ``batch_rate * Table 5.1``.
    fade_share : float
        Fade-in length as a share of the new stage's batches (0.5: ProGAN's equal fade
        and stabilise phases); ignored when ``fade_batches`` is set.
    fade_batches : int or None
        Fade-in length in batches, the same for every stage.
    dropout : float
        Dropout on the three coarsest decoder levels (pix2pix's noise source), active in
        training and, for :func:`~map2map.learn.ab.synthesize.synthesize`, at test time: one
        plan, several SLAM-map hypotheses.
    growth : {"full", "decoder"}
        ``"full"`` (default, the thesis's reading): at stage ``r`` the generator reads
        and writes ``r x r`` maps. ``"decoder"`` (anime2clothing's): the generator always
        reads the last stage's ``size`` input and its decoder exits at ``r``; the
        discriminators grow alike in both (they see the ``r`` output either way), so
        the two differ only in the generator's growth.
    """

    schedule: tuple = TABLE_5_2
    epochs: int = 0
    size: int = 0
    batch_rate: float = 1.0
    fade_share: float = 0.5
    fade_batches: int | None = None
    dropout: float = 0.5
    g_max_channels: int = 256
    growth: str = "full"

    def __post_init__(self):
        if self.growth not in GROWTHS:
            raise ValueError(f"growth must be one of {', '.join(GROWTHS)}, got {self.growth!r}")
        self.schedule = _check_schedule(self.schedule)
        if not self.size:
            self.size = self.schedule[-1][0]
        if self.size != self.schedule[-1][0]:
            raise ValueError(f"size {self.size} differs from the schedule's last resolution")
        if not self.epochs:
            self.epochs = sum(e for _, e in self.schedule)
        if not 0.0 <= self.dropout < 1.0:
            raise ValueError("dropout must be in [0, 1)")

    @property
    def min_size(self) -> int:
        return self.schedule[0][0]

    def stage_batch(self, r: int) -> int:
        """Batch size at resolution ``r``: ``batch`` or Table 5.1 x ``batch_rate``."""
        return self.batch if self.batch else batch_size(r, self.batch_rate)

    def to_dict(self) -> dict:
        d = super().to_dict()
        d["schedule"] = [list(s) for s in self.schedule]
        return d


def stage_of(epoch: int, schedule) -> tuple[int, int, int]:
    """(stage index, resolution, first epoch of that stage) of 0-based ``epoch``."""
    start = 0
    for i, (r, e) in enumerate(schedule):
        if epoch < start + e or i == len(schedule) - 1:
            return i, r, start
        start += e
    raise AssertionError  # pragma: no cover


def fade_steps(stage: int, n_batches: int, cfg: ABConfig) -> int:
    """Batches over which stage ``stage``'s new blocks fade in (0 for the first stage)."""
    if stage == 0:
        return 0
    if cfg.fade_batches is not None:
        return max(0, int(cfg.fade_batches))
    epochs = cfg.schedule[stage][1]
    return max(1, int(round(cfg.fade_share * epochs * n_batches)))
