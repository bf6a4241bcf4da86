"""Optional dependencies: import one, or say which extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["require"]

#: Module -> how to get it.
_HOW = {
    "pandas": 'python -m pip install -e ".[pandas]" (or pip install pandas)',
    "matplotlib.pyplot": 'python -m pip install -e ".[plot]" (the `plot` extra, matplotlib)',
}


def require(module: str, what: str) -> ModuleType:
    """Import ``module`` for ``what`` (e.g. ``"Solution.plot()"``), or raise an ImportError
    that names the missing package and how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(f"{what} needs {module.split('.')[0]}, which is not installed: "
                          f"{_HOW.get(module, f'pip install {module}')}") from None
