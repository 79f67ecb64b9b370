"""Write a :class:`RobotProgram` to files: the format follows the arm's controller.

Deterministic: the same program always gives the same bytes (no dates, fixed number formats,
names numbered in move order). Millimetres and degrees only in the vendor modules
(:mod:`~drakedeburr.programs.rapid`, :mod:`~drakedeburr.programs.krl`,
:mod:`~drakedeburr.programs.ls`), converted with :mod:`drakedeburr.units`. Poses are written
with 6 decimals (mm, deg) and RAPID quaternions with 10, so a reader recomputes the planned
joints to better than 1e-6 rad away from singularities.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

from drakedeburr._io import atomic_write_files, atomic_write_text
from drakedeburr.errors import InputError
from drakedeburr.programs.common import FORMATS, SUFFIXES, program_name_for
from drakedeburr.programs.program import RobotProgram

__all__ = ["FORMATS", "format_for_controller", "check_format", "check_names", "format_program",
           "write_program"]

log = logging.getLogger(__name__)

_CONTROLLER_FORMAT = {"abb": "rapid", "kuka": "krl", "fanuc": "ls"}


def format_for_controller(controller: str) -> str:
    """The program format a controller family runs ("abb" -> "rapid", ...)."""
    return _CONTROLLER_FORMAT[controller]


def check_format(program: RobotProgram, fmt: str) -> None:
    """Refuse to write a program in a format its arm's controller does not run.

    Raises:
        InputError: unknown format, or e.g. KRL for an ABB arm.
    """
    if fmt not in FORMATS:
        raise InputError(f"unknown program format {fmt!r}: use one of {', '.join(FORMATS)}")
    want = _CONTROLLER_FORMAT.get(program.controller)
    if want != fmt:
        arm = program.spec.title if program.spec else program.kinematics.name
        raise InputError(f"{fmt.upper()} is not a program for {arm}: its {program.controller} "
                         f"controller runs {want.upper() if want else 'an unknown format'} "
                         f"(--format {want})")


def check_names(program: RobotProgram, fmt: str) -> None:
    """Refuse a program whose name or data names are not identifiers of ``fmt``'s language
    (:mod:`drakedeburr.programs.names`), or clash with each other.

    Raises:
        ProgramNameError: naming the item.
    """
    from drakedeburr.programs.names import ProgramNameError, check_identifier

    what = {"rapid": "module name", "krl": "program name", "ls": "program name"}[fmt]
    check_identifier(program.name, fmt, "program", what)
    if fmt == "ls":  # the TP program names no data
        return
    data = [program.tool_name, program.wobj_name]
    if fmt == "rapid" and program.stationary_tool:
        data.append(program.wobj_name + "Load")
    for label in data:
        check_identifier(label, fmt, "program data", "data name")
    if program.name.lower() in {d.lower() for d in data} or len(
            {d.lower() for d in data}) < len(data):
        raise ProgramNameError(f"program: {what} {program.name!r} clashes with the data names "
                               f"{', '.join(data)} of the program")


def format_program(program: RobotProgram, fmt: str) -> dict[str, str]:
    """Texts of a program in ``fmt``: {suffix: text} (KRL: ".src" and ".dat"); names
    (:func:`check_names`) and speeds (:func:`~drakedeburr.programs.speeds.check_program_speeds`)
    are checked first."""
    from drakedeburr.programs.speeds import check_program_speeds

    check_format(program, fmt)
    check_names(program, fmt)
    check_program_speeds(program, fmt)
    if fmt == "rapid":
        from drakedeburr.programs.rapid import format_rapid

        return {".mod": format_rapid(program)}
    if fmt == "krl":
        from drakedeburr.programs.krl import format_krl

        src, dat = format_krl(program)
        return {".src": src, ".dat": dat}
    from drakedeburr.programs.ls import format_ls

    return {".ls": format_ls(program)}


def write_program(program: RobotProgram, path: str | Path, fmt: str | None = None) -> list[Path]:
    """Write a program atomically, in the format its arm's controller runs.

    KRL and LS programs take the file's name (DEF/DEFDAT and /PROG must equal it; the name is
    checked against the controller's naming rules). For KRL, ``path`` names the .src file and
    the .dat is written beside it; both texts are formatted before either file is written.

    Args:
        program: the program.
        path: the output file (suffix .mod/.modx/.prg, .src or .ls).
        fmt: "rapid", "krl" or "ls"; default: the arm's controller's format.

    Returns:
        the written paths.

    Raises:
        InputError: wrong format for the arm, or a file name the controller cannot take.
    """
    path = Path(path)
    fmt = fmt or _CONTROLLER_FORMAT.get(program.controller, "rapid")
    check_format(program, fmt)
    if fmt in ("krl", "ls"):
        name = program_name_for(path, fmt)
        if name != program.name:
            program = replace(program, name=name)
    if path.suffix.lower() not in SUFFIXES[fmt]:
        raise InputError(f"{path}: a {fmt.upper()} program file ends in "
                         f"{' or '.join(SUFFIXES[fmt])}")
    texts = format_program(program, fmt)
    if fmt == "krl":  # the pair changes together or not at all
        return atomic_write_files({path: texts[".src"], path.with_suffix(".dat"): texts[".dat"]})
    return [atomic_write_text(path, next(iter(texts.values())))]
