"""The planning stage's own plan of one window, verified (slow: plans with Drake IK).

Whatever the verdict, the certificate must be complete and self-consistent: both FKs agree,
the program and the structure are read correctly, every window expected is cut, and the JSON
is reproducible.
"""

from __future__ import annotations

import pytest
import verify_support as vs

from drakedeburr.config import load_config
from drakedeburr.verify.report import report_json


@pytest.mark.slow
def test_plan_hub_window_is_verified():
    from drakedeburr.cell.station import load_plan_cell
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    plan = plan_hub(load_config(vs.SCENARIO, vs.HUB), options=PlanOptions(windows=(0,)))
    # the cell the plan was made in: the placement search may seat the hub elsewhere for
    # one window than for the whole hub
    cell = load_plan_cell(plan)
    a = vs.verify(plan, expected_windows=[0], params=None, cell=cell)
    for name in ("structure", "fk_agreement", "target_consistency", "windows", "rest_at_ends",
                 "configuration"):
        assert a.item(name).passed, a.item(name)
    assert a.item("path_deviation").value is not None
    assert a.item("clearance").pair is not None
    # the verifier reads the planner's own ToolPath (CL points on the edge)
    assert all(v.get("reference") == "ToolPath"
               for v in a.item("cone").per_window.values())
    # the program's own targets (FK of their joints) inside their CL points' cones too
    # (drakedeburr.verify.cut_geometry.target_cones), read apart from the dense samples
    cone = a.item("cone")
    slack = a.settings["tolerances"]["cone_slack"]
    assert cone.passed and cone.value >= -slack, cone
    n_cl = sum(t.window_index == 0 and t.cl_index >= 0 for t in plan.targets)
    fig = cone.per_window[0]
    assert fig["targets"] >= n_cl > 0 and fig["target_min_margin"] >= -slack
    assert "program targets: " in cone.detail and " 0 outside" in cone.detail
    b = vs.verify(plan, expected_windows=[0], params=None, cell=cell)
    assert report_json(a, include_run=False) == report_json(b, include_run=False)
