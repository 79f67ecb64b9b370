"""Project exceptions. Each message names the file/item and what was wrong."""

from __future__ import annotations

__all__ = ["DrakeDeburrError", "InputError", "NoCuttableWindow", "VerificationFailed",
           "numerical_errors", "describe_numerical_error"]


class DrakeDeburrError(Exception):
    """Base class of drakedeburr's own errors."""


class InputError(DrakeDeburrError, ValueError):
    """Bad user input: a file, an argument or an item in a file. Exit code 2 in the CLI."""


class NoCuttableWindow(InputError):
    """A readable hub mesh whose through-openings are none of them a window the burr can cut
    (too narrow, an edge that leaves the face, ...). Not bad input in the CLI: the hub was
    read and the result is that nothing can be cut, so exit 1 with the reasons (``verify``
    writes them as a report). Subclasses InputError for library callers that refuse it.

    Attributes:
        source: the mesh file (or label). axis: the hub axis looked along (file frame).
        openings: one dict per opening not taken (``kind``, ``reason``, ``radius_mm``, ...).
        rejected: one dict per closed outline rejected as a window edge (``center_xy_mm``,
            ``reason``).
        notes: what the import changed on the way (e.g. a tyre dropped), for the report.
    """

    def __init__(self, message: str, *, source: str, axis, openings: list, rejected: list):
        super().__init__(message)
        self.source = source
        self.axis = [float(x) for x in axis]
        self.openings = list(openings)
        self.rejected = list(rejected)
        self.notes: list[str] = []


class VerificationFailed(DrakeDeburrError):
    """A plan failed verification and the caller asked for something that needs a pass."""


def numerical_errors() -> tuple[type[BaseException], ...]:
    """The exception types the numerical libraries raise on degenerate geometry (coincident or
    collinear points, a flat hull, a singular matrix): numpy/LAPACK ``LinAlgError``, scipy's
    ``QhullError``, and the ``ValueError``/``RuntimeError``/``FloatingPointError``/
    ``ZeroDivisionError``/``IndexError`` that open3d, CoACD, manifold3d, trimesh and scipy raise
    for such input. Catch them where a named failure can be reported instead (issue 42);
    an :class:`InputError` is re-raised before them by the callers."""
    import numpy as np
    from scipy.spatial import QhullError

    return (np.linalg.LinAlgError, QhullError, ValueError, RuntimeError, FloatingPointError,
            ZeroDivisionError, IndexError)


def describe_numerical_error(exc: BaseException) -> str:
    """One line naming the library and the error: ``scipy QhullError: QH6154 ...``."""
    lib = (type(exc).__module__ or "").split(".")[0] or "python"
    first = (str(exc).strip().splitlines() or [""])[0][:200]
    return f"{lib} {type(exc).__name__}: {first}"
