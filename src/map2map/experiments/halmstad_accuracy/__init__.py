"""Accuracy of the alignment on the annotated Halmstad maps, and which warnings it carries.

Every Halmstad sensor map is evaluated against its building's layout in both directions
(36 pairs) with :func:`map2map.evaluate.pipeline.evaluate_maps`; the annotated keypoints,
mapped through the similarity and the nonrigid chain, are compared with their annotated
counterparts against the floor of a similarity fitted to the annotations themselves. Four
wrong-map pairs (a sensor map against the other building's layout) must all warn. This is
the calibration set of :mod:`map2map.evaluate.confidence`.

Run ``python3 -m map2map.experiments.halmstad_accuracy --help``; needs
``../shared/data/halmstad``. Current result: ``README.md`` beside this file.
"""
