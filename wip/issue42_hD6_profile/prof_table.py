import pstats, sys
p = pstats.Stats(sys.argv[1])
st = p.stats
def find(pat):
    tot = [0, 0.0, 0.0]
    for (f, l, n), (cc, nc, tt, ct, callers) in st.items():
        if pat(f, l, n):
            tot[0] += nc; tot[1] += tt; tot[2] += ct
    return tot
rows = [
 ("whole run", lambda f,l,n: n == "<module>" and f.endswith("__main__.py")),
 ("plan_hub", lambda f,l,n: n == "plan_hub"),
 ("tool_refusal (pre-check, window)", lambda f,l,n: n == "tool_refusal"),
 ("blocked_anywhere", lambda f,l,n: n == "blocked_anywhere"),
 ("tool_axis_clearance", lambda f,l,n: n == "tool_axis_clearance"),
 ("  ToolScene.clearance (Drake)", lambda f,l,n: n == "clearance" and "plan/clearance.py" in f),
 ("  _Target.cells", lambda f,l,n: n == "cells" and "plan/clearance.py" in f),
 ("  cone_poses", lambda f,l,n: n == "cone_poses"),
 ("X_HT_from_axis (all callers)", lambda f,l,n: n == "X_HT_from_axis"),
 ("np.cross (all callers)", lambda f,l,n: n == "cross" and "numeric.py" in f),
 ("targets.cross", lambda f,l,n: n == "cross" and "targets.py" in f),
 ("solve_window_ik", lambda f,l,n: n == "solve_window_ik"),
 ("  pydrake Solve (all)", lambda f,l,n: "pydrake.solvers.Solve" in n),
 ("cone_clearance_probe", lambda f,l,n: n == "cone_clearance_probe"),
 ("seed_by_spin", lambda f,l,n: n == "seed_by_spin"),
 ("analytic_seed", lambda f,l,n: n == "analytic_seed"),
 ("distances_along", lambda f,l,n: n == "distances_along"),
 ("  pairs_within", lambda f,l,n: n == "pairs_within"),
 ("SignedDistancePairwise (all)", lambda f,l,n: "ComputeSignedDistancePairwiseClosestPoints" in n),
 ("certified_distance", lambda f,l,n: n == "certified_distance"),
]
print(f"| function | calls | self s | cum s |\n|---|---:|---:|---:|")
for name, pat in rows:
    c, t, ct = find(pat)
    print(f"| {name} | {c} | {t:.1f} | {ct:.1f} |")
