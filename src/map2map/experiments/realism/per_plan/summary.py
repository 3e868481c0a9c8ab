"""The per-plan realism benchmark's ``--json`` report in sentences (issue #33: "reproduce
carries them with one sentence each")."""

from __future__ import annotations

import numpy as np

from ..ranks import ALPHA, holm

__all__ = ["sentences", "GENERATORS"]

#: Report names of the generators summarised (Model_AB's, and ``synthesize --model scans``).
GENERATORS = ("Model_AB", "AB:", "scans")


def sentences(report: dict) -> list[str]:
    """One sentence per test of a ``--json`` report (for ``map2map reproduce``): the
    ranks and the classifier of each Model_AB generator, and the diversity.

    Examples
    --------
    >>> r = {"plans": 600, "ranks": {"Model_AB synthesize": [
    ...     {"statistic": "unknown", "extreme": 0.9, "low": 0.05, "high": 0.85, "met": False},
    ...     {"statistic": "bend", "extreme": 0.5, "low": 0.25, "high": 0.25, "met": True}]},
    ...     "classifier": {"run 2 (floor)": {"auc": 0.52},
    ...                    "Model_AB synthesize": {"auc": 0.99}}, "diversity": {}}
    >>> import textwrap
    >>> for line in sentences(r): print(textwrap.fill(line, 88))
    Model_AB synthesize, ranked among three simulated SLAM maps of each of 600 held-out
    plans, is the most extreme on 90 % of plans for unknown (a perfect generator: 50 %) and
    passes issue #33's rank target on 1 of 2 statistics.
    A CNN tells Model_AB synthesize's maps from simulated ones with AUC 0.99 on plans it
    never saw (two simulated runs: 0.52; target: at most 0.05 above).
    >>> for row, p in zip(r["ranks"]["Model_AB synthesize"], (1e-9, 0.4)):
    ...     row["p_uniform"] = p              # as rank_table's rows carry it
    >>> sentences(r)[0].rsplit("; ", 1)[1]
    "Holm's test over the statistics tells it apart on 1 of 2."
    >>> r["classifier"]["Model_AB synthesize"].update(sd=0.012, aucs=[0.98, 0.99, 1.0])
    >>> sentences(r)[1].split(" on plans")[0][-40:]
    'AUC 0.99 +- 0.01 over 3 classifier seeds'
    >>> r.update(diversity={"scans": {"ratio": 1.01}}, diversity_plans=200)
    >>> sentences(r)[-1].split("(")[1]   # a diversity measured on fewer plans says so
    'target 0.8-1.25, on the first 200 plans); no network is involved.'
    """
    out = []
    n = report.get("plans")
    for name, rows in report.get("ranks", {}).items():
        if not name.startswith(GENERATORS):
            continue
        valid = [r for r in rows if r.get("met") is not None]
        if not valid:
            continue
        worst = max(valid, key=lambda r: r["extreme"])
        adj = holm([r.get("p_uniform", float("nan")) for r in valid])
        tested = int(np.isfinite(adj).sum())
        calibrated = (f"; Holm's test over the statistics tells it apart on "
                      f"{int((adj < ALPHA).sum())} of {tested}" if tested else "")
        out.append(f"{name}, ranked among three simulated SLAM maps of each of {n} held-out "
                   f"plans, is the most extreme on {100 * worst['extreme']:.0f} % of plans "
                   f"for {worst['statistic']} (a perfect generator: 50 %) and passes issue "
                   f"#33's rank target on {sum(r['met'] for r in valid)} of {len(valid)} "
                   f"statistics{calibrated}.")
    cl = report.get("classifier", {})
    floor = cl.get("run 2 (floor)", {}).get("auc")
    for name, c in cl.items():
        if name.startswith(GENERATORS) and floor is not None:
            seeds = len(c.get("aucs", ()))
            spread = (f" +- {c['sd']:.2f} over {seeds} classifier seeds" if seeds > 1
                      else "")
            out.append(f"A CNN tells {name}'s maps from simulated ones with AUC "
                       f"{c['auc']:.2f}{spread} on plans it never saw (two simulated runs: "
                       f"{floor:.2f}; target: at most 0.05 above).")
    for m, d in report.get("diversity", {}).items():
        if m == "simulated":
            continue
        what = (f"the network's dropout makes {100 * d['network_share']:.0f} % of that spread"
                if "network_share" in d else "no network is involved")
        on = (f", on the first {report['diversity_plans']} plans"
              if "diversity_plans" in report else "")
        out.append(f"Three synthesize{'' if m == 'scans' else ' --model ' + m} hypotheses "
                   f"of a plan differ {d['ratio']:.2f} times as much as three simulated runs "
                   f"(target 0.8-1.25{on}); {what}.")
    return out
