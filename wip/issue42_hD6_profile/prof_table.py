"""Per-function table (calls, self s, cumulative s) of a cProfile file: ``prof_table.py FILE``."""
import pstats
import sys

ROWS = [
    ("whole run", lambda f, ln, n: n == "<module>" and f.endswith("__main__.py")),
    ("plan_hub", lambda f, ln, n: n == "plan_hub"),
    ("tool_refusal (pre-check, window)", lambda f, ln, n: n == "tool_refusal"),
    ("blocked_anywhere", lambda f, ln, n: n == "blocked_anywhere"),
    ("tool_axis_clearance", lambda f, ln, n: n == "tool_axis_clearance"),
    ("  ToolScene.clearance (Drake)",
     lambda f, ln, n: n == "clearance" and "plan/clearance.py" in f),
    ("  _Target.cells", lambda f, ln, n: n == "cells" and "plan/clearance.py" in f),
    ("  cone_poses", lambda f, ln, n: n == "cone_poses"),
    ("X_HT_from_axis (all callers)", lambda f, ln, n: n == "X_HT_from_axis"),
    ("np.cross (all callers)", lambda f, ln, n: n == "cross" and "numeric.py" in f),
    ("targets.cross", lambda f, ln, n: n == "cross" and "targets.py" in f),
    ("solve_window_ik", lambda f, ln, n: n == "solve_window_ik"),
    ("  pydrake Solve (all)", lambda f, ln, n: "pydrake.solvers.Solve" in n),
    ("cone_clearance_probe", lambda f, ln, n: n == "cone_clearance_probe"),
    ("seed_by_spin", lambda f, ln, n: n == "seed_by_spin"),
    ("analytic_seed", lambda f, ln, n: n == "analytic_seed"),
    ("distances_along", lambda f, ln, n: n == "distances_along"),
    ("  pairs_within", lambda f, ln, n: n == "pairs_within"),
    ("SignedDistancePairwise (all)",
     lambda f, ln, n: "ComputeSignedDistancePairwiseClosestPoints" in n),
    ("certified_distance", lambda f, ln, n: n == "certified_distance"),
]


def find(stats, pat):
    """Calls, self and cumulative seconds summed over the functions ``pat`` matches."""
    tot = [0, 0.0, 0.0]
    for (f, ln, n), (_cc, nc, tt, ct, _callers) in stats.items():
        if pat(f, ln, n):
            tot[0] += nc
            tot[1] += tt
            tot[2] += ct
    return tot


def main(path):
    stats = pstats.Stats(path).stats
    print("| function | calls | self s | cum s |\n|---|---:|---:|---:|")
    for name, pat in ROWS:
        c, t, ct = find(stats, pat)
        print(f"| {name} | {c} | {t:.1f} | {ct:.1f} |")


if __name__ == "__main__":
    main(sys.argv[1])
