"""Calibrated confidence of an alignment: ``p_correct``, fitted on known-right and wrong cases.

:mod:`.collect` runs the labelled alignments (the synthetic sweep, the Halmstad sensor map
<-> layout pairs, sensor maps against the other building's layout) and caches their
quality figures; ``python3 -m map2map.experiments.alignment_confidence`` refits the
logistic model of :mod:`map2map.evaluate.confidence` on them with held-out folds grouped
by plan or building, prints the held-out reliability, the threshold of the "doubtful"
warning and the warning rates on right and wrong alignments per data set, and writes a
reliability figure. Current result: ``README.md`` beside this file.
"""
