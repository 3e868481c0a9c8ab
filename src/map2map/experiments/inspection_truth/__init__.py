"""Do the inspection's wall verdicts fit the truth? (issue #34, item 3.)

Plans are deformed by the parametric CAD -> SLAM model (thesis 3.2), whose displacement
field is known, scaled so that some walls move less than the tolerance and some more;
the deformed map is evaluated against its plan and inspected
(:func:`map2map.evaluate.walls.inspect_walls`). A wall's **true deviation** is the
p95, along its observed length, of the field's displacement across the wall after the
evaluation's own alignment (the chain the verdict used) maps it back. A verdict agrees
with the truth unless the wall fails while truly within the tolerance, or passes while
truly beyond it (``uncertain`` never contradicts). The script is ``__main__``
(``python -m map2map.experiments.inspection_truth --help``); README.md has the result.
"""
