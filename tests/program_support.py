"""Random, consistent robot programs for the program tests (one per arm and mode)."""

import numpy as np

from drakedeburr.programs import JOINT, LINEAR, MoveDetails, RobotProgram
from drakedeburr.robots import fk_opw, get_robot

SUFFIX = {"rapid": ".mod", "krl": ".src", "ls": ".ls"}
ARMS = {"rapid": "irb1600", "krl": "kr6_r700", "ls": "lrmate200ic"}
# every speed distinct and off the standard values, zones of every kind
SPEEDS = [0.150, 0.0234567, 0.600, 0.0191, 0.1495, 0.45, 0.0208, 0.15, 0.0876, 0.15]
ZONES = [0.0, 0.001, 0.0003, 0.005, 0.0, 0.0012, 0.0005, 0.0, 0.002, 0.0]


def _pose(xyz, rpy_deg=(0, 0, 0)):
    from scipy.spatial.transform import Rotation

    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("ZYX", rpy_deg[::-1], degrees=True).as_matrix()
    X[:3, 3] = xyz
    return X


def random_program(robot: str, stationary: bool = False, seed: int = 0, n: int = 10,
                   name: str = "deburr_test", **kw) -> RobotProgram:
    """``n`` moves at random joints (away from the wrist singularity), first and last joint
    moves, per-move speeds/zones from SPEEDS/ZONES, loads set."""
    spec = get_robot(robot)
    rng = np.random.default_rng(seed)
    q = []
    while len(q) < n:
        v = rng.uniform(0.8 * spec.q_lower, 0.8 * spec.q_upper)
        v[3] = rng.uniform(-2.5, 2.5)
        v[5] = rng.uniform(-2.5, 2.5)
        # FANUC CONFIG has no J3 turn number: keep J3 where one value is meant (docs/post.md)
        v[2] = np.pi - np.mod(np.pi - v[2], 2 * np.pi)
        if not spec.within_limits(v):
            continue
        q_opw = spec.opw.q_opw_from_robot(v)
        if abs(np.sin(q_opw[4])) > 0.15 and abs(np.cos(q_opw[2])) > 0.05:
            q.append(v)
    q = np.array(q)
    X_FT = _pose([0.012, -0.005, 0.18], (0, 30, 10))
    X_WO = _pose([0.70, -0.10, 0.25], (5, 0, 15))
    types = [JOINT] + [LINEAR] * (n - 2) + [JOINT]
    loads = dict(tool_mass=3.05, tool_cog=(-0.018, 0.0, 0.127), load_source="test loads")
    if stationary:
        loads.update(workpiece_mass=11.13, workpiece_cog=(0.0, 0.0, 0.266))
    kw = {**loads, **kw}
    return RobotProgram.from_poses(
        name, fk_opw(spec.opw, q) @ X_FT, q, speed=[SPEEDS[i % 10] for i in range(n)],
        zone=[ZONES[i % 10] for i in range(n)], move_type=types, X_FT=X_FT, X_WO=X_WO,
        robot=spec, stationary_tool=stationary,
        details=MoveDetails(comments=["approach window 1"] + [""] * (n - 2) + ["home"],
                            joint_fractions=[0.33] + [None] * (n - 2) + [0.125]), **kw)
