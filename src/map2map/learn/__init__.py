"""Learned map translation (thesis sec. 3.1, 4.2, 5.1): Model_BA, the SLAM -> CAD
"auto-correct" GAN, and Model_AB, the CAD -> SLAM GAN grown progressively (Model_prog).

PyTorch is imported only inside this package (``pip install 'map2map[learn]'``), and not by
the config modules, so the command line reads the defaults without it. By role:

* :mod:`~map2map.learn.nets` -- the networks: U-Net generator and multi-scale patch
  discriminators (``networks``), their progressive growing (``progressive``), the terms of
  eq. 3.2 (``losses``, eqs. 3.3-3.7);
* :mod:`~map2map.learn.training` -- what both models' training shares: the settings
  (``config``, Table 5.1), the data resident on the device (``data``), the eq. 3.2 step
  (``step``, and ``static_step`` for CUDA graphs), the loop with DDP, exact resume, logs and
  figures (``loop``, ``figures``), safetensors checkpoints (``checkpoint``) and generated
  pairs for tests (``synthetic``);
* :mod:`~map2map.learn.ba` -- Model_BA whole: ``config``, ``model`` (networks, header,
  load, export, shipped weights), ``train``, ``autocorrect`` and the drawing of its walls
  (``squares``, ``postprocess``, ``anchor``, ``faces``, ``pieces``);
* :mod:`~map2map.learn.ab` -- Model_AB whole: ``config`` (Table 5.2), ``model``,
  ``train``, ``synthesize`` and what turns its output into SLAM-like maps (``render``,
  ``drift``, ``room_drift``, ``coverage``).

The experiments that measure the models (Table 5.3, realism, Fig. 5.14) live in
:mod:`map2map.experiments`; the commands run through :mod:`map2map.jobs`.
"""
