"""Lazy re-exports for the package ``__init__`` modules (PEP 562).

A stage package names its public API in its ``__init__`` but imports the defining module only
when a name is first used: importing one module of a stage (``drakedeburr.plan.io``, say)
then no longer imports the whole stage and, through it, pydrake, scipy and open3d, and the
command line builds its parser without them (every command starts ~0.5 s sooner).

Why hand-written: the standard library has no helper for a module ``__getattr__`` table.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_exports(package: str, exports: dict[str, tuple[str, ...]]
                 ) -> tuple[list[str], Callable[[str], object], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` of ``package`` re-exporting, per module
    of ``exports`` (its name relative to ``package``), the names listed: each imported from
    its module on first use and kept in the package afterwards."""
    owner = {name: f"{package}.{module}" for module, names in exports.items()
             for name in names}
    names = list(owner)

    def __getattr__(name: str):
        module = owner.get(name)
        if module is None:  # AttributeError: `from package import submodule` then imports it
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(importlib.import_module(package), name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(names) | set(vars(importlib.import_module(package))))

    return names, __getattr__, __dir__
