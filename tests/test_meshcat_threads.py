"""Drake's Meshcat must die on the thread that made it: our code frees the ones it drops.

Each case runs in a child process because the failure mode is an abort of the whole process
(``meshcat.cc``: ``IsThread(main_thread_id_)``), which would take pytest down with it.
"""

import subprocess
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

PRELUDE = """
import gc, threading
gc.disable()  # only the collections this script asks for
def collect_on_other_thread():
    t = threading.Thread(target=gc.collect); t.start(); t.join()
def dropped_meshcat_in_a_diagram():
    from pydrake.geometry import Meshcat, MeshcatVisualizer, SceneGraph
    from pydrake.systems.framework import DiagramBuilder
    builder = DiagramBuilder()
    sg = builder.AddSystem(SceneGraph())
    MeshcatVisualizer.AddToBuilder(builder, sg, Meshcat())
    builder.Build()
"""


def _run(body: str, tmp_path: Path) -> subprocess.CompletedProcess:
    script = tmp_path / "case.py"
    script.write_text(PRELUDE + textwrap.dedent(body))
    env = {"PYTHONPATH": f"{REPO}{__import__('os').pathsep}{REPO / 'tests'}",
           "DRAKEDEBURR_TEST_MODE": "1", "PATH": "/usr/bin:/bin"}
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=600, env=env, cwd=tmp_path)


def test_a_dropped_meshcat_collected_elsewhere_aborts(tmp_path):
    # the hazard itself: without collect_here the process dies (this is what CI hit once)
    r = _run("""
        dropped_meshcat_in_a_diagram()
        collect_on_other_thread()
        print("survived")
    """, tmp_path)
    assert r.returncode != 0 and "survived" not in r.stdout
    assert "IsThread" in r.stderr


def test_collect_here_frees_it_on_the_calling_thread(tmp_path):
    r = _run("""
        from drakedeburr.viz.scene import collect_here
        dropped_meshcat_in_a_diagram()
        collect_here()
        collect_on_other_thread()
        print("survived")
    """, tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "survived" in r.stdout


def test_replay_html_leaves_no_meshcat_behind(tmp_path):
    r = _run("""
        import verify_support as vs
        from drakedeburr.viz.playback import save_plan_html
        path = save_plan_html(vs.good_plan(), "replay.html", dt=1.0)
        assert path.stat().st_size > 10000
        collect_on_other_thread()
        print("survived")
    """, tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "survived" in r.stdout
