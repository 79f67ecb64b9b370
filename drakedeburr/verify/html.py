"""Self-contained HTML report: pass/fail table, plots (inline SVG) and the Meshcat replay.

One file, no network: the plots are matplotlib SVG written into the page, the replay is
Drake's ``Meshcat.StaticHtml()`` (a complete HTML document with the Meshcat client inlined)
placed in an ``<iframe srcdoc=...>``.
"""

from __future__ import annotations

import html
import io
import logging
from pathlib import Path

import numpy as np

from drakedeburr._io import atomic_write_text
from drakedeburr.units import deg_from_rad, mm_from_m, mm_s_from_m_s
from drakedeburr.verify.report import VerificationReport, report_dict, report_json

__all__ = ["report_html", "write_report_html", "report_figures", "meshcat_replay_html",
           "figures_and_replay", "warm_plotting", "write_report_files"]

log = logging.getLogger(__name__)

_KIND_NAMES = {0: "home", 1: "transition", 2: "approach", 3: "cut", 4: "retract"}


def _svg(fig) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight", metadata={"Date": None})  # reproducible
    import matplotlib.pyplot as plt

    plt.close(fig)
    text = buf.getvalue()
    return text[text.index("<svg"):]  # drop the XML prolog and DOCTYPE


def _envelope(x: np.ndarray, y: np.ndarray, n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """At most ~2n points of (x, y) keeping each bin's minimum and maximum (NaN-aware; the
    first of equal extremes, in sample order; +-inf count where the bin has a finite value,
    a bin without one is its first x with NaN), so a plot of tens of thousands of samples
    stays small and still shows every extreme."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(x) <= 2 * n:
        return x, y
    edges = np.linspace(0, len(x), n + 1).astype(int)
    starts = edges[:-1]
    bins = np.repeat(np.arange(n), np.diff(edges))
    finite = ~np.isnan(y)  # a value, infinite ones included
    lo = np.minimum.reduceat(np.where(finite, y, np.inf), starts)
    hi = np.maximum.reduceat(np.where(finite, y, -np.inf), starts)

    def first(hit: np.ndarray) -> np.ndarray:  # each bin's first sample where ``hit``
        idx = np.flatnonzero(hit)
        _, at = np.unique(bins[idx], return_index=True)
        out = starts.copy()  # an all-NaN bin keeps its first sample
        out[bins[idx[at]]] = idx[at]
        return out

    i = first(finite & (y == lo[bins]))
    j = first(finite & (y == hi[bins]))
    dead = ~np.logical_or.reduceat(np.isfinite(y), starts)  # no finite value in the bin
    i[dead] = j[dead] = starts[dead]
    keep = np.sort(np.concatenate([i, j]))
    keep = keep[np.concatenate([[True], np.diff(keep) > 0])]
    ys = y[keep].copy()
    ys[np.isin(keep, starts[dead])] = np.nan  # such a bin: its first x, y NaN
    return x[keep], ys


def report_figures(report: VerificationReport) -> dict[str, str]:
    """The report's plots as inline SVG strings, keyed by a short id.

    Ids: ``theta`` (theta_A/theta_B along each window's cut), ``joints`` (joint angles vs
    time), ``speed`` (TCP speed vs time), ``clearance`` (distances vs time), ``deviation``
    (path and edge deviation vs time). Drawn in matplotlib's default style whatever the
    process set (a notebook's, say), so the same in any process.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if "t" not in report.series:  # no samples: nothing could be planned (the items say why)
        return {}
    with plt.style.context("default"), plt.rc_context({"svg.hashsalt": "drakedeburr"}):
        return {k: _svg(draw(report, plt)) for k, draw in _FIGURES.items()}  # stable SVG ids


def _fig_theta(report: VerificationReport, plt):
    s = report.series
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.2), sharey=True)
    cut = s["kind"] == 3
    for w in sorted(set(s["window"][cut].tolist())):
        m = cut & (s["window"] == w)
        axes[0].plot(*_envelope(s["s_cut"][m] * 1e3, s["theta_A"][m]), lw=1, label=f"window {w}")
        axes[1].plot(*_envelope(s["s_cut"][m] * 1e3, s["theta_B"][m]), lw=1, label=f"window {w}")
    cone = next((i for i in report.items if i.name == "cone"), None)
    for ax, name in zip(axes, ("theta_A", "theta_B"), strict=True):
        if cone is not None:
            for info in cone.per_window.values():
                for b in info.get("bounds", []):
                    ax.axhline(b, color="0.6", lw=0.6, ls="--")
        ax.set_xlabel("tool travel along the window [mm]")
        ax.set_title(f"{name} of the executed axis [rad]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    return fig


def _fig_joints(report: VerificationReport, plt):
    s = report.series
    fig, ax = plt.subplots(figsize=(10, 3.2))
    for j in range(s["q"].shape[1]):
        ax.plot(*_envelope(s["t"], np.degrees(s["q"][:, j])), lw=1, label=f"J{j + 1}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("joint angle [deg]")
    ax.legend(ncol=6, fontsize=7)
    ax.grid(alpha=0.3)
    return fig


def _fig_speed(report: VerificationReport, plt):
    s, t, tol = report.series, report.series["t"], report.settings["tolerances"]
    cut = s["kind"] == 3
    fig, ax = plt.subplots(figsize=(10, 3.2))
    ax.plot(*_envelope(t, s["speed"] * 1e3), lw=0.8, color="C0", label="TCP speed")
    v_g = report.settings.get("grinding_speed", 0.15)
    for f in (1 - tol["speed_band"], 1 + tol["speed_band"]):
        ax.axhline(v_g * f * 1e3, color="C3", lw=0.6, ls="--")
    tc, fc = _envelope(t, cut * 1.0)
    ax.fill_between(tc, 0, fc * s["speed"].max() * 1e3 * 1.05, color="C2", alpha=0.08,
                    step="mid", label="cutting")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tool speed relative to the hub [mm/s]")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return fig


def _fig_clearance(report: VerificationReport, plt):
    s, t, tol = report.series, report.series["t"], report.settings["tolerances"]
    fig, ax = plt.subplots(figsize=(10, 3.2))
    cap = tol["query_distance"]
    for key, label in (("clearance", "robot/tool to hub and cell"), ("self", "robot to itself"),
                       ("burr", "burr head to hub")):
        v = np.where(np.isfinite(s[key]), s[key], cap)
        ax.plot(*_envelope(t, v * 1e3), lw=0.8, label=label)
    ax.axhline(tol["min_clearance"] * 1e3, color="C3", lw=0.6, ls="--", label="min clearance")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"signed distance [mm] (capped at {cap * 1e3:.0f})")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return fig


def _fig_deviation(report: VerificationReport, plt):
    s, t, tol = report.series, report.series["t"], report.settings["tolerances"]
    fig, ax = plt.subplots(figsize=(10, 3.2))
    ax.plot(*_envelope(t, s["path_dev"] * 1e3), ".", ms=1.5, label="T vs program")
    ax.plot(*_envelope(t, s["edge_dev"] * 1e3), ".", ms=1.5, label="contact vs true edge")
    ax.axhline(tol["path_deviation"] * 1e3, color="C0", lw=0.6, ls="--")
    ax.axhline(tol["edge_deviation"] * 1e3, color="C1", lw=0.6, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("deviation [mm]")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return fig


_FIGURES = {"theta": _fig_theta, "joints": _fig_joints, "speed": _fig_speed,
            "clearance": _fig_clearance, "deviation": _fig_deviation}


def figures_and_replay(report: VerificationReport, plan=None, cell=None,
                       workers: int | None = None) -> tuple[dict[str, str], str | None]:
    """(:func:`report_figures`, :func:`meshcat_replay_html` of ``plan`` or None without one),
    made at once when a pool worker is running (:func:`drakedeburr.pool.map_tasks`;
    ``workers`` as there): the figures there while this process records the replay; none is
    started for them (a worker's start-up costs more than the figures). The same figures
    wherever they are drawn (deterministic SVG)."""
    from drakedeburr.pool import map_tasks, running_workers

    if plan is None:
        return report_figures(report), None
    replay, figs = map_tasks(
        2, lambda k: report_figures(report) if k else meshcat_replay_html(plan, cell),
        lambda k: (report_figures, (report,)) if k else None,
        workers if running_workers() else 1,
        name=lambda k: "the report's figures" if k else "the Meshcat replay")
    return figs, replay


def warm_plotting(workers: int | None = None) -> None:
    """Have the pool's idle running workers import matplotlib now (~0.3 s), so that
    :func:`figures_and_replay` finds it loaded there; starts no worker."""
    from drakedeburr.pool import warm_pool

    warm_pool(_import_pyplot, (), workers, start=False)


def _import_pyplot() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401


def meshcat_replay_html(plan, cell=None, hub_model=None, *, fps: float = 20.0,
                        max_frames: int = 600) -> str | None:
    """Drake's static Meshcat page replaying the plan's trajectory, or None when the viz
    stage is not available (message logged)."""
    try:
        from drakedeburr.viz import scene
    except ImportError as exc:  # pragma: no cover - depends on the viz stage being installed
        log.warning("no Meshcat replay: %s", exc)
        return None
    if len(plan.trajectory.t) < 2:
        log.info("no Meshcat replay: the plan holds no motion (nothing could be planned)")
        return None
    if cell is None:
        from drakedeburr.cell.station import load_plan_cell

        cell = load_plan_cell(plan)
    meshcat = scene.get_meshcat(new=True)
    try:
        scene.publish_cell(meshcat, cell, plan.trajectory.q[0])
        if hub_model is not None:
            scene.publish_edge_loops(meshcat, [w.p_HE for w in hub_model.windows],
                                     cell.X_WH(cell.q_home))
        n = int(min(max_frames, max(2, plan.trajectory.duration * fps)))
        times = np.linspace(0.0, plan.trajectory.duration, n)
        scene.animate_cell(meshcat, cell, times, plan.trajectory.value(times),
                           frames_per_second=n / max(plan.trajectory.duration, 1e-9))
        return meshcat.StaticHtml()
    finally:
        del meshcat
        scene.collect_here()  # free it on this thread (see collect_here)


def _fmt(v, unit: str) -> str:
    if v is None:
        return "&ndash;"
    if unit == "m":
        return f"{v * 1e3:.4g} mm"
    if unit == "m/s":
        return f"{v * 1e3:.4g} mm/s"
    if unit == "rad":
        return f"{v:.4g} rad ({np.degrees(v):.3g}&deg;)"
    return f"{v:.4g} {html.escape(unit)}"


_CSS = """
body { font-family: system-ui, sans-serif; margin: 1.5em; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
.verdict { font-size: 1.3em; font-weight: bold; padding: .3em .8em; display: inline-block; }
.pass { background: #d8f5d8; color: #175217; } .fail { background: #f8d7d7; color: #7a1212; }
.adv { background: #fff3cd; color: #6b5100; }
table { border-collapse: collapse; font-size: .85em; }
td, th { border: 1px solid #ccc; padding: .25em .5em; vertical-align: top; text-align: left; }
figure { margin: .5em 0 1.5em; } figure svg { max-width: 100%; height: auto; }
iframe { width: 100%; height: 600px; border: 1px solid #ccc; }
"""


def report_html(report: VerificationReport, *, replay_html: str | None = None,
                figures: dict[str, str] | None = None) -> str:
    """The HTML page (see module docstring); ``figures``: :func:`report_figures` of the
    report when already made."""
    doc = report_dict(report)
    figs = report_figures(report) if figures is None else figures
    rows = []
    for it in report.items:
        cls = "pass" if it.passed else ("fail" if it.required else "adv")
        verdict = "PASS" if it.passed else ("FAIL" if it.required else "MISS")
        where = []
        if it.window is not None:
            where.append(f"window {it.window}")
        if it.time is not None:
            where.append(f"t = {it.time:.3f} s")
        if it.target_index is not None:
            where.append(f"target {it.target_index}")
        if it.pair:
            where.append(" &harr; ".join(html.escape(p) for p in it.pair))
        rows.append(
            f'<tr class="item" data-name="{html.escape(it.name)}">'
            f'<td class="{cls}">{verdict}</td><td>{html.escape(it.name)}'
            f'{"" if it.required else " (advisory)"}</td>'
            f"<td>{_fmt(it.value, it.unit)}</td><td>{html.escape(it.comparison)} "
            f"{_fmt(it.limit, it.unit)}</td><td>{'<br>'.join(where)}</td>"
            f"<td>{html.escape(it.detail)}</td></tr>")
    info = doc["plan"]
    verdict = ("<span class='verdict pass'>PASSED</span>" if report.passed else
               f"<span class='verdict fail'>FAILED: {html.escape(', '.join(report.failed))}"
               "</span>")
    titles = {"theta": "Tool axis angles along the path", "joints": "Joint angles",
              "speed": "TCP speed", "clearance": "Clearance", "deviation": "Deviation"}
    figures = "\n".join(
        f'<h2>{titles[k]}</h2><figure class="plot" id="plot-{k}">{svg}</figure>'
        for k, svg in figs.items())
    if replay_html:
        replay = ('<h2>Replay (Meshcat)</h2><iframe id="replay" title="Meshcat replay" '
                  f'srcdoc="{html.escape(replay_html, quote=True)}"></iframe>')
    else:
        replay = "<h2>Replay (Meshcat)</h2><p>not included</p>"
    per_window = []
    for it in report.items:
        if it.per_window and it.name in ("theta_statistics", "j4_j6_range", "tcp_speed_band",
                                         "cl_chord_error"):
            per_window.append(f"<h3>{html.escape(it.name)}</h3><pre>"
                              f"{html.escape(_pretty(doc, it.name))}</pre>")
        if it.name == "tcp_speed_band" and it.per_window:
            per_window.append(_slow_stretch_table(it.per_window))
        if it.name == "time_budget" and it.per_window:
            per_window.append(_time_budget_tables(it.per_window))
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>drakedeburr verification: {html.escape(str(info['hub']))}</title>
<style>{_CSS}</style></head>
<body>
<h1>Verification of the plan for hub {html.escape(str(info['hub']))}
({html.escape(str(info['scenario']))}, {html.escape(str(info['mode']))}-in-hand)</h1>
<p>{verdict}</p>
<p>{info['targets']} targets, {info['segments']} segments, {info['knots']} knots,
cycle {info['duration_s']:.3f} s, windows {info['windows']} of {info['expected_windows']};
{report.settings['samples']} samples. Schema {html.escape(doc['schema'])};
run {html.escape(str(report.run.get('timestamp', '')))}.</p>
<h2>Checks</h2>
<table id="checks"><thead><tr><th></th><th>check</th><th>measured</th><th>limit</th>
<th>worst location</th><th>detail</th></tr></thead><tbody>
{''.join(rows)}
</tbody></table>
{figures}
<h2>Per window</h2>
{''.join(per_window)}
{replay}
</body></html>
"""


def _slow_stretch_table(per_window: dict) -> str:
    """Where each window's cut leaves the speed band and which joint limit sets the speed."""
    rows = []
    for w, info in per_window.items():
        for st in info.get("slow_stretches", []):
            rows.append(
                f"<tr><td>{html.escape(str(w))}</td><td>{mm_from_m(st['from_m']):.1f} - "
                f"{mm_from_m(st['to_m']):.1f}</td><td>{mm_s_from_m_s(st['min_mps']):.1f}</td>"
                f"<td>{html.escape(st['at'])}</td><td>{html.escape(st['joint'])} "
                f"{html.escape(st['limit'])}</td><td>{100 * st['ratio']:.0f} %</td></tr>")
    return ("<h3>slow stretches (outside the speed band)</h3>"
            '<table id="slow-stretches"><thead><tr><th>window</th><th>tool travel [mm]</th>'
            "<th>slowest [mm/s]</th><th>where</th><th>nearest limit</th><th>share of it</th>"
            f"</tr></thead><tbody>{''.join(rows)}</tbody></table>")


def _time_budget_tables(per_window: dict) -> str:
    """Where the cycle's time goes: per window the cut against its edge length over the feed,
    the wrist ranges and the limits binding its slow stretches; every move off the cut
    against the least time of its joint displacement at the joint limits."""
    cuts, moves = [], []

    def move_rows(ms, before):
        for m in ms:
            prog = "&ndash;" if m["programmed_s"] is None else f"{m['programmed_s']:.3f}"
            moves.append(
                f"<tr><td>{html.escape(str(before))}</td><td>{html.escape(m['kind'])}</td>"
                f"<td>{m['duration_s']:.3f}</td><td>{m['bound_s']:.3f}</td>"
                f"<td>{m['duration_s'] / max(m['bound_s'], 1e-9):.2f}</td>"
                f"<td>{html.escape(m['bound_joint'])} {html.escape(m['bound_limit'])}</td>"
                f"<td>{prog}</td><td>{html.escape(m['peak_joint'])} "
                f"{html.escape(m['peak_limit'])} {100 * m['peak_ratio']:.0f} %</td></tr>")

    for w, r in per_window.items():
        if "air_after" in r:
            move_rows(r["air_after"], "end")
            continue
        move_rows(r["air_before"], f"window {w}")
        slow = "<br>".join(
            f"{mm_from_m(st['from_m']):.1f}-{mm_from_m(st['to_m']):.1f} mm, "
            f"{mm_s_from_m_s(st['min_mps']):.0f} mm/s: {html.escape(st['joint'])} "
            f"{html.escape(st['limit'])} {100 * st['ratio']:.0f} %"
            for st in r["slow_stretches"])
        wrist = " / ".join(f"{deg_from_rad(r[k]):.1f}"
                           for k in ("j4_range_rad", "j5_range_rad", "j6_range_rad"))
        cuts.append(
            f"<tr><td>{html.escape(str(w))}</td><td>{r['cut_s']:.3f}</td>"
            f"<td>{mm_from_m(r['edge_length_m']):.1f}</td><td>{r['edge_seconds']:.3f}</td>"
            f"<td>{r['cut_ratio']:.3f}</td><td>{100 * r['fraction_in_band']:.1f} %</td>"
            f"<td>{wrist}</td><td>{r['air_before_s']:.3f} / {r['air_bound_s']:.3f}</td>"
            f"<td>{slow}</td></tr>")
    return ("<h3>time_budget: where the cycle goes</h3>"
            '<table id="time-budget"><thead><tr><th>window</th><th>cut [s]</th>'
            "<th>edge length [mm]</th><th>edge / feed [s]</th><th>ratio</th><th>at the feed</th>"
            "<th>J4 / J5 / J6 range [deg]</th><th>moves before: time / bound [s]</th>"
            f"<th>slow stretches: the limit that binds</th></tr></thead><tbody>{''.join(cuts)}"
            "</tbody></table>"
            "<h3>moves off the cut against the least time of their joint displacement at the "
            "joint limits</h3>"
            '<table id="air-moves"><thead><tr><th>before</th><th>move</th><th>time [s]</th>'
            "<th>bound [s]</th><th>ratio</th><th>bound set by</th>"
            "<th>at programmed speed [s]</th><th>limit most in use</th></tr></thead><tbody>"
            f"{''.join(moves)}</tbody></table>")


def _pretty(doc: dict, name: str) -> str:
    import json

    item = next(i for i in doc["items"] if i["name"] == name)
    return json.dumps(item["per_window"], indent=1, sort_keys=True)


def write_report_html(report: VerificationReport, path: str | Path, *,
                      replay_html: str | None = None) -> Path:
    """Write ``report.html`` atomically."""
    return atomic_write_text(Path(path), report_html(report, replay_html=replay_html))


def write_report_files(report: VerificationReport, folder: str | Path, *, plan=None,
                       replay: bool = True, cell=None) -> tuple[Path, Path]:
    """Write the report into its plan's folder, where the export gate reads it:
    ``report.json`` and ``report.html`` (with a Meshcat replay of ``plan`` when given and
    ``replay``, in ``cell`` when given, else the plan's cell built here). The two are written
    together (:func:`drakedeburr._io.atomic_write_files`): an interruption leaves both as they
    were. Returns their paths."""
    from drakedeburr._io import atomic_write_files
    from drakedeburr.verify.gate import REPORT_FILE, REPORT_HTML

    folder = Path(folder)
    figures, replay_html = figures_and_replay(report, plan if replay else None, cell)
    html = report_html(report, replay_html=replay_html, figures=figures)
    written = atomic_write_files({folder / REPORT_HTML: html,
                                  folder / REPORT_FILE: report_json(report)})
    return written[1], written[0]
