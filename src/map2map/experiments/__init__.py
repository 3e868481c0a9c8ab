"""Experiments: the thesis's tables and figures and the accuracy measurements behind the
documented figures, one folder each.

Every experiment is a package ``map2map.experiments.<name>`` holding its script
(``__main__.py``, run as ``python -m map2map.experiments.<name> ...``) and a short
write-up of its current result (``README.md``: what it measures, the command, the
latest figures with their date and machine). Real data are read from
``$MAP2MAP_SHARED_DATA`` or ``../shared/data`` beside the working folder
(:func:`map2map.experiments._data.shared_data`); an experiment that needs them says so
when they are absent. Performance benchmarks (speed, memory) stay in the repository's
``benchmarks/`` (``python -m benchmarks.bench_sim``).

Experiments
-----------
table53
    Thesis Table 5.3 / Fig. 5.12: does Model_BA bring held-out simulated SLAM maps closer
    to their plans (its library, :mod:`~map2map.experiments.table53.measure`, is what
    ``map2map reproduce`` runs); also where the error comes from and the wall faces.
table53_real
    Table 5.3 on the Halmstad sensor maps against their floor plans.
realism
    Model_AB's synthesized maps against simulated runs of the same plans (and the
    perfect generator's null draws).
fig514
    Thesis Fig. 5.14: simulated, parametric and Model_AB maps of the same plans.
halmstad_accuracy
    The alignment on the annotated Halmstad maps: keypoint residuals against their
    floor, and which confidence warnings fire on good, bad and wrong-map pairs.
metric_accuracy
    The error metric (Algorithm 1) on maps with known wall errors: reported mean and
    max against the true ones.
align_sweep
    ``evaluate`` on plans against rotated and scaled copies of themselves: recovered,
    flagged and silently wrong alignments.
alignment_confidence
    Fits and checks ``p_correct`` (the probability that an alignment is right) on the
    sweep and the Halmstad pairs with held-out folds: reliability, the "doubtful"
    threshold and the warning rates on right and wrong alignments per data set.
inspection_truth
    The as-built inspection's wall verdicts against the known field of parametric
    deformations.
slam_accuracy
    The SLAM backends' trajectory and map error: on the two real CARMEN logs against
    their corrected poses (``slam_accuracy.carmen``) and on simulated explorations
    against the plan (``slam_accuracy.simulated``).
"""
