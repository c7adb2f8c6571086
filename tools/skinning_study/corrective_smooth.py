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
    lbs, mushed = {}, {}
    for name, pose in poses.items():
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
        "step": step, "iterations": iterations, "poses": lbs})
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


def compare(folder):
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("command", choices=("export", "compare"))
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--iterations", default="5,10,20,50", help="comma-separated iteration counts")
    parser.add_argument("--step", type=float, default=0.5, help="libdeform's step, Blender's factor")
    args = parser.parse_args()
    if args.command == "export":
        export(args.folder, [int(n) for n in args.iterations.split(",")], args.step)
    else:
        compare(args.folder)


if __name__ == "__main__":
    main()
