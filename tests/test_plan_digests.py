"""The bundled hubs' plans are the same, bit for bit, as the stored digests
(tests/data/plan_digests.json, written by the planner before its window pipeline
(drakedeburr.plan.window.plan_window_pass) and hub policy (drakedeburr.plan.policy) were
restructured): a refactor of the planner changes no plan. After a change that is MEANT to
change plans, regenerate the file with ``python tests/test_plan_digests.py`` and say why in the
commit."""

import json
import sys
from pathlib import Path

import pytest

from drakedeburr.resources import hub_names

STORED = Path(__file__).parent / "data" / "plan_digests.json"
CASES = ("h5_straight:0", "h5_straight", "h5_deepdish", "h5_split", "h6_curved")

pytestmark = pytest.mark.skipif("h5_straight" not in hub_names(), reason="no bundled hub")


def relocated_digest(plan, root: str | None = None) -> str:
    """The plan's content digest with the checkout's own folder (``root``; default: the one
    this package is imported from) written as ``<repo>`` in its record (a hub's own recipe
    file is recorded by its path), so the stored digests hold in any checkout."""
    from dataclasses import replace

    import drakedeburr
    from drakedeburr.plan.io import plan_digest

    root = root or str(Path(drakedeburr.__file__).resolve().parent.parent)

    def rel(v):
        if isinstance(v, str):
            return "<repo>" + v[len(root):] if v.startswith(root) else v
        if isinstance(v, dict):
            return {k: rel(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return type(v)(rel(x) for x in v)
        return v

    return plan_digest(replace(plan, meta=rel(plan.meta)))


def _plan(case: str):
    from drakedeburr.config import load_config
    from drakedeburr.plan.planner import PlanOptions, plan_hub

    hub, _, windows = case.partition(":")
    options = PlanOptions(windows=tuple(int(w) for w in windows.split(","))) if windows \
        else PlanOptions()
    return plan_hub(load_config("tool_in_hand", hub), options=options)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_bundled_hub_plan_is_unchanged(case):
    stored = json.loads(STORED.read_text())[case]
    plan = _plan(case)
    assert len(plan.failures) == stored["failures"]
    assert relocated_digest(plan) == stored["digest"]


if __name__ == "__main__":  # regenerate the stored digests (a change meant to change plans)
    out = {}
    for c in CASES:
        p = _plan(c)
        out[c] = {"digest": relocated_digest(p), "failures": len(p.failures)}
        print(c, out[c], file=sys.stderr)
    STORED.write_text(json.dumps(out, indent=1, sort_keys=True))
