"""Every bundled hub plans in both cells through the real chain (whole hubs: slow): hub edges ->
CL points (path stage) -> tool axes and theta box (orientation stage ToolPath) -> plan."""

import numpy as np
import pytest

from drakedeburr.resources import hub_names

HUBS = hub_names()


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["tool", "workpiece"])
@pytest.mark.parametrize("hub", HUBS)
def test_whole_hub_plans_in_both_cells(hub, mode, request):
    if mode == "workpiece":
        # known gap (docs/plan.md, "Limits"): h5_straight window 2 and h5_split window 4 fail
        # late in the loop in the workpiece cell with the real chain; not strict, so a fix shows
        request.applymarker(pytest.mark.xfail(reason="workpiece cell: real-chain IK failures "
                                              "late in some windows", strict=False))
    from drakedeburr.hub import load_hub
    from drakedeburr.plan.planner import plan_hub

    plan = plan_hub(hub=hub, mode=mode, source="toolpath")
    assert plan.failures == ()
    planned = [w["window"] for w in plan.meta["windows"]]
    assert planned == [w.index for w in load_hub(hub).windows]
    tr = plan.trajectory
    tt = np.linspace(0, tr.duration, 20000)
    qd = tr.derivative(tt)
    v_max = np.array([3.1416, 3.1416, 3.2289, 6.7195, 6.9813, 8.0285])  # irb1600 model limits
    assert np.all(np.abs(qd) <= v_max * (1 + 1e-6))
    for w in plan.meta["windows"]:
        assert w["min_clearance_m"] >= 2e-3
        assert w["joint_fit_deviation_m"] <= 0.05e-3
        assert w["reached"] == w["cl_points"] + 1  # every CL point, the loop closed on CL 0
