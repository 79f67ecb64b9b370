"""A plan folder -> a robot program, through the gate (:mod:`drakedeburr.verify.gate`): the
program is written only when the folder's verification report passed for this very plan and
cell, unless forced; a forced program's header says FORCED or UNVERIFIED and why. The CLI's
``export`` and ``demo`` both come here."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from drakedeburr.errors import DrakeDeburrError

__all__ = ["ExportRefused", "Exported", "export_plan", "plan_program"]


class ExportRefused(DrakeDeburrError):
    """The gate refused to write a program (exit code 1: the result failed, nothing written)."""


@dataclass(frozen=True)
class Exported:
    """What an export wrote: the files, and the header flag ("" for a verified plan)."""

    paths: tuple[Path, ...]
    flag: str
    reason: str


def plan_program(plan, name: str, *, flag: str = "", flag_reason: str = "",
                 verified: bool = False, robot: str | None = None):
    """The plan's program with the loads of its cell's tool (and workpiece) models."""
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.errors import InputError
    from drakedeburr.programs import program_from_plan

    try:  # the plan's own cell: its arm, burr and hub pose (the workpiece's centre of mass)
        cell = load_plan_cell(plan)
    except FileNotFoundError as exc:
        raise InputError(f"the plan's cell ({plan.scenario}, hub {plan.hub}) is needed for the "
                         f"tool's mass and centre of gravity: {exc}") from exc
    return program_from_plan(plan, name, robot=robot, loads=cell.flange_loads(),
                             verified=verified, flag=flag, flag_reason=flag_reason)


def export_plan(folder: str | Path, output: str | Path, fmt: str | None = None, *,
                name: str = "Deburr", force: bool = False, robot: str | None = None,
                plan=None) -> Exported:
    """Write the program of the plan in ``folder`` to ``output`` (see module docstring).

    Args:
        folder: a plan folder (:func:`drakedeburr.plan.io.save_plan`) with its report.
        output: the program file (KRL: the .src; the .dat is written beside it).
        fmt: "rapid", "krl" or "ls" (default: the plan's arm's controller's).
        name: RAPID module name (KRL/LS programs take the file's name).
        force: write even when the gate refuses; the header then says why.
        robot: the arm the program is for; it must be the plan's.
        plan: the plan already loaded from ``folder`` (default: load it).

    Raises:
        ExportRefused: the gate refused and ``force`` is not given, or the plan holds no
            motion (nothing could be planned); nothing is written.
        InputError: the folder is not a plan, or the format does not suit the arm.
    """
    from drakedeburr.plan.io import load_plan
    from drakedeburr.programs import write_program
    from drakedeburr.verify.gate import gate

    folder = Path(folder)
    folder = folder.parent if folder.name == "plan.json" else folder
    plan = plan if plan is not None else load_plan(folder)
    if len(plan.trajectory.t) < 2:  # not even --force: there is no motion to write
        raise ExportRefused(f"{folder}: no program to write: nothing could be planned "
                            f"({len(plan.failures)} failure records; drakedeburr verify "
                            f"{folder} reports them)")
    verdict = gate(folder, plan)
    flag = reason = ""
    if not verdict.ok:
        if not force:
            raise ExportRefused(f"{folder}: refusing to export: {verdict.reason} (use --force "
                                "to write it anyway; its header then says so)")
        flag, reason = verdict.flag, f"written with --force although {verdict.reason}"
    program = plan_program(plan, name, flag=flag, flag_reason=reason, verified=verdict.ok,
                           robot=robot)
    return Exported(tuple(write_program(program, output, fmt)), flag, reason)
