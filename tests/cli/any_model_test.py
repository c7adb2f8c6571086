#!/usr/bin/env python3
"""Every model-taking command on imported models (issue 30): `ik`, `simulate`, `bake`, `weights` and `ffd` take any
model the importers read, with its default rig or --rig FILE, and a rig file whose "model" is {"file": ...} brings
its model along; a file given in the wrong place is named for what it is.

Models: a glTF binary written here (`deform export --builtin --format gltf`), and Debian's assimp-testmodels IQM
(mrfixit.iqm) and DirectX (Testwuson.X) when installed. The effector and its chain are not assumed: they are the
rig's own (the chain `ik` reports without --effector), so this test holds whatever the default rig chooses.

usage: any_model_test.py DEFORM_EXE ASSIMP_MODELS WORK_DIR"""
import json, math, os, shutil, subprocess, sys

exe, models, work = (os.path.abspath(a) for a in sys.argv[1:4])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)
    return condition


def deform(*args, expect=0):
    p = subprocess.run([exe, *args], capture_output=True, text=True, timeout=600, cwd=work)
    if not check(p.returncode == expect, f"deform {' '.join(args)}: exit {p.returncode} (not {expect}): {p.stderr}"):
        return None
    return json.loads(p.stdout) if expect == 0 else p.stderr


def rejected(text, *args):
    """Exit 2, with `text` in the message."""
    err = deform(*args, expect=2)
    if err is not None:
        check(text in err, f"deform {' '.join(args)}: the message does not say '{text}': {err}")


out = deform("export", "--builtin", "--format", "gltf", "--out", "hero.glb")
candidates = [("hero.glb", os.path.join(work, "hero.glb"))]
for name, rel in (("mrfixit", "IQM/mrfixit.iqm"), ("wuson", "X/Testwuson.X")):
    path = os.path.join(models, rel)
    if os.path.exists(path):
        candidates.append((name, path))
    else:
        print(f"skipped {name}: {path} is missing (Debian's assimp-testmodels)")

for name, path in candidates:
    info = deform("info", path)
    if info is None:
        continue
    # --- ik: the rig's chain without --effector; the same chain named explicitly gives the same answer ---
    default = deform("ik", path, "--target", "0,0,0")
    if not default:
        continue
    chain = list(default["bones"])
    check(len(chain) >= 2, f"{name}: ik's default chain has {len(chain)} bones")
    named = deform("ik", path, "--root", chain[0], "--effector", chain[-1], "--target", "0,0,0")
    if named:
        check(named["bones"] == default["bones"], f"{name}: ik --root {chain[0]} --effector {chain[-1]} differs from"
              " the rig's chain")
    size = max(abs(c) for c in default["effector"]) or 1.0  # the model's scale, roughly
    # --- simulate and bake with the default rig: reach for a point near the effector, and the clips ---
    effector = default["effector"]
    target = ",".join(str(c + 0.05 * size) for c in effector)
    sim = deform("simulate", path, "--target", target, "--seconds", "0.25", "--dt", "0.05")
    if sim:
        check(len(sim["samples"]) == 6, f"{name}: simulate printed {len(sim['samples'])} samples, not 6")
        check(all(math.isfinite(c) for s in sim["samples"] for c in s["effector"]), f"{name}: simulate diverged")
    clips = [c["name"] for c in info.get("clips", [])]
    if clips:
        sim = deform("simulate", path, "--clip", clips[0], "--seconds", "0.2", "--dt", "0.05")
        if sim:
            moved = math.dist(sim["samples"][0]["effector"], sim["samples"][-1]["effector"])
            print(f"{name}: clip '{clips[0]}' moves the effector {moved:g}")
    bake = deform("bake", path, "--target", target, "--seconds", "0.2", "--fps", "10", "--out", f"{name}-reach.glb")
    if bake:
        check(bake["frames"] == 3, f"{name}: bake wrote {bake['frames']} frames, not 3")
    # --- a saved rig that names its model by file, relative to the rig's folder ---
    # The model lies outside the rig's folder: read only where the run allows its folder (docs/security.md).
    allow = ["--allow-outside", os.path.dirname(os.path.abspath(path))]
    os.makedirs(os.path.join(work, "rigs"), exist_ok=True)
    rig = {"rig": 1, "model": {"file": os.path.relpath(path, os.path.join(work, "rigs"))},
           "reach": {"effector": chain[-1], "root": chain[0]}, "lattices": []}
    with open(os.path.join(work, "rigs", f"{name}.rig.json"), "w") as f:
        json.dump(rig, f)
    rejected("key 'model.file': refused, outside", "ik", f"rigs/{name}.rig.json", "--target", "0,0,0")
    from_rig = deform("ik", f"rigs/{name}.rig.json", "--target", "0,0,0", *allow)
    if from_rig:
        check(from_rig["bones"] == default["bones"], f"{name}: ik on the rig file differs from the default chain")
    shutil.copy(os.path.join(work, "rigs", f"{name}.rig.json"), os.path.join(work, "rigs", f"{name}.rig"))
    from_rig = deform("ik", f"rigs/{name}.rig", "--target", "0,0,0", *allow)  # a rig by its content, not its name
    if from_rig:
        check(from_rig["bones"] == default["bones"], f"{name}: ik on {name}.rig differs from the default chain")
    saved = f"rigs/{name}.rig.json"
    for args in ([saved], ["--rig", saved], [path, "--rig", saved]):
        sim = deform("simulate", *args, "--target", target, "--seconds", "0.1", "--dt", "0.05", *allow)
        if sim:
            check(len(sim["samples"]) == 3, f"{name}: simulate {' '.join(args)}: {len(sim['samples'])} samples")
    # `simulate --save-rig` writes the rig as run, naming its model: the file alone runs the same simulation.
    first = deform("simulate", path, "--target", target, "--inertia", "0.5", "--seconds", "0.2", "--dt", "0.05",
                   "--save-rig", f"rigs/{name}-saved.rig.json")
    again = deform("simulate", f"rigs/{name}-saved.rig.json", "--target", target, "--seconds", "0.2", "--dt", "0.05",
                   *allow)
    check(first is not None and first == again, f"{name}: simulate of the saved rig differs from the run that saved it")
    with open(os.path.join(work, "rigs", f"{name}-saved.rig.json")) as f:
        saved = json.load(f)
    check(os.path.realpath(os.path.join(work, "rigs", saved["model"]["file"])) == os.path.realpath(path),
          f"{name}: the saved rig names {saved['model']} for {path}")
    # --inertia scales each lattice's tuned inertia, its part's (docs/elasticity.md, "Tuned per part"), which the
    # default rig stores with every lattice.
    tuned = {"upper_limb": 0.3, "lower_limb": 0.3, "hand": 0.2, "foot": 0.1, "torso": 0.4, "head": 0.1,
             "appendage": 0.8}
    check(all(l.get("motion", {}).get("part") in tuned for l in saved["lattices"]),
          f"{name}: a lattice of the default rig has no part: {[l.get('motion') for l in saved['lattices']]}")
    check(all(abs(l["motion"]["inertia"] - 0.5 * tuned[l["motion"]["part"]]) < 1e-6 for l in saved["lattices"]
              if l.get("motion", {}).get("part") in tuned),
          f"{name}: the saved rig lost --inertia 0.5, half of each part's tuned inertia")
    # Without a "model" the rig needs the model on the command line.
    del rig["model"]
    with open(os.path.join(work, "rigs", f"{name}-bare.rig.json"), "w") as f:
        json.dump(rig, f)
    deform("simulate", path, "--rig", f"rigs/{name}-bare.rig.json", "--target", target, "--seconds", "0.1")
    rejected("names no model", "simulate", f"rigs/{name}-bare.rig.json", "--target", target)
    # --- weights and ffd on the import's own mesh and skeleton ---
    weights = deform("weights", path, "--method", "distance", "--out", f"{name}.skw")
    if weights:
        check(weights["vertices"] == info["vertices"], f"{name}: weights for {weights['vertices']} points, "
              f"the model has {info['vertices']}")
    box = {"origin": [c - 0.1 * size for c in effector], "size": [0.2 * size] * 3,
           "displacements": [{"index": [1, 1, 1], "offset": [0.0, 0.05 * size, 0.0]}]}
    with open(os.path.join(work, f"{name}.lattice.json"), "w") as f:
        json.dump(box, f)
    ffd = deform("ffd", path, "--lattice", f"{name}.lattice.json", "--out", f"{name}-ffd.obj")
    if ffd:
        check(ffd["vertices"] == info["vertices"], f"{name}: ffd read {ffd['vertices']} points")

# --- a file given where another kind is expected is named for what it is ---
rejected("hero.glb: expected a rig JSON file (--rig), got a glTF binary",
         "simulate", "--builtin", "--rig", "hero.glb", "--target", "1,1,1")
rejected("hero.glb: expected a rig JSON file (--rig), got a glTF binary",
         "bake", "--rig", "hero.glb", "--target", "1,1,1", "--out", "x.glb")
rejected("rigs: expected a rig JSON file (--rig), got a folder", "simulate", "--builtin", "--rig", "rigs",
         "--target", "1,1,1")
with open(os.path.join(work, "list.json"), "w") as f:
    f.write("[1, 2]")
rejected("list.json: must be an object", "simulate", "list.json", "--target", "1,1,1")
shutil.copy(os.path.join(work, "hero.glb"), os.path.join(work, "hero.sk"))
rejected("hero.sk: expected a skeleton (.sk), got a glTF binary",
         "ik", "hero.sk", "--effector", "a", "--target", "0,0,0")
rejected("--builtin takes no skeleton file", "ik", "--builtin", "hero.sk", "--effector", "a", "--target", "0,0,0")
rejected("'rigs/x.rig.json' is a rig and --rig names another", "ik", "rigs/x.rig.json", "--rig", "rigs/y.rig.json",
         "--target", "0,0,0")
check(not os.path.exists(os.path.join(work, "x.glb")), "a refused bake wrote its output")

print(f"{len(candidates)} models; {len(failures)} failures")
sys.exit(1 if failures else 0)
