"""drakedeburr.programs: robot programs as data, a neutral room used by export, post and the
verifier: :class:`RobotProgram`, writers for ABB RAPID, KUKA KRL and FANUC LS (each move with
its own speed and zone), strict readers of the same formats, and :func:`compare_programs`,
which names every line where a program differs from the plan it should carry."""

from drakedeburr.programs.common import FORMATS, ProgramFormatError
from drakedeburr.programs.compare import (
    CompareTolerances,
    Discrepancy,
    compare_programs,
    expected_values,
)
from drakedeburr.programs.krl import format_krl, read_krl, read_krl_dat
from drakedeburr.programs.ls import format_ls, read_ls
from drakedeburr.programs.plan_program import (
    FlangeLoads,
    joint_fractions,
    plan_robot,
    program_from_plan,
)
from drakedeburr.programs.program import (
    DEFAULT_JOINT_SPEED_FRACTION,
    JOINT,
    LINEAR,
    ProgramMove,
    RobotProgram,
)
from drakedeburr.programs.rapid import format_rapid, read_rapid
from drakedeburr.programs.reading import ReadMove, ReadProgram, format_of, read_program
from drakedeburr.programs.writers import (
    check_format,
    format_for_controller,
    format_program,
    write_program,
)

__all__ = [
    "RobotProgram", "ProgramMove", "LINEAR", "JOINT", "DEFAULT_JOINT_SPEED_FRACTION",
    "FORMATS", "write_program", "format_program", "check_format", "format_for_controller",
    "format_rapid", "format_krl", "format_ls",
    "ReadProgram", "ReadMove", "ProgramFormatError", "read_program", "format_of",
    "read_rapid", "read_krl", "read_krl_dat", "read_ls",
    "CompareTolerances", "Discrepancy", "compare_programs", "expected_values",
    "FlangeLoads", "program_from_plan", "plan_robot", "joint_fractions",
]
