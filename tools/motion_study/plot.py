#!/usr/bin/env python3
"""The figure of docs/elasticity.md, "Measured": a whipped six-link chain's tip height over time at 15 Hz and at
240 Hz, libdeform's spring chain beside a naive per-frame spring (VRM's update) with the same parameters at 60 Hz.

    python3 tools/motion_study/plot.py MOTION_STUDY_BINARY [--out FILE]   (default: docs/images/secondary-motion.png)

Runs the study binary (built as build/tools/motion_study) for its CSV, then draws it with matplotlib.
"""
import argparse
import csv
import pathlib
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("binary")
    parser.add_argument("--out", default="docs/images/secondary-motion.png")
    args = parser.parse_args()
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
