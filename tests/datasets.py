"""Where the shared measured records are (never copied into the repository or package).

Looked up in ``$SETOBS_DATA``, then ``<repo>/../shared/data``, then
``/work/shared/data``; tests that need a record skip when it is absent.
"""

from __future__ import annotations

import os
from pathlib import Path

_REPO = Path(__file__).resolve().parents[1]


def shared_data(relative: str) -> Path | None:
    """The first existing ``<data dir>/<relative>``, or ``None``."""
    roots = [os.environ.get("SETOBS_DATA"), _REPO.parent / "shared" / "data",
             "/work/shared/data"]
    for root in roots:
        if root and (Path(root) / relative).exists():
            return Path(root) / relative
    return None


HSM150 = shared_data("hsm150/idf_pos_0.06_1.mat")

if HSM150 is None and os.environ.get("SETOBS_REQUIRE_DATA") == "1":
    raise RuntimeError("SETOBS_REQUIRE_DATA=1 but the HSM150 record was not found "
                       "($SETOBS_DATA, <repo>/../shared/data, /work/shared/data): the tests "
                       "that need it would silently skip")
