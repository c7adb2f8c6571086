"""python/examples/figures.py (the figures of docs/python.md) runs and writes its PNG files."""
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_figures_script_writes_its_pngs(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "python" / "examples" / "figures.py"), "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    for name in ("python_reach.png", "python_reach_pose.png", "python_lattice.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    assert "reach: residual after IK 0.919 m" in run.stdout
