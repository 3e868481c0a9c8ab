"""Known-similarity sweep of ``evaluate``: recovered, flagged and silently wrong alignments.

Every plan (HouseExpo renders, generated apartments and offices, irregular HouseExpo-style
plans) is evaluated against copies of itself rotated and scaled by known amounts; a case is
recovered, flagged (wrong but warned) or silently wrong (the outcome that must not happen).
Target: 0 silently wrong, >= 96 % recovered.

Run ``python3 -m map2map.experiments.align_sweep --help`` (``--quick``: 12 cases); the
HouseExpo plans need ``../shared/data/houseexpo`` and are skipped, with a message, without
it. Current result: ``README.md`` beside this file.
"""
