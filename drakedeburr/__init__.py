"""drakedeburr: plan and verify robot deburring paths for wheel-hub windows with Drake.

The public API is re-exported lazily (heavy libraries such as pydrake and open3d load only
when the name is first used).
"""

from __future__ import annotations

import importlib
import logging

__version__ = "0.1.0"

logging.getLogger(__name__).addHandler(logging.NullHandler())

# public name -> module that defines it
_EXPORTS: dict[str, str] = {
    "ProcessParameters": "drakedeburr.config",
    "Tolerances": "drakedeburr.config",
    "InputError": "drakedeburr.errors",
    "VerificationFailed": "drakedeburr.errors",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'drakedeburr' has no attribute {name!r}")
