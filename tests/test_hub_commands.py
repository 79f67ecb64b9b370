import json

import numpy as np

from drakedeburr.cli import main


def test_hub_list_and_info(capsys):
    assert main(["-q", "hub", "list"]) == 0
    out = capsys.readouterr().out
    for name in ("h5_straight", "h5_split", "h6_curved", "h5_deepdish"):
        assert name in out
    assert "5 large, 5 small" in out
    assert main(["-q", "hub", "info", "h5_split"]) == 0
    assert "small" in capsys.readouterr().out
    assert main(["-q", "hub", "info", "h5_split", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["window_count"] == 10


def test_hub_generate_bad_input_exit_code(tmp_path, capsys):
    assert main(["-q", "hub", "generate", "no_such_hub", "--out", str(tmp_path)]) == 2
    assert "unknown hub 'no_such_hub'" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nspoke_count: 5\nspoke_width_mm: 95\n")
    assert main(["-q", "hub", "generate", "--spec", str(bad), "--out", str(tmp_path)]) == 2
    assert "'spoke_width'" in capsys.readouterr().err


def test_hub_scan_writes_a_point_cloud(tmp_path):
    import open3d as o3d

    out = tmp_path / "scan.ply"
    assert main(["-q", "hub", "scan", "h5_straight", str(out), "--spacing-mm", "6"]) == 0
    pts = np.asarray(o3d.io.read_point_cloud(str(out)).points)
    assert len(pts) > 1000
    assert np.hypot(pts[:, 0], pts[:, 1]).max() < 0.24  # metres, frame H
