"""The verifier's own kinematics: tool pose relative to the hub from joints by the analytic
OPW model of the cell's arm (vectorised), independent of the planner's code."""

from __future__ import annotations

import numpy as np

__all__ = ["VerifyKinematics", "opw_of"]


def opw_of(cell):
    """The OPW parameters of the cell's arm (``cell.arm``, from the arm registry)."""
    return cell.arm.opw


class VerifyKinematics:
    """Tool pose relative to the hub from joints, by the analytic OPW model (vectorised), plus
    the Drake plant for the cross-check. Works for both cells."""

    def __init__(self, cell) -> None:
        self.cell = cell
        self.opw = opw_of(cell)
        q0 = np.asarray(cell.q_home, float)
        ctx = cell.plant.CreateDefaultContext()
        cell.plant.SetPositions(ctx, q0)
        self.mode = cell.mode
        X_WF0 = cell.flange_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        X_W_base = cell.base_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        self.X_WB = X_W_base
        if cell.mode == "tool":
            self.X_FT = np.linalg.inv(X_WF0) @ cell.tool_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
            self.X_WH = cell.hub_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
        else:
            self.X_FH = np.linalg.inv(X_WF0) @ cell.hub_frame.CalcPoseInWorld(ctx).GetAsMatrix4()
            self.X_WT = cell.tool_frame.CalcPoseInWorld(ctx).GetAsMatrix4()

    def X_WF(self, q: np.ndarray) -> np.ndarray:
        from drakedeburr.robots.opw import fk_opw

        return self.X_WB @ fk_opw(self.opw, q)

    def X_HT(self, q: np.ndarray) -> np.ndarray:
        """(N, 4, 4) tool pose in hub frame for (N, 6) joints."""
        X_WF = self.X_WF(np.atleast_2d(q))
        if self.mode == "tool":
            return np.linalg.inv(self.X_WH) @ X_WF @ self.X_FT
        X_WH = X_WF @ self.X_FH
        return np.linalg.inv(X_WH) @ self.X_WT
