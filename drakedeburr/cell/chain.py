"""The cell's kinematic tree in numpy: every body's pose at many configurations at once.

Read once from the Drake plant (each joint's frames on parent and child, revolute axes, weld
poses), so it is the plant's own model, evaluated vectorised: the verifier needs body poses,
joint axes and the flange Jacobian at 10^4-10^5 configurations, where one Drake call per
configuration costs more in Python overhead than the arithmetic. Cross-checked against the
plant's own evaluation in the tests and, in every run, at a subset of the samples
(:func:`drakedeburr.verify.distances.measure_samples`).

Only revolute and weld joints are supported (the cells' arms are serial 6R chains); the
verifier's motion bounds also need the moving joints of any two bodies to lie on one path
(:meth:`KinematicTree.joint_path`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drakedeburr.errors import InputError

__all__ = ["KinematicTree", "rotation_angle"]


def _rodrigues(axis: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations by angles ``q`` (N,) [rad] about the unit ``axis`` (3,)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def rotation_angle(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """Angle of the rotation taking ``R_a`` to ``R_b`` [rad], (..., 3, 3) -> (...)."""
    tr = np.einsum("...ij,...ij->...", R_a, R_b)  # trace(R_a^T R_b)
    return np.arccos(np.clip(0.5 * (tr - 1.0), -1.0, 1.0))


@dataclass(frozen=True)
class _Step:
    child: int
    parent: int
    X_PF: np.ndarray  # (4, 4) joint frame F in the parent body P
    X_MC: np.ndarray  # (4, 4) child body C in the joint's child frame M
    axis: np.ndarray | None  # (3,) unit axis in F (= in M); None for a weld
    X_FM: np.ndarray | None  # (4, 4) weld pose
    q_index: int  # position index of a revolute joint (-1: weld)


class KinematicTree:
    """Body poses of a plant for arrays of configurations (see module docstring).

    Args:
        plant: a finalized ``MultibodyPlant`` whose positions are its revolute joints.

    Attributes:
        n_bodies: number of bodies (indices as the plant's ``BodyIndex``; 0 is the world).
        link_of: (n_bodies,) the body each body moves with: the child body of the last
            revolute joint on its path from the world (0 for bodies welded to the world).
        path_of: per body, the position indices of the revolute joints from the world to it.
    """

    def __init__(self, plant) -> None:
        from pydrake.multibody.tree import RevoluteJoint, WeldJoint

        self.n_bodies = plant.num_bodies()
        self.nq = plant.num_positions()
        joints = [plant.get_joint(j) for j in plant.GetJointIndices()]
        placed, steps = {0}, []
        while len(steps) < len(joints):
            ready = [j for j in joints if int(j.parent_body().index()) in placed
                     and int(j.child_body().index()) not in placed]
            if not ready:
                raise InputError(f"plant: joints {[j.name() for j in joints]} do not form a tree "
                                 "rooted at the world")
            for j in ready:
                X_PF = j.frame_on_parent().GetFixedPoseInBodyFrame().GetAsMatrix4()
                X_CM = j.frame_on_child().GetFixedPoseInBodyFrame().GetAsMatrix4()
                if isinstance(j, RevoluteJoint):
                    step = _Step(int(j.child_body().index()), int(j.parent_body().index()),
                                 X_PF, np.linalg.inv(X_CM), np.asarray(j.revolute_axis(), float),
                                 None, int(j.position_start()))
                elif isinstance(j, WeldJoint):
                    step = _Step(int(j.child_body().index()), int(j.parent_body().index()),
                                 X_PF, np.linalg.inv(X_CM), None, j.X_FM().GetAsMatrix4(), -1)
                else:
                    raise InputError(f"plant: joint {j.name()!r} is a {type(j).__name__}; the "
                                     "verifier supports revolute and weld joints")
                steps.append(step)
                placed.add(step.child)
        self._steps = steps
        self.link_of = np.zeros(self.n_bodies, int)
        self.path_of: list[tuple[int, ...]] = [()] * self.n_bodies
        self._revolute = {}  # position index -> step
        for s in steps:
            if s.axis is not None:
                self.path_of[s.child] = self.path_of[s.parent] + (s.q_index,)
                self.link_of[s.child] = s.child
                self._revolute[s.q_index] = s
            else:
                self.path_of[s.child] = self.path_of[s.parent]
                self.link_of[s.child] = self.link_of[s.parent]

    def body_poses(self, q: np.ndarray) -> np.ndarray:
        """(N, n_bodies, 4, 4) poses X_WB of every body for joints ``q`` (N, nq) [rad]."""
        q = np.atleast_2d(np.asarray(q, float))
        X = np.empty((len(q), self.n_bodies, 4, 4))
        X[:, 0] = np.eye(4)
        for s in self._steps:
            if s.axis is None:
                X[:, s.child] = X[:, s.parent] @ (s.X_PF @ s.X_FM @ s.X_MC)
                continue
            X_FM = np.zeros((len(q), 4, 4))
            X_FM[:, :3, :3] = _rodrigues(s.axis, q[:, s.q_index])
            X_FM[:, 3, 3] = 1.0
            X[:, s.child] = (X[:, s.parent] @ s.X_PF) @ X_FM @ s.X_MC
        return X

    def joint_axes(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points on and directions of the revolute axes in world from body poses ``X``
        (N, n_bodies, 4, 4): (N, nq, 3) origins of the joints' frames [m], (N, nq, 3) unit
        axes, in position order."""
        o = np.empty(X.shape[:1] + (self.nq, 3))
        a = np.empty_like(o)
        for k, s in self._revolute.items():
            X_WM = X[:, s.child] @ np.linalg.inv(s.X_MC)
            o[:, k], a[:, k] = X_WM[:, :3, 3], X_WM[:, :3, :3] @ s.axis
        return o, a

    def jacobian_det(self, X: np.ndarray, body: int, p_B: np.ndarray) -> np.ndarray:
        """|det J| (N,) of the spatial-velocity Jacobian (angular; translational of the point
        ``p_B`` of ``body``), in world, with respect to the joint rates."""
        o, a = self.joint_axes(X)
        p_W = X[:, body, :3, :3] @ p_B + X[:, body, :3, 3]
        J = np.concatenate([a, np.cross(a, p_W[:, None] - o)], axis=2)  # (N, nq, 6) rows=cols
        return np.abs(np.linalg.det(J))

    def joint_path(self, ref: int, body: int) -> tuple[int, ...]:
        """Revolute joints (position indices) moving ``body`` relative to ``ref``, ordered
        from ``ref`` outward: forward if ``ref``'s path is a prefix of ``body``'s, backward
        if the reverse; InputError for bodies on different branches."""
        pr, pb = self.path_of[ref], self.path_of[body]
        if pb[:len(pr)] == pr:
            return pb[len(pr):]
        if pr[:len(pb)] == pb:
            return tuple(reversed(pr[len(pb):]))
        raise InputError(f"bodies {ref} and {body} move on different branches of the plant; "
                         "the clearance certificate needs a serial chain")

    def reach(self, X_home: np.ndarray, path: tuple[int, ...], link: int, c_L: np.ndarray,
              rho: float) -> np.ndarray:
        """Bounds of the distance of any point of a ball (centre ``c_L`` in the frame of
        ``link``, radius ``rho``) from each axis of ``path`` (ordered from the reference
        outward), over all configurations [m] -> (len(path),).

        Each term is a distance between two things fixed in one link (an axis and the next
        joint's origin, two consecutive joint origins, the last origin and the ball), so it is
        read at any one configuration (``X_home``: (n_bodies, 4, 4)); their sum along the path
        bounds the distance by the triangle inequality.
        """
        o, a = self.joint_axes(X_home[None])
        o, a = o[0], a[0]
        c_W = X_home[link, :3, :3] @ c_L + X_home[link, :3, 3]

        def off_axis(p, k):
            v = p - o[k]
            return float(np.linalg.norm(v - (v @ a[k]) * a[k]))

        n = len(path)
        out = np.empty(n)
        for i, k in enumerate(path):
            if i == n - 1:
                out[i] = off_axis(c_W, k) + rho
                continue
            tail = sum(np.linalg.norm(o[path[m + 1]] - o[path[m]]) for m in range(i + 1, n - 1))
            out[i] = (off_axis(o[path[i + 1]], k) + tail + np.linalg.norm(c_W - o[path[-1]])
                      + rho)
        return out
