"""Learned map translation (thesis sec. 3.1, 4.2, 5.1): Model_BA, the SLAM -> CAD
"auto-correct" GAN, and Model_AB, the CAD -> SLAM GAN grown progressively (Model_prog),
with their training loops, checkpoints and inference.

PyTorch is imported only inside this package (``pip install 'map2map[learn]'``);
``import map2map`` stays light. Modules:

* :mod:`~map2map.learn.nets.networks` -- U-Net generator, multi-scale patch discriminators;
* :mod:`~map2map.learn.nets.losses` -- the terms of eq. 3.2 (eqs. 3.3-3.7), one function each;
* :mod:`~map2map.learn.training.config` -- :class:`TrainConfig` and Table 5.1's batch mapping;
* :mod:`~map2map.learn.training.data` -- the training set resident on the device, batches by index;
* :mod:`~map2map.learn.training.checkpoint` -- safetensors checkpoints (no pickle);
* :mod:`~map2map.learn.training.loop` -- the training loop both models share (the eq. 3.2 step,
  DDP, checkpoints and exact resume, logs, figures, progress);
* :mod:`~map2map.learn.training.static_step` -- the same step on static buffers, replayed as one
  CUDA graph (``--cuda-graph``), and :func:`count_ops` (operator calls per step);
* :mod:`~map2map.learn.ba.train` -- :func:`train_ba` (``map2map train ba``);
* :mod:`~map2map.learn.ba.postprocess` -- post-processing of Model_32/64 (upsample, snap, straighten);
* :mod:`~map2map.learn.ba.autocorrect` -- :func:`autocorrect` (``map2map autocorrect``);
* :mod:`~map2map.learn.training.synthetic` -- provisional generated pairs (tests, provisional weights);
* :mod:`~map2map.learn.training.figures` -- loss curves (Fig. 5.2), sample grids, before/after;
* :mod:`~map2map.learn.nets.progressive` -- Model_prog: growing generator and discriminators,
  Table 5.2's schedule, the fade-in alpha, :class:`ABConfig`;
* :mod:`~map2map.learn.ab.train` -- :func:`train_ab` (``map2map train ab``, Fig. 5.1);
* :mod:`~map2map.learn.ab.synthesize` -- K SLAM-map hypotheses of a plan (``map2map
  synthesize``) and their diversity;
* :mod:`~map2map.learn.ab.coverage` -- a hypothesis's own simulated exploration of the plan
  (``oracle`` mapper): what it did not see turns unknown, its path drives the drift
  (``synthesize --coverage explore --drift-route explore``, opt-in);
* :mod:`~map2map.experiments.realism.measure` -- issue #15's realism statistics of generated SLAM maps
  against two simulated runs of the same plans (numpy only);
* :mod:`~map2map.experiments.fig514.measure` -- Fig. 5.14: simulated | parametric (same trajectory) |
  Model_AB, with appendix-metric error and wall recall.

* :mod:`~map2map.experiments.table53.measure` -- thesis Table 5.3 / Fig. 5.12 (:func:`run_table53`) on
  held-out pairs of a dataset build (:func:`heldout_pairs_from_dataset`) or generated ones.

Wall recall, boundary F1, Chamfer distance and per-class IoU (the guards of Table 5.3)
live in :mod:`map2map.evaluate.wallmetrics`, a lower layer.
"""
