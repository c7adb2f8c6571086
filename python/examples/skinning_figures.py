"""Pictures and figures for docs/skinning.md: the skinning methods side by side on the built-in character.

    PYTHONPATH=build/python python3 python/examples/skinning_figures.py [--out docs/images]

Writes skinning-methods.png: the left arm with its elbow bent to 150 degrees (the top row) and its forearm twisted
by 120 degrees (the bottom row: the candy wrapper), skinned by linear blend skinning, dual quaternions, linear
blend skinning followed by Delta Mush, and Direct Delta Mush. Prints, per method and pose, how much of the body's
volume is kept (the signed volume of the closed mesh, before and after; all of the change is at the arm), and the
two binds' times in this process (docs/performance.md has the per-frame costs). Needs the deform module and
matplotlib.
"""
import argparse
import pathlib
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

import deform  # noqa: E402

METHODS = ("LBS", "DQS", "LBS + Delta Mush", "Direct Delta Mush")


def signed_volume(points, triangles):
    a, b, c = (points[triangles[:, k]].astype(np.float64) for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def posed(model, bone, degrees):
    skeleton = model.skeleton
    pose = skeleton.bind_pose()
    skeleton.set_euler(pose, bone, degrees, clamp=False)
    return pose


def skin_all(model, pose, ddm, timings):
    """The points of `pose` by each method, in METHODS' order."""
    out = {}
    for method in ("lbs", "dqs"):
        character = deform.Character(model)
        character.skinning = method
        character.set_pose(pose)
        start = time.perf_counter()
        character.update(0.0)
        timings.setdefault(method.upper(), []).append(time.perf_counter() - start)
        out[method.upper()] = np.array(character.positions)
    character = deform.Character(model)
    start = time.perf_counter()
    character.set_delta_mush(iterations=10, step=0.5)
    timings.setdefault("bind LBS + Delta Mush", []).append(time.perf_counter() - start)
    character.set_pose(pose)
    start = time.perf_counter()
    character.update(0.0)
    timings.setdefault("LBS + Delta Mush", []).append(time.perf_counter() - start)
    out["LBS + Delta Mush"] = np.array(character.positions)
    _, palette = deform.forward_kinematics(model.skeleton, pose)
    start = time.perf_counter()
    out["Direct Delta Mush"] = np.array(ddm.skin(palette))
    timings.setdefault("Direct Delta Mush", []).append(time.perf_counter() - start)
    return out


def arm_region(model, points, pose):
    """Triangles of the left arm around the elbow, the elbow, and the direction to look from: across the plane of
    shoulder, elbow and wrist when the arm bends, else from the front."""
    skeleton = model.skeleton
    world, _ = deform.forward_kinematics(skeleton, pose)
    head = {name: np.array(world[skeleton.find(name)])[:3, 3] for name in ("upperarm_l", "forearm_l", "hand_l")}
    elbow = head["forearm_l"]
    triangles = np.asarray(model.triangles)
    centres = points[triangles].mean(axis=1)
    near = np.linalg.norm(centres - elbow, axis=1) < 0.3
    across = np.cross(head["forearm_l"] - head["upperarm_l"], head["hand_l"] - head["forearm_l"])
    if np.linalg.norm(across) < 1e-6:
        across = np.array([0.0, 0.15, 1.0])
    return triangles[near], elbow, across / np.linalg.norm(across)


def draw(ax, points, triangles, centre, look, title):
    faces = points[triangles]
    normals = np.cross(faces[:, 1] - faces[:, 0], faces[:, 2] - faces[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    light = look + np.array([0.0, 0.6, 0.0])
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.abs(normals @ light)
    colours = np.clip(np.outer(shade, [0.85, 0.72, 0.62]), 0, 1)
    # matplotlib draws x, y, z with z up: the model's y (up) goes to the plot's z.
    swapped = faces[:, :, [0, 2, 1]]
    ax.add_collection3d(Poly3DCollection(swapped, facecolors=colours, edgecolors="none"))
    r = 0.22
    ax.set_xlim(centre[0] - r, centre[0] + r)
    ax.set_ylim(centre[2] - r, centre[2] + r)
    ax.set_zlim(centre[1] - r, centre[1] + r)
    ax.set_box_aspect((1, 1, 1))
    # Looking along -look: matplotlib's elevation and azimuth of `look` in the plot's axes (x, z, y).
    ax.view_init(elev=np.degrees(np.arcsin(look[1])), azim=np.degrees(np.arctan2(look[2], look[0])))
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="docs/images", help="folder for the PNG file")
    out = pathlib.Path(parser.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)

    model = deform.builtin_character()
    triangles = np.asarray(model.triangles)
    rest_volume = signed_volume(np.asarray(model.positions), triangles)
    start = time.perf_counter()
    ddm = deform.DirectDeltaMush(model)
    ddm_bind = time.perf_counter() - start

    poses = (("elbow bent 150°", posed(model, "forearm_l", (150.0, 0.0, 0.0))),
             ("forearm twisted 120°", posed(model, "forearm_l", (0.0, 120.0, 0.0))))
    timings = {}
    fig = plt.figure(figsize=(12, 6.4), dpi=100)
    print("| pose | method | body volume kept | volume lost |")
    print("|---|---|---:|---:|")
    for row, (name, pose) in enumerate(poses):
        skinned = skin_all(model, pose, ddm, timings)
        for col, method in enumerate(METHODS):
            points = skinned[method]
            region, elbow, look = arm_region(model, points, pose)
            ax = fig.add_subplot(2, 4, row * 4 + col + 1, projection="3d")
            draw(ax, points, region, elbow, look, f"{method}\n{name}")
            volume = signed_volume(points, triangles)
            lost_cm3 = (rest_volume - volume) * 1e6  # the model is in metres
            print(f"| {name} | {method} | {100.0 * volume / rest_volume:.2f}% | {lost_cm3:.0f} cm³ |")
    fig.tight_layout()
    fig.savefig(out / "skinning-methods.png")
    plt.close(fig)
    print(f"bind: Delta Mush {1e3 * min(timings['bind LBS + Delta Mush']):.1f} ms, "
          f"Direct Delta Mush {1e3 * ddm_bind:.1f} ms (this process, one run)")
    print(f"wrote {out}/skinning-methods.png")


if __name__ == "__main__":
    main()
