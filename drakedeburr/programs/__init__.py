"""drakedeburr.programs: robot programs as data, a neutral room used by export, post and the
verifier: :class:`RobotProgram`, writers for ABB RAPID, KUKA KRL and FANUC LS (each move with
its own speed and zone), strict readers of the same formats, and :func:`compare_programs`,
which names every line where a program differs from the plan it should carry."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "common": ("FORMATS", "ProgramFormatError"),
    "compare": ("CompareTolerances", "Discrepancy", "compare_programs", "expected_values"),
    "krl": ("format_krl", "read_krl", "read_krl_dat"),
    "ls": ("format_ls", "read_ls"),
    "plan_program": ("FlangeLoads", "joint_fractions", "plan_robot", "program_from_plan"),
    "program": ("DEFAULT_JOINT_SPEED_FRACTION", "JOINT", "LINEAR", "MoveDetails", "ProgramMove",
                "RobotProgram", "zones_within_half_moves"),
    "rapid": ("format_rapid", "read_rapid"),
    "read_types": ("ReadMove", "ReadProgram"),
    "reading": ("format_of", "read_program"),
    "writers": ("check_format", "format_for_controller", "format_program", "write_program"),
})
