#!/usr/bin/env python3
"""`deform bake --as bones` (docs/gltf-export.md, "Baking bones"): the skinning decomposition held to its targets and
played by a peer.
  - the built-in character's reach-stretch-release and its walk with the jiggle (--inertia 1), with its own rig (the
    left arm's lattices) and with a lattice on every limb bone (the walk and the run): RMS <= 0.5 % and largest
    <= 2 % of the bounding-box diagonal with at most 24 extra bones, as the tool reports them; with 8 influences too
    (JOINTS_1), two clips in one file, and on imported characters (Testwuson's walk, mrfixit's idle, both jiggling);
  - every bones file passes the Khronos validator with 0 errors and 0 warnings, and is smaller than the morph bake of
    the same motion;
  - three.js (tests/node/three_skin.mjs: GLTFLoader, AnimationMixer, SkinnedMesh) plays the bones file and the morph
    bake of the same motion (libdeform's own frames, to 1e-6 of the diagonal) at every frame time: every triangle
    corner agrees within the reported largest error (plus 2e-5 of the diagonal for float rounding). A fit that got
    worse than it says, a bone track or weight written wrong, or a clip that three.js reads differently fails here;
  - no extra bones (--max-bones 0) still writes a valid file whose error is what the deformers did;
  - bad usage exits 2 and writes nothing.
Usage: bake_bones_test.py DEFORM NODE_DIR MODELS_DIR WORK_DIR
Exits 77 (skipped) when node, three.js or the validator is missing (scripts/test installs them)."""
import json, math, os, shutil, subprocess, sys

deform, node_dir, models, work = sys.argv[1:5]
if shutil.which("node") is None or not all(
        os.path.isdir(os.path.join(node_dir, "node_modules", m)) for m in ("three", "gltf-validator")):
    print("skipped: node, three.js or gltf-validator missing (npm ci --prefix tests/node)")
    sys.exit(77)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def bake(*args, expect=0):
    p = subprocess.run([deform, "bake", *args], capture_output=True, text=True, cwd=work, timeout=600)
    if p.returncode != expect:
        check(False, f"bake {' '.join(args)}: exit {p.returncode}, expected {expect}: {p.stderr.strip()}")
        return None
    return json.loads(p.stdout) if expect == 0 else p.stderr


def validate(path):
    p = subprocess.run(["node", os.path.join(node_dir, "validate_gltf.js"), path], capture_output=True, text=True,
                       timeout=300)
    report = json.loads(p.stdout.splitlines()[0]) if p.returncode == 0 and p.stdout else None
    check(report is not None and report["errors"] == 0 and report["warnings"] == 0,
          f"validator on {os.path.basename(path)}: {report['messages'][:3] if report else p.stderr.strip()}")


def three(path, times=None, animation=0, names=False):
    """The corners three.js puts the file's meshes at: at rest (no times), or at each time of clip `animation`
    (with the file's animation names when `names`)."""
    args = ["node", os.path.join(node_dir, "three_skin.mjs"), path]
    if times:
        args += [str(animation), ",".join(map(repr, times))]
    p = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        check(False, f"three.js on {os.path.basename(path)}: {p.stderr.strip()[-300:]}")
        return None
    result = json.loads(p.stdout)
    return (result["frames"], result["animations"]) if names else result["frames" if times else "corners"]


def diagonal(points):
    lo = [min(p[i] for p in points) for i in range(3)]
    hi = [max(p[i] for p in points) for i in range(3)]
    return math.dist(lo, hi)


def bake_both(label, model_args, motion, extra=()):
    """Bakes one motion as bones and as morphs; checks the bones file against the validator, the morph file's size
    and three.js. Returns the bones bake's report."""
    bones = bake(*model_args, *motion, "--as", "bones", *extra, "--out", f"{label}-bones.glb")
    morphs = bake(*model_args, *motion, "--out", f"{label}-morphs.glb")
    return compare(label, bones, morphs)


def compare(label, bones, morphs, animation=0):
    """Checks a bones bake against the morph bake of the same motion (its animation `animation`)."""
    if bones is None or morphs is None:
        return None
    validate(os.path.join(work, f"{label}-bones.glb"))
    check(bones["bytes"] < morphs["bytes"],
          f"{label}: the bones file ({bones['bytes']} bytes) is not smaller than the morphs' ({morphs['bytes']})")
    check(animation > 0 or bones["frames"] == morphs["frames"],
          f"{label}: {bones['frames']} frames against {morphs['frames']}")
    times = [k / morphs["fps"] for k in range(morphs["frames"])]
    played = three(os.path.join(work, f"{label}-bones.glb"), times, animation)
    reference = three(os.path.join(work, f"{label}-morphs.glb"), times)
    rest = three(os.path.join(work, f"{label}-morphs.glb"))
    if played and reference and rest:
        size = diagonal(rest)  # the tool's errors are fractions of the bind mesh's diagonal
        allowed = (bones["max_error"] + 2e-5) * size
        worst = max(max(math.dist(a, b) for a, b in zip(f, g)) for f, g in zip(played, reference))
        check(len(played[0]) == len(reference[0]), f"{label}: three.js sees different meshes in the two files")
        check(worst <= allowed, f"{label}: three.js puts a corner {worst / size:.3%} of the diagonal from the frames, "
                                f"more than the reported largest error {bones['max_error']:.3%}")
        moved = max(max(math.dist(a, b) for a, b in zip(f, reference[0])) for f in reference)
        check(moved > 10 * allowed, f"{label}: the motion ({moved / size:.3%}) is too small for the check to mean much")
    print(f"{label}: {bones['extra_bones']} extra bones, {bones['moved_points']} moved points, RMS "
          f"{bones['rms_error']:.4%}, largest {bones['max_error']:.4%}, {bones['bytes']} bytes (morphs "
          f"{morphs['bytes']}), {bones['seconds']:.2f} s (morphs {morphs['seconds']:.2f} s)")
    return bones


def hold_to_targets(label, report, bones=24):
    if report is None:
        return
    check(report["extra_bones"] <= bones, f"{label}: {report['extra_bones']} extra bones, more than {bones}")
    check(report["extra_bones"] > 0 and report["moved_points"] > 0, f"{label}: nothing was fitted: {report}")
    check(report["rms_error"] <= 0.005, f"{label}: RMS error {report['rms_error']:.3%} > 0.5 %")
    check(report["max_error"] <= 0.02, f"{label}: largest error {report['max_error']:.3%} > 2 %")


# --- the built-in character: the reach-stretch-release, and the walk with the jiggle ---
reach = ["--target", "1.3,1.6,0.4", "--release-at", "1", "--seconds", "3", "--fps", "10"]
hold_to_targets("reach", bake_both("reach", ["--builtin"], reach))
hold_to_targets("walk", bake_both("walk", ["--builtin"], ["--clip", "walk", "--inertia", "1"]))
eight = bake(*["--builtin"], *reach, "--as", "bones", "--influences", "8", "--out", "reach-8.glb")
hold_to_targets("reach --influences 8", eight)
if eight:
    validate(os.path.join(work, "reach-8.glb"))
# The targets at the default 30 frames a second, the frame rate the numbers are for.
hold_to_targets("reach at 30 fps", bake("--builtin", *reach[:-2], "--as", "bones", "--out", "reach-30.glb"))

# --- the whole body's flesh: a lattice on each of the twelve limb bones, each part's tuned jiggle ---
parts = {"upperarm": "upper_limb", "forearm": "lower_limb", "hand": "hand", "thigh": "upper_limb",
         "shin": "lower_limb", "foot": "foot"}
full = {"rig": 1, "model": "builtin", "reach": {"effector": "hand_l", "root": "clavicle_l"},
        "lattices": [{"name": f"{b}_{s}", "bone": f"{b}_{s}", "motion": {"part": p}}
                     for s in ("l", "r") for b, p in parts.items()]}
with open(os.path.join(work, "full.rig.json"), "w") as f:
    json.dump(full, f)
hold_to_targets("whole-body walk", bake_both("bodywalk", ["--builtin", "--rig", "full.rig.json"],
                                             ["--clip", "walk", "--inertia", "1"]))
hold_to_targets("whole-body run", bake("--builtin", "--rig", "full.rig.json", "--clip", "run", "--inertia", "1",
                                       "--as", "bones", "--out", "bodyrun.glb"))

# --- two clips in one file: one skin, one set of extra bones, an animation each; the second played by three.js ---
walk_run = bake("--builtin", "--clip", "walk", "--clip", "run", "--inertia", "1", "--as", "bones", "--out",
                "walkrun-bones.glb")
hold_to_targets("walk + run", walk_run)
run_morphs = bake("--builtin", "--clip", "run", "--inertia", "1", "--out", "walkrun-morphs.glb")
if walk_run and run_morphs:
    validate(os.path.join(work, "walkrun-bones.glb"))
    _, animations = three(os.path.join(work, "walkrun-bones.glb"), [0.0, 0.1], 0, names=True) or (None, None)
    check(animations == ["walk", "run"], f"walk + run: the file's animations are {animations}")
    check(walk_run["frames"] == 31 + run_morphs["frames"], f"walk + run: {walk_run['frames']} frames")
    compare("walkrun", walk_run, run_morphs, animation=1)
bake("--builtin", "--clip", "walk", "--clip", "run", "--out", "bad.glb", expect=2)  # morphs: one motion a file
bake("--builtin", "--clip", "walk", "--clip", "walk", "--as", "bones", "--out", "bad.glb", expect=2)

# --- imported characters, their default rigs jiggling ---
wuson = os.path.join(models, "X", "Testwuson.X")
mrfixit = os.path.join(models, "IQM", "mrfixit.iqm")
if os.path.isfile(wuson):
    hold_to_targets("Testwuson walk", bake_both("wuson", [wuson], ["--clip", "Wuson_Walk", "--inertia", "1"]))
if os.path.isfile(mrfixit):
    report = bake(mrfixit, "--clip", "idle", "--inertia", "1", "--as", "bones", "--out", "mrfixit.glb")
    hold_to_targets("mrfixit idle", report)
    if report:
        validate(os.path.join(work, "mrfixit.glb"))

# --- no extra bones: the body's motion alone, its error what the deformers did ---
none = bake("--builtin", *reach, "--as", "bones", "--max-bones", "0", "--out", "none.glb")
if none:
    check(none["extra_bones"] == 0 and none["max_error"] > 0.005,
          f"--max-bones 0: {none['extra_bones']} extra bones, largest error {none['max_error']:.3%}")
    validate(os.path.join(work, "none.glb"))

# --- bad usage writes nothing ---
for args in (["--as", "cubes"], ["--as", "bones", "--influences", "5"], ["--as", "bones", "--max-bones", "1001"],
             ["--as", "bones", "--max-bones", "2.5"], ["--max-bones", "3"], ["--as", "morphs", "--influences", "4"]):
    bake("--builtin", "--target", "1.3,1.6,0.4", *args, "--out", "bad.glb", expect=2)
ffd_mesh = os.path.join(work, "box.obj")
with open(ffd_mesh, "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
bake(ffd_mesh, "--lattice", "none.json", "--as", "bones", "--out", "bad.glb", expect=2)
check(not os.path.exists(os.path.join(work, "bad.glb")), "bad usage wrote bad.glb")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
