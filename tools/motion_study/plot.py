#!/usr/bin/env python3
"""The figures of docs/elasticity.md, "Measured": a whipped six-link chain's tip height over time at 15 Hz and at
240 Hz, libdeform's spring chain beside a naive per-frame spring (VRM's update) with the same parameters at 60 Hz;
and the built-in run's limbs' lengths with the tuned jiggle and an untamed one, against the rigid run, beside an
imported run's (Testwuson.X with default_rig) with the tuned jiggle and every lattice at inertia 1.

    python3 tools/motion_study/plot.py MOTION_STUDY_BINARY [--out FILE] [--flesh-out FILE]
      (defaults: docs/images/secondary-motion.png, docs/images/jiggle-flesh.png)

Runs the study binary (built as build/tools/motion_study) for its CSVs, then draws them with matplotlib.
"""
import argparse
import csv
import pathlib
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def draw_flesh(binary, out):
    """The built-in run's right leg and left arm, and an imported run's leg that the old knob changed most (Testwuson,
    default_rig, when assimp-testmodels is installed): length change against the rigid run (%)."""
    with tempfile.TemporaryDirectory() as folder:
        path, imported_path = pathlib.Path(folder) / "flesh.csv", pathlib.Path(folder) / "imported.csv"
        subprocess.run([binary, "--flesh-csv", str(path), "--imported-csv", str(imported_path)], check=True,
                       stdout=subprocess.DEVNULL)
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        with open(imported_path, newline="") as f:
            imported = list(csv.DictReader(f))

    def change(table, limb, kind):
        return [100.0 * (float(r[limb + "_" + kind]) / float(r[limb + "_rigid"]) - 1.0) for r in table]

    untamed = "inertia 1, far faces free, no bound"
    panels = [(rows, "thigh_r-foot_r", "built-in run: right leg, hip to ankle", "untamed", untamed),
              (rows, "upperarm_l-hand_l", "built-in run: left arm, shoulder to wrist", "untamed", untamed)]
    if imported:
        limbs = [key[:-len("_rigid")] for key in imported[0] if key.endswith("_rigid")]
        worst = max(limbs, key=lambda limb: max(abs(c) for c in change(imported, limb, "every")))
        panels.append((imported, worst, f"Testwuson.X run (default_rig): {worst}", "every",
                       "every lattice inertia 1 (the old knob at 1)"))
    figure, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 3.6))
    for ax, (table, limb, title, other, other_label) in zip(axes, panels):
        t = [float(r["t"]) for r in table]
        ax.axhspan(-2.0, 2.0, color="#2ca02c", alpha=0.12, label="within 2%")
        ax.plot(t, change(table, limb, other), color="#d62728", linestyle="--", label=other_label)
        ax.plot(t, change(table, limb, "tuned"), color="#1f77b4", label="tuned (default_lattice_motion)")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=7)
    axes[0].set_ylabel("length change vs the rigid run (%)")
    figure.suptitle("Runs: limbs keep their length, the flesh between the joints jiggles", fontsize=11)
    figure.tight_layout()
    pathlib.Path(out).parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=110)
    print(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("binary")
    parser.add_argument("--out", default="docs/images/secondary-motion.png")
    parser.add_argument("--flesh-out", default="docs/images/jiggle-flesh.png")
    args = parser.parse_args()
    draw_flesh(args.binary, args.flesh_out)
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "whip.csv"
        subprocess.run([args.binary, "--csv", str(path)], check=True, stdout=subprocess.DEVNULL)
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    t = [float(r["t"]) for r in rows]
    figure, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, method, title in ((axes[0], "libdeform", "libdeform: exact sub-steps"),
                              (axes[1], "naive", "naive per-frame spring (VRM's update)")):
        ax.plot(t, [float(r[method + "_240"]) for r in rows], color="#1f77b4", label="240 Hz")
        ax.plot(t, [float(r[method + "_15"]) for r in rows], color="#d62728", linestyle="--", label="15 Hz")
        ax.set_title(title)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right")
    axes[0].set_ylabel("tip height (m)")
    figure.suptitle("A whipped six-link chain, sampled every 1/15 s", fontsize=11)
    figure.tight_layout()
    pathlib.Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=110)
    print(args.out)


if __name__ == "__main__":
    main()
