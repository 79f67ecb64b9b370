"""Project exceptions. Each message names the file/item and what was wrong."""

from __future__ import annotations

__all__ = ["DrakeDeburrError", "InputError", "VerificationFailed"]


class DrakeDeburrError(Exception):
    """Base class of drakedeburr's own errors."""


class InputError(DrakeDeburrError, ValueError):
    """Bad user input: a file, an argument or an item in a file. Exit code 2 in the CLI."""


class VerificationFailed(DrakeDeburrError):
    """A plan failed verification and the caller asked for something that needs a pass."""
