#!/usr/bin/env python3
"""The figures of docs/python.md, made with the `deform` module and matplotlib.

    python3 python/examples/figures.py [--out FOLDER]     (default: docs/images, relative to the current folder)

1. python_reach.png: the built-in character reaches past its arm's length, its elastic lattices stretch to cover
   the rest, then it lets go and the stretch springs back (distance to the target and stretch over time).
2. python_reach_pose.png: the character's points (front view) at rest and reaching, just before it lets go.
3. python_lattice.png: a Bezier lattice around a point cloud (a torus), four control points moved, the cloud deformed.
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import deform  # noqa: E402

DT = 1.0 / 60.0


def reach_and_release(out):
    hero = deform.Character.builtin()
    hero.update(0.0)
    rest = hero.positions.copy()  # positions is a view of the character's storage: copy to keep a frame
    target = np.array([1.6, 1.5, 0.3], np.float32)
    result = hero.reach("hand_l", target)
    times, distances, stretches = [], [], []
    reached = None
    for frame in range(int(4.0 / DT)):
        if frame == int(2.0 / DT):
            reached = hero.positions.copy()
            hero.release()
        hero.update(DT)
        times.append((frame + 1) * DT)
        distances.append(float(np.linalg.norm(np.array(hero.bone_position("hand_l")) - target)))
        stretches.append(hero.stretch)

    fig, ax = plt.subplots(figsize=(7, 3.6), dpi=100)
    ax.plot(times, distances, label="hand to target (m)")
    ax.plot(times, stretches, label="lattice stretch (m)")
    ax.axvline(2.0, color="grey", linestyle=":", linewidth=1)
    ax.text(2.03, max(stretches) * 0.95, "release()", color="grey")
    ax.set_xlabel("time (s), update(1/60) per frame")
    ax.set_title(f"reach(hand_l): IK leaves {result.residual:.2f} m, the lattices stretch to cover it")
    ax.legend(loc="center right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "python_reach.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=100)
    ax.scatter(rest[:, 0], rest[:, 1], s=0.5, color="0.7", label="rest")
    ax.scatter(reached[:, 0], reached[:, 1], s=0.5, color="tab:blue", label="reached, 2 s after reach()")
    ax.plot([target[0]], [target[1]], "x", color="tab:red", markersize=8)
    ax.annotate("target", (target[0], target[1]), textcoords="offset points", xytext=(-12, 10), color="tab:red")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="lower right", markerscale=8)
    fig.tight_layout()
    fig.savefig(out / "python_reach_pose.png")
    plt.close(fig)
    return result, distances, stretches


def torus(count, seed=0):
    rng = np.random.default_rng(seed)
    a, b = rng.uniform(0, 2 * np.pi, size=(2, count))
    r = 1.0 + 0.35 * np.cos(b)
    return np.stack([r * np.cos(a), 0.35 * np.sin(b), r * np.sin(a)], axis=1).astype(np.float32)


def lattice_on_a_cloud(out):
    cloud = torus(6000)
    lattice = deform.BezierLattice.around(cloud, degree=(2, 2, 2))
    binding = lattice.bind(cloud)  # once; deform() below reuses it
    points = lattice.control_points  # a writeable view: moving it moves the lattice
    for i in range(3):
        for k in range(3):
            if i == 2:
                points[lattice.index(i, 2, k)] += (0.0, 0.9, 0.0)  # lift the +x side of the top face
    points[lattice.index(0, 1, 1)] += (-0.6, 0.0, 0.0)  # pull the middle of the -x face out
    moved = lattice.deform(cloud, binding)

    fig = plt.figure(figsize=(9, 4.2), dpi=100)
    for n, (data, title) in enumerate(((cloud, "rest"), (moved, "deformed"))):
        ax = fig.add_subplot(1, 2, n + 1, projection="3d")
        ax.scatter(data[:, 0], data[:, 2], data[:, 1], s=0.3, c=cloud[:, 0], cmap="viridis")
        shown = lattice.rest_points if n == 0 else points
        ax.scatter(shown[:, 0], shown[:, 2], shown[:, 1], s=12, color="tab:red")
        ax.set_title(title)
        ax.set_xlim(-1.5, 1.5)
        ax.set_ylim(-1.5, 1.5)
        ax.set_zlim(-0.8, 1.6)
        ax.view_init(elev=18, azim=-60)
    fig.tight_layout()
    fig.savefig(out / "python_lattice.png")
    plt.close(fig)
    return cloud, moved


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="docs/images", help="folder for the PNG files")
    out = pathlib.Path(parser.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)
    result, distances, stretches = reach_and_release(out)
    print(f"reach: residual after IK {result.residual:.3f} m, hand to target after 2 s {distances[119]:.4f} m, "
          f"stretch 2 s after release {stretches[-1]:.4f} m")
    cloud, moved = lattice_on_a_cloud(out)
    print(f"lattice: {len(cloud)} points, largest move {np.linalg.norm(moved - cloud, axis=1).max():.3f}")
    print(f"wrote {out}/python_reach.png, python_reach_pose.png, python_lattice.png")


if __name__ == "__main__":
    main()
