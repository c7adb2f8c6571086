#!/usr/bin/env python3
"""`deform simplify` (docs/cli.md): a level-of-detail mesh written as glTF.
  - the built-in character at 0.25 as .glb and at 0.5 as .gltf + .bin: the printed counts (triangles near the target,
    fewer points), the four clips, no file left but the outputs (written atomically); with the importer, `deform
    info` reads the file back with the printed triangles and points, every bone and every clip;
  - short of the ratio it says why on stderr: --max-error (the built-in character at 0.1 with 0.001), or seams (the
    built-in character with every triangle given UVs of its own, a faceted mesh, keeps all its triangles);
  - a ratio out of (0, 1] or not a number, a --max-error out of [0, 1] and an output that is not .gltf or .glb exit 2
    and write nothing.
A deform built without the simplify component (meshoptimizer) exits 77 (skipped), after checking that it says so.
Usage: simplify_test.py DEFORM WORK_DIR WITH_IMPORT(0|1)"""
import json, os, shutil, subprocess, sys

deform, work, with_import = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, expect=0):
    p = subprocess.run([deform, *args], capture_output=True, text=True, cwd=work, timeout=300)
    if p.returncode != expect:
        check(False, f"{' '.join(args)}: exit {p.returncode}, expected {expect}: {p.stderr.strip()}")
        return None
    return json.loads(p.stdout) if expect == 0 else p.stderr


# A build without the simplify component (the cross builds) refuses with exit 1 and says so: nothing else to check
# (77: skipped).
probe = subprocess.run([deform, "simplify", "--builtin", "--ratio", "0.5", "--out", "probe.glb"], capture_output=True,
                       text=True, cwd=work, timeout=300)
if probe.returncode == 1 and "needs the simplify component" in probe.stderr:
    print("skipped: this deform was built without the simplify component:", probe.stderr.strip())
    sys.exit(77)
os.remove(os.path.join(work, "probe.glb"))

for ratio, out, files in (("0.25", "lod.glb", ["lod.glb"]), ("0.5", "lod.gltf", ["lod.gltf", "lod.bin"])):
    before = set(os.listdir(work))
    r = run("simplify", "--builtin", "--ratio", ratio, "--out", out)
    if not r:
        continue
    target = float(ratio) * r["source_triangles"]
    check(target * 0.8 <= r["triangles"] <= target * 1.15 + 2, f"{out}: {r['triangles']} triangles for {target}")
    check(r["vertices"] < r["source_vertices"] and r["render_vertices"] >= r["vertices"], f"{out}: {r}")
    check(r["clips"] == 4 and r["error"] >= 0, f"{out}: {r}")
    added = sorted(set(os.listdir(work)) - before)
    check(added == sorted(files), f"{out}: wrote {added}, expected {files}")
    if with_import:
        info = run("info", out)
        if info:
            check(info["triangles"] == r["triangles"], f"{out} read back: {info['triangles']} triangles")
            check(info["vertices"] == r["vertices"], f"{out} read back: {info['vertices']} points")
            check(info["bones"] == 33, f"{out} read back: {info['bones']} bones, the built-in character has 33")
            check(len(info["clips"]) == 4, f"{out} read back: clips {info['clips']}")

# Short of the ratio, it says why: the surface error (--max-error), or seams that stay: the built-in character with
# every triangle given UVs of its own (a faceted mesh) keeps all of its triangles.
p = subprocess.run([deform, "simplify", "--builtin", "--ratio", "0.1", "--max-error", "0.001", "--out", "tight.glb"],
                   capture_output=True, text=True, cwd=work, timeout=300)
check(p.returncode == 0 and "stopped at --max-error" in p.stderr, f"--max-error 0.001: {p.returncode} {p.stderr!r}")
if run("export", "--builtin", "--out", "native") is not None:
    faceted, corners = [], 0
    with open(os.path.join(work, "native", "builtin.obj")) as f:
        for line in f:
            if line.startswith("vt "):
                continue
            if not line.startswith("f "):
                faceted.append(line)
                continue
            refs = []
            for corner in line.split()[1:]:
                corners += 1
                refs.append(f"{corner.partition('/')[0]}/{corners}")
                faceted.append(f"vt {0.001 * (corners % 997)} {0.002 * (corners % 499)}\n")
            faceted.append("f " + " ".join(refs) + "\n")
    with open(os.path.join(work, "native", "faceted.obj"), "w") as f:
        f.writelines(faceted)
    native = os.path.join("native", "builtin")
    p = subprocess.run([deform, "simplify", os.path.join("native", "faceted.obj"), "--skeleton", native + ".sk",
                        "--weights", native + ".skw", "--ratio", "0.25", "--out", "faceted.glb"],
                       capture_output=True, text=True, cwd=work, timeout=300)
    check(p.returncode == 0, f"faceted: exit {p.returncode}: {p.stderr}")
    if p.returncode == 0:
        r = json.loads(p.stdout)
        check(r["triangles"] == r["source_triangles"] and "seams" in p.stderr, f"faceted: {r} {p.stderr!r}")

before = set(os.listdir(work))
for args in (["--ratio", "0"], ["--ratio", "1.5"], ["--ratio", "half"], ["--ratio", "0.5", "--max-error", "-1"]):
    err = run("simplify", "--builtin", *args, "--out", "bad.glb", expect=2)
    check(err is None or "--ratio" in err or "--max-error" in err, f"{args}: {err}")
err = run("simplify", "--builtin", "--ratio", "0.5", "--out", "bad.obj", expect=2)
check(err is None or ".gltf or .glb" in err, f"bad.obj: {err}")
check(set(os.listdir(work)) == before, f"refused commands wrote {sorted(set(os.listdir(work)) - before)}")

if failures:
    print(f"{len(failures)} failure(s)")
    sys.exit(1)
print("simplify: OK")
