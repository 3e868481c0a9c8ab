"""``map2map reproduce``: every quantitative result of the thesis and its appendix, re-run.

One module per section, each a function ``run(ctx, out)`` that measures with this
project's code and writes a section of the report with the thesis's number beside ours
and one sentence on each difference:

=======================  =====================================================================
:mod:`.parametric_time`  Table 5.4 / Fig. 5.13: parametric model run time, EKF vs additive
:mod:`.fig515`           Fig. 5.15: plan, trajectory, displacement field, deformed map
:mod:`.table2`           Appendix Table 2: synthetic maps with known errors vs the truth
:mod:`.halmstad`         Appendix Tables 3-4 in spirit: real sensor maps vs their plans
:mod:`.table53`          Table 5.3 / Fig. 5.12: Model_BA, SLAM map -> CAD-like plan
:mod:`.fig514`           Fig. 5.3 / 5.14: Model_AB vs parametric vs simulated SLAM maps
:mod:`.dataset`          Thesis 4.1: dataset build rate and cleaning yield
:mod:`.runner`           :func:`reproduce`: runs them, writes the report and results.json
=======================  =====================================================================

Examples
--------
>>> from map2map.reports.reproduce import SECTIONS
>>> list(SECTIONS)[:3]
['parametric_time', 'fig515', 'table2']
"""

from .runner import EXIT_SECTION_FAILED, SECTIONS, ReproduceSummary, reproduce

__all__ = ["EXIT_SECTION_FAILED", "SECTIONS", "ReproduceSummary", "reproduce"]
