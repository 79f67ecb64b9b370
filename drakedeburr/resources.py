"""Where the bundled models live: the only module that knows.

Models are written by us under the top-level ``models/`` folder of the source checkout. A wheel
ships the same tree as ``drakedeburr/models`` (see setup.py). ``package://drakedeburr/...``
URLs used in SDF/URDF/scenario files resolve through :func:`add_package_to` which registers
that folder with a Drake ``PackageMap``.
"""

from __future__ import annotations

import functools
from pathlib import Path

__all__ = [
    "PACKAGE_NAME",
    "models_dir",
    "model_path",
    "hubs_dir",
    "hub_dir",
    "hub_names",
    "resolve_hub_dir",
    "scenario_path",
    "scenario_names",
    "add_package_to",
    "resolve_package_url",
    "arm_file_path",
    "extdata_dir",
]

PACKAGE_NAME = "drakedeburr"


@functools.cache
def models_dir() -> Path:
    """Absolute path of the ``models/`` tree (installed wheel first, then source checkout)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "models", here.parent / "models"):
        if (candidate / "package.xml").is_file():
            return candidate
    raise FileNotFoundError(
        f"drakedeburr models not found: looked for package.xml in {here / 'models'} "
        f"(installed wheel) and {here.parent / 'models'} (source checkout)"
    )


def model_path(relative: str) -> Path:
    """Path of a file under ``models/``, e.g. ``model_path('robots/irb1600_10_120.urdf')``."""
    path = models_dir() / relative
    if not path.exists():
        raise FileNotFoundError(f"no bundled model {relative!r} (looked in {models_dir()})")
    return path


def hubs_dir() -> Path:
    return models_dir() / "hubs"


def hub_names() -> list[str]:
    """Names of the bundled hub models (folders of ``models/hubs`` holding a ``hub.yaml``)."""
    if not hubs_dir().is_dir():
        return []
    return sorted(p.name for p in hubs_dir().iterdir() if (p / "hub.yaml").is_file())


def hub_dir(name: str) -> Path:
    path = hubs_dir() / name
    if not (path / "hub.yaml").is_file():
        raise FileNotFoundError(
            f"no bundled hub {name!r}; available: {', '.join(hub_names()) or '(none)'}"
        )
    return path


def resolve_hub_dir(name_or_dir: str | Path) -> Path:
    """A hub folder from a bundled name (``h5_split``), a folder, or a file inside it."""
    path = Path(name_or_dir)
    if path.is_file() and path.name in ("hub.yaml", "hub.sdf", "hub.obj", "edges.npz"):
        path = path.parent
    if path.is_dir():
        if not (path / "hub.yaml").is_file():
            raise FileNotFoundError(f"{path}: not a hub model folder (no hub.yaml)")
        return path.resolve()
    return hub_dir(str(name_or_dir))


def scenario_names() -> list[str]:
    return sorted(p.stem for p in (models_dir() / "scenarios").glob("*.yaml"))


def scenario_path(name_or_path: str | Path) -> Path:
    """A scenario by bundled name (``tool_in_hand``) or by file path."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") and path.is_file():
        return path.resolve()
    bundled = models_dir() / "scenarios" / f"{name_or_path}.yaml"
    if bundled.is_file():
        return bundled
    raise FileNotFoundError(
        f"no scenario {str(name_or_path)!r}: not a file and not one of "
        f"{', '.join(scenario_names()) or '(none)'}"
    )


def add_package_to(package_map) -> None:
    """Register ``package://drakedeburr/`` with a ``pydrake.multibody.parsing.PackageMap``."""
    if not package_map.Contains(PACKAGE_NAME):
        package_map.Add(PACKAGE_NAME, str(models_dir()))


def resolve_package_url(url: str) -> Path:
    """Turn ``package://drakedeburr/x/y`` into a file path without Drake."""
    prefix = f"package://{PACKAGE_NAME}/"
    if not url.startswith(prefix):
        raise ValueError(f"not a {prefix} URL: {url!r}")
    return models_dir() / url[len(prefix):]


def arm_file_path(name: str) -> Path:
    """The bundled arm file of a registry arm: ``models/robots/<name>.yaml``."""
    path = models_dir() / "robots" / f"{name}.yaml"
    if not path.is_file():
        raise FileNotFoundError(f"no bundled arm file {path}")
    return path


def extdata_dir() -> Path | None:
    """``../shared/extdata`` next to a source checkout (tests only); None when absent.

    ``$DRAKEDEBURR_EXTDATA`` overrides the search (e.g. for a git worktree elsewhere).
    """
    import os

    here = Path(__file__).resolve().parent.parent
    env = os.environ.get("DRAKEDEBURR_EXTDATA")
    candidates = [Path(env)] if env else []
    candidates += [here.parent / "shared" / "extdata", here / "shared" / "extdata"]
    for candidate in candidates:
        if candidate.is_dir():
            return candidate
    return None
