"""Pictures and figures for docs/skinning.md: the skinning methods side by side on the built-in character.

    PYTHONPATH=build/python python3 python/examples/skinning_figures.py [--out docs/images]

Writes skinning-methods.png: the left arm with its elbow bent to 150 degrees (the top row) and its forearm twisted
by 120 degrees (the bottom row: the candy wrapper), skinned by linear blend skinning, dual quaternions, linear
blend skinning followed by Delta Mush, and Direct Delta Mush; and skinning-methods-mrfixit.png: the same four on a
real character, assimp-testmodels' mrfixit (--real), its left elbow bent by 100 degrees. Prints, per method and pose, how much of the body's
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


def arm_region(model, points, pose, arm=("upperarm_l", "forearm_l", "hand_l"), reach=0.3, front=(0.0, 0.15, 1.0)):
    """Triangles of an arm around the elbow (within `reach` of it), the elbow, and the direction to look from: across
    the plane of shoulder, elbow and wrist when the arm bends, else `front`."""
    skeleton = model.skeleton
    world, _ = deform.forward_kinematics(skeleton, pose)
    shoulder, elbow, wrist = (np.array(world[skeleton.find(name)])[:3, 3] for name in arm)
    triangles = np.asarray(model.triangles)
    centres = points[triangles].mean(axis=1)
    near = np.linalg.norm(centres - elbow, axis=1) < reach
    across = np.cross(elbow - shoulder, wrist - elbow)
    if np.linalg.norm(across) < 1e-6 * reach * reach:
        across = np.array(front)
    return triangles[near], elbow, across / np.linalg.norm(across)


def draw(ax, points, triangles, centre, look, title, radius=0.22, up=1):
    faces = points[triangles]
    normals = np.cross(faces[:, 1] - faces[:, 0], faces[:, 2] - faces[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    light = look + 0.6 * np.eye(3)[up]
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.abs(normals @ light)
    colours = np.clip(np.outer(shade, [0.85, 0.72, 0.62]), 0, 1)
    # matplotlib draws x, y, z with z up: the model's up axis (1 for +Y, 2 for +Z) goes to the plot's z.
    axes = [0, 2, 1] if up == 1 else [0, 1, 2]
    ax.add_collection3d(Poly3DCollection(faces[:, :, axes], facecolors=colours, edgecolors="none"))
    c, v = centre[axes], look[axes]
    ax.set_xlim(c[0] - radius, c[0] + radius)
    ax.set_ylim(c[1] - radius, c[1] + radius)
    ax.set_zlim(c[2] - radius, c[2] + radius)
    ax.set_box_aspect((1, 1, 1))
    # Looking along -look: matplotlib's elevation and azimuth of `look` in the plot's axes.
    ax.view_init(elev=np.degrees(np.arcsin(v[2])), azim=np.degrees(np.arctan2(v[1], v[0])))
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


# assimp-testmodels' mrfixit (Debian's package, which scripts/deps.sh installs): a game character, +Z up.
MRFIXIT = pathlib.Path("/usr/share/assimp/models/IQM/mrfixit.iqm")


def real_character(path, out):
    """skinning-methods-mrfixit.png: the same four methods on a real character's left elbow bent by 100 degrees."""
    if not path.exists():
        print(f"skipped the real character: {path} is not there")
        return
    model = deform.import_model(str(path))["model"]
    pose = posed(model, "LowerArm.L", (0.0, 0.0, 100.0))
    skinned = skin_all(model, pose, deform.DirectDeltaMush(model), {})
    fig = plt.figure(figsize=(12, 3.6), dpi=100)
    for col, method in enumerate(METHODS):
        points = skinned[method]
        region, elbow, _ = arm_region(model, points, pose, ("UpperArm.L", "LowerArm.L", "Hand.L"), reach=1.8)
        top = np.array([0.0, -0.2, 1.0]) / np.linalg.norm([0.0, -0.2, 1.0])  # from above: the arm bends level
        ax = fig.add_subplot(1, 4, col + 1, projection="3d")
        draw(ax, points, region, elbow, top, f"{method}\n{path.stem}, elbow bent 100°", radius=1.5, up=2)
    fig.tight_layout()
    fig.savefig(out / "skinning-methods-mrfixit.png")
    plt.close(fig)
    print(f"wrote {out}/skinning-methods-mrfixit.png")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="docs/images", help="folder for the PNG files")
    parser.add_argument("--real", default=str(MRFIXIT), help="the rigged model of the second picture")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
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
    real_character(pathlib.Path(args.real), out)
    print(f"bind: Delta Mush {1e3 * min(timings['bind LBS + Delta Mush']):.1f} ms, "
          f"Direct Delta Mush {1e3 * ddm_bind:.1f} ms (this process, one run)")
    print(f"wrote {out}/skinning-methods.png")


if __name__ == "__main__":
    main()
