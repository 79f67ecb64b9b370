"""A plan folder -> a robot program, through the gate (:mod:`drakedeburr.verify.gate`): the
program is written only when the folder's verification report passed for this very plan and
cell, unless forced; a forced program's header says FORCED or UNVERIFIED and why. The CLI's
``export`` and ``demo`` both come here.

Export checks what it wrote: the program is written into a staging folder, read back and
checked as the controller runs it (:mod:`drakedeburr.post.program_check`: the file equals the
plan's program, the controller's joints, path, clearance and zones are the verified ones);
only then are the same bytes written to the output. A failing check refuses the export
(nothing written) unless forced (the header then says FORCED and why)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from drakedeburr.errors import DrakeDeburrError
from drakedeburr.post.program_check import plan_program

__all__ = ["ExportRefused", "Exported", "export_plan"]


class ExportRefused(DrakeDeburrError):
    """The gate refused to write a program (exit code 1: the result failed, nothing written)."""


@dataclass(frozen=True)
class Exported:
    """What an export wrote: the files, and the header flag ("" for a verified plan)."""

    paths: tuple[Path, ...]
    flag: str
    reason: str


def export_plan(folder: str | Path, output: str | Path, fmt: str | None = None, *,
                name: str = "Deburr", force: bool = False, robot: str | None = None,
                plan=None, partial: bool = False) -> Exported:
    """Write the program of the plan in ``folder`` to ``output`` (see module docstring).

    Args:
        folder: a plan folder (:func:`drakedeburr.plan.io.save_plan`) with its report.
        output: the program file (KRL: the .src; the .dat is written beside it).
        fmt: "rapid", "krl" or "ls" (default: the plan's arm's controller's).
        name: RAPID module name (KRL/LS programs take the file's name).
        force: write even when the gate refuses; the header then says why.
        robot: the arm the program is for; it must be the plan's.
        plan: the plan already loaded from ``folder`` (default: load it).
        partial: write a plan whose verification failed only on ``uncut_edge`` (partial
            windows: every other required check passed on the motion planned); the header
            says PARTIAL and lists the uncut stretches (window, CL range, mm, reason).

    Raises:
        ExportRefused: the gate refused and ``force`` is not given, or the plan holds no
            motion (nothing could be planned); nothing is written.
        InputError: the folder is not a plan, or the format does not suit the arm.
    """
    from drakedeburr.plan.io import load_plan
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
    if not verdict.ok and partial and verdict.partial:
        flag, reason = "PARTIAL", f"written with --partial: edge left uncut: {verdict.partial}"
    elif not verdict.ok:
        if not force:
            raise ExportRefused(f"{folder}: refusing to export: {verdict.reason} (use --force "
                                "to write it anyway; its header then says so)")
        flag, reason = verdict.flag, f"written with --force although {verdict.reason}"
    from drakedeburr.cell.station import load_plan_cell

    try:
        cell = load_plan_cell(plan)
    except FileNotFoundError:
        cell = None  # plan_program names the missing cell
    program = plan_program(plan, name, flag=flag, flag_reason=reason, verified=verdict.ok,
                           robot=robot, cell=cell)
    paths, failed = _write_checked(program, Path(output), fmt, plan, cell)
    if failed:
        what = "; ".join(f"{i.name}: {i.detail}" for i in failed)
        if not force:
            raise ExportRefused(f"{folder}: refusing to export: the program as the controller "
                                f"runs it fails {', '.join(i.name for i in failed)} ({what}); "
                                "nothing written (use --force to write it anyway)")
        also = f"the program check fails {', '.join(i.name for i in failed)}"
        flag = flag or "FORCED"
        reason = (f"{reason}; {also}" if reason else f"written with --force although {also}")
        program = plan_program(plan, name, flag=flag, flag_reason=reason, verified=False,
                               robot=robot, cell=cell)
        paths, _ = _write_checked(program, Path(output), fmt, plan, cell, check=False)
    return Exported(tuple(paths), flag, reason)


def _write_checked(program, output: Path, fmt, plan, cell, check: bool = True):
    """Write ``program`` into a staging folder, check it as read back
    (:func:`drakedeburr.post.program_check.program_items`), and write the same bytes to
    ``output`` (atomically, :func:`drakedeburr.programs.write_program`) only when every
    required item passed. Returns (paths, failed items)."""
    import tempfile

    from drakedeburr.config import default_tolerances
    from drakedeburr.post.program_check import program_items
    from drakedeburr.programs import read_program, write_program

    failed = []
    if check:
        with tempfile.TemporaryDirectory(prefix="drakedeburr-export-") as tmp:
            try:
                staged = write_program(program, Path(tmp) / output.name, fmt)
            except OSError as exc:  # name the output, not its staging copy
                if exc.errno is None:
                    raise
                raise OSError(exc.errno, exc.strerror, str(output)) from None
            texts = [p.read_bytes() for p in staged]
            items = program_items(plan, read_program(staged[0]), cell, default_tolerances())
            failed = [i for i in items if i.required and not i.passed]
        if failed:
            return [], failed
    paths = write_program(program, output, fmt)
    if check and [p.read_bytes() for p in paths] != texts:  # deterministic writers
        raise RuntimeError(f"{output}: the program written differs from the one checked")
    return paths, []
