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


def test_skinning_figures_script_writes_its_png_and_volumes(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "python" / "examples" / "skinning_figures.py"), "--out",
                          str(tmp_path)], capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    for name in ("skinning-methods.png", "skinning-methods-mrfixit.png"):  # assimp-testmodels: scripts/deps.sh
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    kept = {}
    for line in run.stdout.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 4 and cells[2].endswith("%"):
            kept[(cells[0], cells[1])] = float(cells[2][:-1])
    assert len(kept) == 8, run.stdout
    # Every method keeps the arm's volume within 3%; dual quaternions keep it best at the bent elbow (their bulge).
    assert all(97.0 < v < 101.0 for v in kept.values()), kept
    bent = {m: v for (p, m), v in kept.items() if p.startswith("elbow")}
    assert bent["DQS"] == max(bent.values()), bent


def test_bake_figures_script_writes_its_png_and_holds_the_bones_bake_to_its_targets(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "python" / "examples" / "bake_figures.py"), "--out",
                          str(tmp_path)], capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    data = (tmp_path / "bake-error.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    rows = {}
    for line in run.stdout.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 6 and cells[2].endswith("%"):
            rows[(cells[0], cells[1])] = [float(c[:-1]) for c in cells[2:]]
    assert len(rows) == 4, run.stdout
    for (motion, bake), (largest_on, largest_between, rms_on, rms_between) in rows.items():
        if bake == "bones":  # issue 35's targets, on the frames the bake saw
            assert largest_on <= 2.0 and rms_on <= 0.5, (motion, rows)
        else:  # the morph targets are the frames themselves, to the writer's tolerance
            assert largest_on < 1e-3, (motion, rows)
        assert largest_between < 5.0, (motion, rows)
