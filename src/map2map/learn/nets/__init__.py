"""The networks of both models: :mod:`~map2map.learn.nets.networks` (U-Net generator,
multi-scale patch discriminators), :mod:`~map2map.learn.nets.progressive` (their growing
versions, thesis 3.1) and :mod:`~map2map.learn.nets.losses` (eq. 3.2's terms)."""
