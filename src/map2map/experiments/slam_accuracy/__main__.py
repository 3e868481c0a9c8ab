"""``python3 -m map2map.experiments.slam_accuracy {carmen,simulated} [ARGS]``: run one of
the two SLAM accuracy measurements with its own arguments (``ARGS``; ``--help`` lists
them). The same as ``python3 -m map2map.experiments.slam_accuracy.carmen [ARGS]`` and
``python3 -m map2map.experiments.slam_accuracy.simulated [ARGS]``.
"""

from __future__ import annotations

import sys

EXPERIMENTS = {
    "carmen": "the two real CARMEN logs against their corrected poses",
    "simulated": "simulated explorations against the plan",
}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] not in EXPERIMENTS:
        print(__doc__.strip(), file=sys.stderr)
        for name, what in EXPERIMENTS.items():
            print(f"  {name:<10s} {what}", file=sys.stderr)
        return 0 if argv[:1] in (["-h"], ["--help"]) else 2
    if argv[0] == "carmen":
        from .carmen.__main__ import main as run
    else:
        from .simulated.__main__ import main as run
    return run(argv[1:]) or 0


if __name__ == "__main__":
    sys.exit(main())
