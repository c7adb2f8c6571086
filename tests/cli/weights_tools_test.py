#!/usr/bin/env python3
"""The rigger's weight controls end to end, on the built-in character and its files: `deform weights
--deform-bones/--exclude-bones` (globs, `used`), heat's --smoothing, and `deform weights-edit`'s tools, each checked
for what it promises with arithmetic done here (sums of 1, no weight under the prune threshold, at most N influences,
the mirror's symmetry, smoothing lowering the sum over the mesh's edges of squared weight differences), plus exit 2
with the file and line for hostile input and the output untouched. With MODELS (Debian's assimp-testmodels, in
builds with the importer), `used` on an import whose skeleton has nodes no vertex is weighted to, and weights-edit
on an import's own weights; and a glTF written here whose skin lists a joint no vertex uses.
Usage: weights_tools_test.py DEFORM SAMPLES_DATA WORK_DIR [MODELS]"""
import base64, fnmatch, json, os, shutil, struct, subprocess, sys

deform, samples, work = (os.path.abspath(a) for a in sys.argv[1:4])
models = sys.argv[4] if len(sys.argv) > 4 else None
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def run(*args):
    p = subprocess.run([deform, *args], capture_output=True, text=True, timeout=300, cwd=work)
    return p.returncode, p.stdout, p.stderr


def ok(*args):
    rc, out, err = run(*args)
    check(rc == 0, f"{' '.join(args)}: exit {rc}: {err}")
    return json.loads(out) if rc == 0 else None


def rejected(text, *args):
    """Exit 2, nothing on stdout, `text` on stderr, keep.skw untouched."""
    with open(os.path.join(work, "keep.skw"), "w") as f:
        f.write("keep")
    rc, out, err = run(*args, "--out", "keep.skw")
    check(rc == 2 and out == "" and text in err, f"{' '.join(args)}: expected exit 2 with '{text}', got {rc}: {err}")
    with open(os.path.join(work, "keep.skw")) as f:
        check(f.read() == "keep", f"{' '.join(args)}: the output was touched")


def read_skw(name):
    rows = []
    with open(os.path.join(work, name)) as f:
        lines = [l.split("#")[0].split() for l in f]
    lines = [l for l in lines if l]
    check(lines[0] == ["skw", "1"] and lines[1][0] == "vertices", f"{name}: header {lines[:2]}")
    for t in lines[2:]:
        rows.append({int(t[i]): float(t[i + 1]) for i in range(1, len(t), 2)})
    return rows


def read_obj(path):
    points, edges = [], set()
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "v":
                points.append(tuple(map(float, t[1:4])))
            elif t and t[0] == "f":
                corners = [int(c.split("/")[0]) - 1 for c in t[1:]]
                for i in range(len(corners)):
                    a, b = corners[i], corners[(i + 1) % len(corners)]
                    edges.add((min(a, b), max(a, b)))
    return points, sorted(edges)


points, edges = read_obj(os.path.join(samples, "builtin.obj"))
sk = os.path.join(samples, "builtin.sk")
bones = [b["name"] for b in ok("info", sk)["bones"]]


def check_normalised(rows, name):
    bad = [p for p, r in enumerate(rows) if abs(sum(r.values()) - 1.0) > 1e-5 or min(r.values()) <= 0.0]
    check(not bad, f"{name}: points {bad[:5]} do not sum to 1 ({len(bad)} in all)")


def energy(rows):
    """Σ over the mesh's edges (points welded by position) and bones of the squared weight differences."""
    welded = {}
    for p, xyz in enumerate(points):
        welded.setdefault(xyz, []).append(p)
    mean = {}
    for group in welded.values():
        m = {}
        for p in group:
            for b, w in rows[p].items():
                m[b] = m.get(b, 0.0) + w / len(group)
        for p in group:
            mean[p] = m
    total, seen = 0.0, set()
    for a, b in edges:
        key = (min(points[a], points[b]), max(points[a], points[b]))
        if points[a] == points[b] or key in seen:
            continue
        seen.add(key)
        wa, wb = mean[a], mean[b]
        total += sum((wa.get(k, 0.0) - wb.get(k, 0.0)) ** 2 for k in set(wa) | set(wb))
    return total


# --- deform weights: which bones deform ---
heat = ok("weights", "--builtin", "--out", "heat.skw")
check(heat and heat["deforming"] == len(bones), f"all bones deform by default: {heat}")
chosen = ok("weights", "--builtin", "--deform-bones", "hips,spine,chest,neck,head,*arm_?,hand_[lr]",
            "--deform-bones", "thigh_*,shin_*", "--exclude-bones", "forearm_r", "--out", "chosen.skw")
allowed = {i for i, n in enumerate(bones)
           if any(fnmatch.fnmatchcase(n, g) for g in ["hips", "spine", "chest", "neck", "head", "*arm_?", "hand_[lr]",
                                                      "thigh_*", "shin_*"]) and n != "forearm_r"}
check(chosen and chosen["deforming"] == len(allowed), f"--deform-bones: {chosen} against {len(allowed)} bones")
rows = read_skw("chosen.skw")
check_normalised(rows, "chosen.skw")
used = set(b for r in rows for b in r)
check(used <= allowed, f"--deform-bones: weight on non-deforming bones {[bones[b] for b in used - allowed]}")
check(bones.index("forearm_l") in used and bones.index("forearm_r") not in used, "--exclude-bones forearm_r")
# The same with the mask from the method's own option: voxel and distance take it too.
for method in ("voxel", "distance"):
    extra = ["--resolution", "40"] if method == "voxel" else []
    r = ok("weights", "--builtin", "--method", method, *extra, "--exclude-bones", "ponytail*", "--out", f"{method}.skw")
    check(r and r["deforming"] == len(bones) - 4, f"{method} --exclude-bones: {r}")
    used = set(b for row in read_skw(f"{method}.skw") for b in row)
    check(not any(bones[b].startswith("ponytail") for b in used), f"{method}: a ponytail bone kept weight")
# `used`: the bones the built-in character's shipped weights use (all 33 but the bones they leave out).
with open(os.path.join(samples, "builtin.skw")) as f:
    shipped_used = set()
    for line in f.readlines()[2:]:
        t = line.split()
        shipped_used |= {int(t[i]) for i in range(1, len(t), 2) if float(t[i + 1]) > 0}
r = ok("weights", "--builtin", "--deform-bones", "used", "--exclude-bones", "toe_?", "--out", "used.skw")
check(r and r["deforming"] == len(shipped_used - {bones.index("toe_l"), bones.index("toe_r")}),
      f"--deform-bones used: {r}, the shipped weights use {len(shipped_used)} bones")
rejected("pattern 'pelvis': matches no bone", "weights", "--builtin", "--deform-bones", "hips,pelvis")
rejected("pattern 'tail*': matches no bone", "weights", "--builtin", "--exclude-bones", "tail*")
rejected("no bone deforms", "weights", "--builtin", "--deform-bones", "hips", "--exclude-bones", "h*")
rejected("unclosed '['", "weights", "--builtin", "--deform-bones", "hand_[lr")
rejected("has no weights of its own", "weights", os.path.join(samples, "builtin.obj"), "--skeleton", sk,
         "--deform-bones", "used")
rejected("--deform-bones: an empty item", "weights", "--builtin", "--deform-bones", "hips,,spine")

# --- heat's smoothing: sums of 1, a smaller gradient ---
r = ok("weights", "--builtin", "--smoothing", "3", "--out", "heat-smooth.skw")
smooth_rows = read_skw("heat-smooth.skw")
check_normalised(smooth_rows, "heat-smooth.skw")
heat_rows = read_skw("heat.skw")
check(energy(smooth_rows) < 0.9 * energy(heat_rows), "heat --smoothing 3 did not lower the gradient energy")
rejected("--smoothing: 101 is outside [0, 100]", "weights", "--builtin", "--smoothing", "101")

# --- weights-edit: each tool's promise ---
triple = [os.path.join(samples, "builtin.obj"), "--skeleton", sk, "--weights", "heat.skw"]
base = read_skw("heat.skw")
r = ok("weights-edit", *triple, "--prune", "0.2", "--out", "pruned.skw")
pruned = read_skw("pruned.skw")
check_normalised(pruned, "pruned.skw")
check(all(w >= 0.2 * (1 - 1e-6) for row in pruned for w in row.values()), "--prune 0.2 left a weight below 0.2")
removed = sum(len(a) - len(b) for a, b in zip(base, pruned))
check(r and r["pruned"] == removed and removed > 0, f"--prune reported {r and r['pruned']}, removed {removed}")
for n in (1, 2, 3):
    r = ok("weights-edit", "--builtin", "--weights", "heat.skw", "--limit", str(n), "--out", f"limit{n}.skw")
    limited = read_skw(f"limit{n}.skw")
    check_normalised(limited, f"limit{n}.skw")
    check(all(len(row) <= n for row in limited), f"--limit {n} left more influences")
    check(all(max(a, key=a.get) in b for a, b in zip(base, limited)), f"--limit {n} lost a point's strongest bone")
r = ok("weights-edit", *triple, "--smooth", "4", "--out", "smooth.skw")
smoothed = read_skw("smooth.skw")
check_normalised(smoothed, "smooth.skw")
check(energy(smoothed) < energy(base), f"--smooth 4: energy {energy(smoothed)} not below {energy(base)}")
check(all(len(row) <= 4 for row in smoothed), "--smooth kept more than four influences")
# Normalise a hand-edited file whose lines do not sum to 1.
with open(os.path.join(work, "unnormalised.skw"), "w") as f:
    f.write("skw 1\nvertices 2850\n")
    for p, row in enumerate(base):
        f.write(f"{p} " + " ".join(f"{b} {3 * w}" for b, w in row.items()) + "\n")
ok("weights-edit", "--builtin", "--weights", "unnormalised.skw", "--normalize", "--out", "normalised.skw")
normalised = read_skw("normalised.skw")
check_normalised(normalised, "normalised.skw")
check(all(abs(a[b] - w) < 1e-6 for a, n in zip(base, normalised) for b, w in n.items()), "--normalize changed ratios")

# --- the mirror: flip twice gives the input back; a left-only painting appears on the right ---
mirror = lambda b: bones.index(b[:-2] + {"_l": "_r", "_r": "_l"}[b[-2:]]) if b[-2:] in ("_l", "_r") else bones.index(b)
r = ok("weights-edit", *triple, "--mirror", "flip", "--out", "flip.skw")
check(r and r["mirror"]["axis"] == "x" and r["mirror"]["bone_pairs"] == 12, f"--mirror flip: {r}")
ok("weights-edit", os.path.join(samples, "builtin.obj"), "--skeleton", sk, "--weights", "flip.skw", "--mirror",
   "flip", "--out", "flip2.skw")
flipped, twice = read_skw("flip.skw"), read_skw("flip2.skw")
check(all(a.keys() == b.keys() and all(abs(a[k] - b[k]) < 1e-5 for k in a) for a, b in zip(base, twice)),
      "--mirror flip twice is not the input")
# A point and its mirror image (found here by position) hold the same weights, sides swapped.
index = {}
for p, (x, y, z) in enumerate(points):
    index.setdefault((round(x, 4), round(y, 4), round(z, 4)), p)
pairs = 0
for p, (x, y, z) in enumerate(points):
    q = index.get((round(-x, 4), round(y, 4), round(z, 4)))
    if q is None:
        continue
    pairs += 1
    expected = {mirror(bones[b]): w for b, w in base[q].items()}
    if expected.keys() != flipped[p].keys() or any(abs(expected[b] - flipped[p][b]) > 1e-5 for b in expected):
        check(False, f"--mirror flip: point {p} has {flipped[p]}, its mirror {q} had {base[q]}")
        break
check(pairs > 2000, f"only {pairs} points found their mirror here")
# Paint the left (+x) only, hips on the right: positive-to-negative copies the left over.
with open(os.path.join(work, "left.skw"), "w") as f:
    f.write("skw 1\nvertices 2850\n")
    for p, row in enumerate(base):
        row = row if points[p][0] >= 0 else {bones.index("hips"): 1.0}
        f.write(f"{p} " + " ".join(f"{b} {w}" for b, w in row.items()) + "\n")
r = ok("weights-edit", "--builtin", "--weights", "left.skw", "--mirror", "positive-to-negative", "--out", "both.skw")
left, both = read_skw("left.skw"), read_skw("both.skw")
check(all(both[p].keys() == left[p].keys() and all(abs(both[p][b] - w) < 1e-6 for b, w in left[p].items())
          for p in range(len(points)) if points[p][0] >= 0), "positive-to-negative changed the positive side")
right_arm = bones.index("upperarm_r")
check(any(right_arm in both[p] for p in range(len(points)) if points[p][0] < 0), "the left arm did not reach the right")
for p, (x, y, z) in enumerate(points):
    q = index.get((round(-x, 4), round(y, 4), round(z, 4)))
    if x > -0.01 or q is None:
        continue
    expected = {mirror(bones[b]): w for b, w in left[q].items()}
    if expected.keys() != both[p].keys() or any(abs(expected[b] - both[p][b]) > 1e-5 for b in expected):
        check(False, f"positive-to-negative: point {p} has {both[p]}, its mirror {q} has {left[q]}")
        break

# --- errors: exit 2, the message names the file and line or the element, the output untouched ---
with open(os.path.join(work, "hostile.skw"), "w") as f:
    f.write("skw 1\nvertices 2850\n0 1 0.5 99999 0.5\n")
rejected("hostile.skw: line 3", "weights-edit", "--builtin", "--weights", "hostile.skw", "--normalize")
with open(os.path.join(work, "short.skw"), "w") as f:
    f.write("skw 1\nvertices 12\n")
rejected("short.skw", "weights-edit", "--builtin", "--weights", "short.skw", "--limit", "2")
rejected("no tool given", "weights-edit", "--builtin")
rejected("--mirror: 'left' is not flip", "weights-edit", "--builtin", "--mirror", "left")
rejected("--axis applies to --mirror", "weights-edit", "--builtin", "--axis", "x", "--limit", "2")
rejected("--axis: 'w' is not x, y or z", "weights-edit", "--builtin", "--mirror", "flip", "--axis", "w")
rejected("--tolerance", "weights-edit", "--builtin", "--mirror", "flip", "--tolerance", "0")
rejected("--pattern: 'x' is not two different texts", "weights-edit", "--builtin", "--mirror", "flip", "--pattern", "x")
rejected("has no mirror partner: no bone is named", "weights-edit", "--builtin", "--mirror", "flip", "--axis", "x",
         "--pattern", "_l,_x")
rejected("has no mirror point within", "weights-edit", "--builtin", "--mirror", "flip", "--axis", "y")
rejected("--prune: 2 is outside [0, 1]", "weights-edit", "--builtin", "--prune", "2")
rejected("--limit: 17 is outside [1, 16]", "weights-edit", "--builtin", "--limit", "17")
rejected("--smooth: 0 is outside [1, 100]", "weights-edit", "--builtin", "--smooth", "0")
rejected("--smooth-factor applies to --smooth", "weights-edit", "--builtin", "--smooth-factor", "0.3", "--limit", "2")
rejected("--weights W.skw is required", "weights-edit", os.path.join(samples, "builtin.obj"), "--skeleton", sk,
         "--limit", "2")

# --- an import: mrfixit.iqm's skeleton has 76 nodes, its skin weights 48 of them (IK goals and end nodes not) ---
if models:
    mrfixit = os.path.join(models, "IQM", "mrfixit.iqm")
    r = ok("weights", mrfixit, "--deform-bones", "used", "--out", "mrfixit.skw")
    check(r and r["bones"] == 76 and r["deforming"] == 48, f"mrfixit --deform-bones used: {r}")
    all_bones = ok("weights", mrfixit, "--out", "mrfixit-all.skw")
    check(all_bones and all_bones["deforming"] == 76, f"mrfixit, every bone: {all_bones}")
    # The bones `used` keeps are exactly those the file's own weights use: weights-edit --normalize without
    # --weights writes the file's weights, whose bones are the `used` set.
    ok("weights-edit", mrfixit, "--normalize", "--out", "mrfixit-own.skw")
    own = set(b for row in read_skw("mrfixit-own.skw") for b in row)
    check(len(own) == 48, f"mrfixit's own weights use {len(own)} bones")
    computed = set(b for row in read_skw("mrfixit.skw") for b in row)
    check(computed <= own, f"--deform-bones used weighted bones the file does not: {sorted(computed - own)}")
    computed_all = set(b for row in read_skw("mrfixit-all.skw") for b in row)
    check(not computed_all <= own, "without the mask no helper node got weight: the test shows nothing")
    rejected("has no mirror point within", "weights-edit", mrfixit, "--mirror", "flip")

    # --- a glTF skin with a joint no vertex uses (an IK goal): `used` leaves it out ---
    blob = b""
    views, accessors = [], []

    def accessor(values, kind, component=5126, fmt="f", extra=None):
        global blob
        while len(blob) % 4:
            blob += b"\0"
        data = struct.pack("<%d%s" % (len(values), fmt), *values)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        accessors.append(dict({"bufferView": len(views) - 1, "componentType": component,
                               "count": len(values) // width, "type": kind}, **(extra or {})))
        return len(accessors) - 1

    pos, joints, weights = [], [], []
    for r in range(5):  # a bar of 5 rows × 2 points from y 0 to 2, on joints 0 and 1 of the skin
        for side in (-0.2, 0.2):
            w = min(max(0.5 * r - 0.5, 0.0), 1.0)
            pos += [side, 0.5 * r, 0.0]
            joints += [0, 1, 0, 0]
            weights += [1 - w, w, 0, 0]
    primitive = {"attributes": {
        "POSITION": accessor(pos, "VEC3", extra={"min": [-0.2, 0, 0], "max": [0.2, 2, 0]}),
        "JOINTS_0": accessor(joints, "VEC4", 5121, "B"), "WEIGHTS_0": accessor(weights, "VEC4")},
        "indices": accessor([i for r in range(4) for i in (2 * r, 2 * r + 1, 2 * r + 3, 2 * r, 2 * r + 3, 2 * r + 2)],
                            "SCALAR", 5123, "H")}
    identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]
    inverse_binds = accessor(identity + [0, 0, 0, 1] + identity + [0, -1, 0, 1] + identity + [-0.1, -1.5, 0, 1], "MAT4")
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 3]}],
           "nodes": [{"name": "hips", "children": [1, 2]}, {"name": "spine", "translation": [0, 1, 0]},
                     {"name": "goal", "translation": [0.1, 1.5, 0]}, {"name": "body", "mesh": 0, "skin": 0}],
           "meshes": [{"name": "bar", "primitives": [primitive]}],
           "skins": [{"joints": [0, 1, 2], "inverseBindMatrices": inverse_binds}],
           "accessors": accessors, "bufferViews": views,
           "buffers": [{"byteLength": len(blob),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}]}
    with open(os.path.join(work, "bar.gltf"), "w") as f:
        json.dump(doc, f)
    names = [b["name"] for b in ok("info", "bar.gltf").get("skeleton", [])]
    check("goal" in names, f"bar.gltf: the unused joint is not a bone: {names}")
    every = ok("weights", "bar.gltf", "--out", "bar-all.skw")
    masked = ok("weights", "bar.gltf", "--deform-bones", "used", "--out", "bar-used.skw")
    check(every and masked and every["deforming"] == len(names) and masked["deforming"] == len(names) - 1,
          f"bar.gltf: every bone {every}, used {masked}")
    if "goal" in names:
        goal = names.index("goal")
        check(any(goal in row for row in read_skw("bar-all.skw")), "bar.gltf: without the mask the goal got no weight")
        check(not any(goal in row for row in read_skw("bar-used.skw")), "bar.gltf: --deform-bones used weighted the goal")

for f in failures:
    print("FAIL:", f)
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
