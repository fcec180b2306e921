"""Build of the optional compiled set operations (``setobs.geometry._setops``).

Everything else is declared in ``pyproject.toml``. The extension is optional: where it
cannot be built (no C compiler), setobs installs without it and runs the same operations
in NumPy (``setobs.geometry.compiled_set_operations()`` tells which).
"""

import sys

import numpy as np
from setuptools import Extension, setup

# Each sum and product rounded on its own, as in NumPy (no fused multiply-add), so that
# the compiled rounding bounds and the NumPy ones agree.
ARGS = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]

setup(
    ext_modules=[
        Extension(
            "setobs.geometry._setops",
            ["src/setobs/geometry/_setops.c"],
            include_dirs=[np.get_include()],
            extra_compile_args=ARGS,
            optional=True,
        )
    ]
)
