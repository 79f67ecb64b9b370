"""Per window of a verify report: cut?, cut share, failed required checks naming it, the
reason uncut_edge gives (its per_window record).

    python wip/issue42_hC7_rims/summarize.py OUT_DIR/report.json
"""
import json
import sys

r = json.load(open(sys.argv[1]))
items = {it["name"]: it for it in r["items"]}
failed = [it for it in r["items"] if it["required"] and not it["passed"]]
print("failed required:", ", ".join(f"{it['name']} ({it['value']:.4g} {it['unit']})"
                                     for it in failed) or "none")
print("windows:", items["windows"]["detail"])
uncut = items.get("uncut_edge", {}).get("per_window", {})
print("| window | cut | cut share | failed required checks naming it | blocked/uncut reason |")
print("|---|---|---|---|---|")
for w in sorted(int(k) for k in items["windows"]["per_window"]):
    cut = items["windows"]["per_window"][str(w)].get("cut")
    fails = [it["name"] for it in failed if it.get("per_window", {}).get(str(w))
             or (it.get("where") or {}).get("window") == w]
    u = uncut.get(str(w), {})
    share = (f"{float(u['cut_share']) * 100:.0f} % ({float(u['cut_mm']):.0f}/"
             f"{float(u['loop_mm']):.0f} mm)" if "cut_share" in u else "-")
    why = "; ".join(s for s in (u.get("uncut") or [{}])[0].get("why", [])) if u else ""
    print(f"| {w} | {cut} | {share} | {', '.join(fails) or '-'} | {why[:400]} |")
