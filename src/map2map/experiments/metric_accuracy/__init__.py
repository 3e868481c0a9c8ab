"""Accuracy of the error metric (Algorithm 1) on maps whose wall errors are known exactly.

Generated office plans are rebuilt with walls moved by known amounts, bent by smooth known
displacement fields, or deformed by the parametric CAD->SLAM model's field
(:func:`map2map.evaluate.validation.known_error_case`); the metric's reported mean and max
local error are compared with the true ones (target: within 5 %).

Run ``python3 -m map2map.experiments.metric_accuracy``; synthetic, no data needed.
Current result: ``README.md`` beside this file.
"""
