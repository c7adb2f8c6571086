"""libdeform's Delta Mush against Blender's Corrective Smooth on the built-in character (docs/skinning.md, "Against
Blender's Corrective Smooth"). Run by blender_study.sh; by hand:

    PYTHONPATH=build/python python3 tools/skinning_study/corrective_smooth.py export DIR
    blender --background --factory-startup --python tools/skinning_study/blender_corrective_smooth.py -- DIR
    PYTHONPATH=build/python python3 tools/skinning_study/corrective_smooth.py compare DIR

export: poses the built-in character as the pictures of docs/skinning.md do (left elbow bent 150 degrees, left
forearm twisted 120 degrees), skins it by LBS and writes DIR/input.json (bind points, point triangles, the LBS points
per pose, step and iteration counts, for Blender) and DIR/libdeform.json (Character's LBS + Delta Mush at each count).

compare: per pose and iteration count, the distance per point between libdeform's and Blender's results (mean, p99,
max, in % of the bind bounding-box diagonal), and what explains it, from double-precision NumPy re-implementations
of both algorithms as their sources describe them: the smoothing alone (Blender's use_only_smooth) against
libdeform's smoothing rule; each implementation against its own re-implementation; and the points libdeform pins.
--picture FILE also draws both results side by side (docs/images/skinning-corrective-smooth.png).

record DIR --fixture FILE: Blender's result at --fixture-at iterations (default 10), the points it moves, for
python/tests/test_delta_mush_blender.py, so that the suite compares with Blender without running it.
"""
import argparse
import json
import os
import pathlib

import numpy as np


def write_json(path, data):
    tmp = str(path) + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f)
    os.replace(tmp, path)


def export(folder, iterations, step):
    import deform

    model = deform.builtin_character()
    skeleton = model.skeleton
    poses = {}
    for name, euler in (("elbow bent 150°", (150.0, 0.0, 0.0)), ("forearm twisted 120°", (0.0, 120.0, 0.0))):
        pose = skeleton.bind_pose()
        skeleton.set_euler(pose, "forearm_l", euler, clamp=False)
        poses[name] = pose
    lbs, mushed, views = {}, {}, {}
    for name, pose in poses.items():
        # For the picture: the elbow, and a view across the plane of shoulder, elbow and wrist (or from the front).
        world, _ = deform.forward_kinematics(skeleton, pose)
        arm = ("upperarm_l", "forearm_l", "hand_l")
        shoulder, elbow, wrist = (np.array(world[skeleton.find(b)])[:3, 3] for b in arm)
        across = np.cross(elbow - shoulder, wrist - elbow)
        across = across if np.linalg.norm(across) > 1e-6 else np.array([0.0, 0.15, 1.0])
        views[name] = {"centre": elbow.tolist(), "look": (across / np.linalg.norm(across)).tolist()}
        character = deform.Character(model)
        character.skinning = "lbs"
        character.set_pose(pose)
        character.update(0.0)
        lbs[name] = np.asarray(character.positions, dtype=np.float32).tolist()
        for n in iterations:
            character = deform.Character(model)
            character.skinning = "lbs"
            character.set_delta_mush(iterations=n, step=step)
            character.set_pose(pose)
            character.update(0.0)
            mushed[f"{name}/{n}"] = np.asarray(character.positions, dtype=np.float32).tolist()
    folder.mkdir(parents=True, exist_ok=True)
    write_json(folder / "input.json", {
        "points": np.asarray(model.positions, dtype=np.float32).tolist(),
        "triangles": np.asarray(model.triangles).tolist(),
        "step": step, "iterations": iterations, "poses": lbs, "views": views})
    write_json(folder / "libdeform.json", {"results": mushed})
    print(f"wrote {folder}/input.json and {folder}/libdeform.json")


# ---- Double-precision re-implementations, from the two sources -------------------------------------------------

def edges_of(triangles):
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


def smooth(x, edges, step, iterations):
    """Both sources' smoothing: x <- x + step (mean of the one-ring - x), all points from the previous iteration."""
    x = x.copy()
    valence = np.bincount(edges.ravel(), minlength=len(x)).astype(np.float64)
    for _ in range(iterations):
        d = np.zeros_like(x)
        e = x[edges[:, 1]] - x[edges[:, 0]]
        np.add.at(d, edges[:, 0], e)
        np.add.at(d, edges[:, 1], -e)
        x += step * d / valence[:, None]
    return x


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def corner_frames(x, triangles):
    """Blender's tangent space per face corner (c with previous p and next n in the face): P = p - c and N = c - n,
    normalised; axes unit(P + N), unit(P x N) x unit(P + N), unit(P x N); its weight the angle between P and N (pi
    minus the corner's angle)."""
    c = x[triangles]
    prev, nxt = np.roll(c, 1, axis=1), np.roll(c, -1, axis=1)
    p, n = unit(prev - c), unit(c - nxt)
    z = unit(np.cross(p, n))
    t = unit(p + n)
    b = np.cross(z, t)
    weight = np.abs(np.arccos(np.clip(np.einsum("ijk,ijk->ij", p, n), -1.0, 1.0)))
    return np.stack([t, b, z], axis=-1), weight  # columns t, b, z


def blender_mush(rest, posed, triangles, step, iterations):
    edges = edges_of(triangles)
    s = smooth(rest, edges, step, iterations)
    frames, _ = corner_frames(s, triangles)
    deltas = np.einsum("ijkl,ijk->ijl", frames, (rest - s)[triangles])  # frame^T (rest - smoothed), per corner
    y = smooth(posed, edges, step, iterations)
    frames, weight = corner_frames(y, triangles)
    total = np.zeros(len(rest))
    np.add.at(total, triangles.ravel(), weight.ravel())
    moved = np.einsum("ijkl,ijl->ijk", frames, deltas) * (weight / total[triangles])[..., None]
    out = y.copy()
    np.add.at(out, triangles.reshape(-1), moved.reshape(-1, 3))
    return out


def libdeform_frames(x, triangles, tangent):
    """libdeform's frame per point: normal the sum of (a - x) x (b - x) over its triangles (x, a, b), tangent the
    edge to the chosen neighbour projected into the plane, bitangent normal x tangent. Also the unnormalised
    normal's length and the triangle count (the binder's scale)."""
    normal = np.zeros_like(x)
    for k in range(3):
        a, b, c = triangles[:, k], triangles[:, (k + 1) % 3], triangles[:, (k + 2) % 3]
        np.add.at(normal, a, np.cross(x[b] - x[a], x[c] - x[a]))
    length = np.linalg.norm(normal, axis=1)
    normal = normal / length[:, None]
    e = x[tangent] - x
    t = e - normal * np.einsum("ij,ij->i", normal, e)[:, None]
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    fans = np.bincount(triangles.ravel(), minlength=len(x))
    return np.stack([t, np.cross(normal, t), normal], axis=-1), normal, length, fans


def libdeform_mush(rest, posed, triangles, step, iterations):
    """The points and which of them the binder pins (they keep their input): the offset more than 8 times the
    neighbourhood's scale, the smaller of sqrt(|normal sum| / triangles) and the tangent edge's part in the plane."""
    edges = edges_of(triangles)
    s = smooth(rest, edges, step, iterations)
    _, normal, length, fans = libdeform_frames(s, triangles, np.arange(len(rest)))
    # The neighbour whose edge lies most in the plane, the first (lowest index) of equals.
    best = np.full(len(rest), -1.0)
    best_length2 = np.zeros(len(rest))
    tangent = np.zeros(len(rest), dtype=np.int64)
    for i, j in sorted([tuple(e) for e in edges] + [tuple(e[::-1]) for e in edges]):
        e = s[j] - s[i]
        share = 1.0 - np.dot(normal[i], e) ** 2 / np.dot(e, e)
        if share > best[i]:
            best[i], best_length2[i], tangent[i] = share, np.dot(e, e), j
    frames, _, _, _ = libdeform_frames(s, triangles, tangent)
    deltas = np.einsum("ikl,ik->il", frames, rest - s)
    scale = np.minimum(np.sqrt(length / fans), np.sqrt(best * best_length2))
    pinned = ~(np.linalg.norm(deltas, axis=1) <= 8.0 * scale)
    y = smooth(posed, edges, step, iterations)
    frames, _, _, _ = libdeform_frames(y, triangles, tangent)
    out = y + np.einsum("ikl,il->ik", frames, deltas)
    out[pinned] = posed[pinned]
    return out, pinned


def stats(a, b, diagonal):
    d = np.linalg.norm(np.asarray(a, np.float64) - np.asarray(b, np.float64), axis=1) / diagonal * 100.0
    return d.mean(), np.percentile(d, 99), d.max()


def picture(path, data, ours, theirs, iterations):
    """Per pose (rows): LBS, libdeform's Delta Mush, Blender's Corrective Smooth, and libdeform's coloured by its
    distance from Blender's, on the left arm around the elbow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    rest = np.asarray(data["points"], np.float64)
    triangles = np.asarray(data["triangles"])
    diagonal = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
    fig = plt.figure(figsize=(12, 6.4), dpi=90)
    for row, (name, lbs) in enumerate(data["poses"].items()):
        key = f"{name}/{iterations}"
        a, b = np.asarray(ours[key]), np.asarray(theirs[key])
        centre, look = np.asarray(data["views"][name]["centre"]), np.asarray(data["views"][name]["look"])
        near = np.linalg.norm(np.asarray(lbs)[triangles].mean(axis=1) - centre, axis=1) < 0.3
        distance = (np.linalg.norm(a - b, axis=1) / diagonal * 100.0)[triangles[near]].max(axis=1)
        panels = (("LBS", np.asarray(lbs), None), (f"libdeform Delta Mush, {iterations} it.", a, None),
                  (f"Blender Corrective Smooth, {iterations} it.", b, None),
                  ("distance (red: 0.1% of the diagonal or more)", a, np.clip(distance / 0.1, 0, 1)))
        for col, (title, points, heat) in enumerate(panels):
            faces = points[triangles[near]]
            normals = np.cross(faces[:, 1] - faces[:, 0], faces[:, 2] - faces[:, 0])
            normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
            light = look + np.array([0.0, 0.6, 0.0])
            shade = 0.25 + 0.75 * np.abs(normals @ (light / np.linalg.norm(light)))
            base = np.array([0.85, 0.72, 0.62]) if heat is None else None
            colours = np.outer(shade, base) if heat is None else \
                shade[:, None] * (np.outer(1 - heat, [0.8, 0.8, 0.8]) + np.outer(heat, [0.9, 0.1, 0.1]))
            ax = fig.add_subplot(2, 4, row * 4 + col + 1, projection="3d")
            axes = [0, 2, 1]  # +Y up: the model's y goes to the plot's z
            ax.add_collection3d(Poly3DCollection(faces[:, :, axes], facecolors=np.clip(colours, 0, 1),
                                                 edgecolors="none"))
            c, v = centre[axes], look[axes]
            for k, setter in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
                setter(c[k] - 0.17, c[k] + 0.17)
            ax.set_box_aspect((1, 1, 1))
            ax.view_init(elev=np.degrees(np.arcsin(v[2])), azim=np.degrees(np.arctan2(v[1], v[0])))
            ax.set_axis_off()
            ax.set_title(f"{title}\n{name}", fontsize=9)
    fig.tight_layout()
    tmp = str(path) + ".tmp.png"
    fig.savefig(tmp)
    plt.close(fig)
    os.replace(tmp, path)
    print(f"wrote {path}")


def compare(folder, picture_path=None, picture_iterations=10):
    data = json.loads((folder / "input.json").read_text())
    ours = json.loads((folder / "libdeform.json").read_text())["results"]
    theirs = json.loads((folder / "blender.json").read_text())
    rest = np.asarray(data["points"], np.float64)
    triangles = np.asarray(data["triangles"])
    diagonal = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
    step = data["step"]
    print(f"Blender {theirs['blender']}; {len(rest)} points, {len(triangles)} triangles, {theirs['edges']} edges; "
          f"bind diagonal {diagonal:.4f}; step {step}")
    print("distances per point in % of the bind bounding-box diagonal, mean / p99 / max")
    print()
    print("| pose | iterations | libdeform vs Blender | the same without libdeform's pinned points | pinned |")
    print("|---|---:|---|---|---:|")
    checks = []
    for name, lbs in data["poses"].items():
        lbs = np.asarray(lbs, np.float64)
        for n in data["iterations"]:
            key = f"{name}/{n}"
            a, b = np.asarray(ours[key], np.float64), np.asarray(theirs["results"][key], np.float64)
            libdeform_ref, pinned = libdeform_mush(rest, lbs, triangles, step, n)
            full = "{:.3f} / {:.3f} / {:.3f}".format(*stats(a, b, diagonal))
            kept = "{:.3f} / {:.3f} / {:.3f}".format(*stats(a[~pinned], b[~pinned], diagonal))
            print(f"| {name} | {n} | {full} | {kept} | {int(pinned.sum())} |")
            smooth_ref = smooth(lbs, edges_of(triangles), step, n)
            blender_ref = blender_mush(rest, lbs, triangles, step, n)
            # How much of each point's rest offset (its distance from the smoothed rest) each result keeps, over the
            # points that LBS moves: libdeform's one orthonormal frame keeps all of it; Blender's mean of the
            # corners' rotated offsets is shorter wherever the corners' frames disagree.
            moved = np.linalg.norm(lbs - rest, axis=1) > 1e-4 * diagonal
            offset = np.linalg.norm(rest - smooth(rest, edges_of(triangles), step, n), axis=1)[moved]
            kept_by = [np.mean(np.linalg.norm(r[moved] - smooth_ref[moved], axis=1) / offset) for r in (a, b)]
            checks.append((name, n, kept_by, stats(theirs["results"][key + "/smooth"], smooth_ref, diagonal)[2],
                           stats(b, blender_ref, diagonal)[2], stats(a, libdeform_ref, diagonal)[2],
                           stats(libdeform_ref, blender_ref, diagonal)[2]))
    print()
    print("What explains it (max distance, % of the diagonal): Blender's use_only_smooth against the shared smoothing "
          "rule; Blender against its algorithm re-implemented; libdeform against its "
          "algorithm re-implemented (pins included); the two re-implementations against each other; the mean share "
          "of the rest offsets each result keeps over the points LBS moves")
    print()
    print("| pose | iterations | smoothing alone | Blender vs its re-impl. | libdeform vs its re-impl. "
          "| re-impl. vs re-impl. | offset kept: libdeform, Blender |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, n, kept_by, s, bl, ld, both in checks:
        print(f"| {name} | {n} | {s:.1e} | {bl:.1e} | {ld:.1e} | {both:.3f} | "
              f"{100 * kept_by[0]:.1f}%, {100 * kept_by[1]:.1f}% |")
    if picture_path is not None:
        picture(picture_path, data, ours, theirs["results"], picture_iterations)


def record(folder, target, iterations):
    """A small fixture of Blender's results for python/tests/test_delta_mush_blender.py: per pose, at `iterations`,
    the points that Blender moves by more than 1e-5 of the bind diagonal from the rest (index and position to the
    micrometre); every other point Blender left at the rest within that."""
    data = json.loads((folder / "input.json").read_text())
    theirs = json.loads((folder / "blender.json").read_text())
    rest = np.asarray(data["points"], np.float64)
    diagonal = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
    poses = {}
    for name in data["poses"]:
        b = np.asarray(theirs["results"][f"{name}/{iterations}"], np.float64)
        moved = np.flatnonzero(np.linalg.norm(b - rest, axis=1) > 1e-5 * diagonal)
        poses[name] = {"points": moved.tolist(), "positions": np.round(b[moved], 6).tolist()}
    write_json(target, {"blender": theirs["blender"], "modifier": "CORRECTIVE_SMOOTH", "smooth_type": "SIMPLE",
                        "rest_source": "ORCO", "factor": data["step"], "iterations": iterations, "scale": 1.0,
                        "input": "libdeform's LBS of the built-in character as a shape key", "poses": poses})
    print(f"wrote {target}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("command", choices=("export", "compare", "record"))
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--iterations", default="5,10,20,50", help="comma-separated iteration counts")
    parser.add_argument("--step", type=float, default=0.5, help="libdeform's step, Blender's factor")
    parser.add_argument("--picture", type=pathlib.Path, help="compare: also draw both results (PNG) at --picture-at")
    parser.add_argument("--picture-at", type=int, default=10, help="the iteration count drawn")
    parser.add_argument("--fixture", type=pathlib.Path, help="record: the fixture file to write")
    parser.add_argument("--fixture-at", type=int, default=10, help="record: the iteration count recorded")
    args = parser.parse_args()
    if args.command == "export":
        export(args.folder, [int(n) for n in args.iterations.split(",")], args.step)
    elif args.command == "compare":
        compare(args.folder, args.picture, args.picture_at)
    else:
        record(args.folder, args.fixture, args.fixture_at)


if __name__ == "__main__":
    main()
