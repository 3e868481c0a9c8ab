"""Where the experiments find the real data (``../shared/data``), and what they say when
it is absent.

The real data (HouseExpo, Halmstad, CARMEN logs; see ``../shared/data/README.md``) are
not part of the package: ``$MAP2MAP_SHARED_DATA`` names their folder, else
``../shared/data`` beside the working folder (the repository root when run from it), as
for ``map2map reproduce`` and the tests.

Examples
--------
>>> from pathlib import Path
>>> isinstance(shared_data(), Path)
True
"""

from __future__ import annotations

import os
from pathlib import Path


def shared_data() -> Path:
    """The real-data folder: ``$MAP2MAP_SHARED_DATA``, else ``../shared/data`` beside the
    working folder. Returned whether or not it exists: callers check the subfolder they
    need and say where they looked.

    Returns
    -------
    Path
        The folder (not resolved, not checked).

    Examples
    --------
    >>> shared_data().name if "MAP2MAP_SHARED_DATA" not in os.environ else "data"
    'data'
    """
    env = os.environ.get("MAP2MAP_SHARED_DATA")
    return Path(env) if env else Path.cwd().parent / "shared" / "data"
