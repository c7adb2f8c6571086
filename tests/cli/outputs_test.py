#!/usr/bin/env python3
"""Outputs and the environment through the whole `deform` CLI (docs/cli.md, docs/reliability.md):
- a multi-file output lands as a set: a failure leaves the previous files byte for byte (.gltf + .bin from export and
  bake, a native export into an existing folder) and no temporary file;
- exit 1 for what the system refuses (a full disk, a FIFO no process reads), 2 for usage and input (a target or a
  voxel box that would overflow);
- a dangling output link is followed; the import worker dies with a killed CLI and stops itself at its CPU limit.
Usage: outputs_test.py DEFORM WORK_DIR [WORKER]  (WORKER: deform-import-worker, when the importer is built)"""
import json, os, shutil, signal, subprocess, sys, time

deform, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
worker = os.path.abspath(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[3] else None
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def run(*args, env=None, timeout=120):
    return subprocess.run([deform, *args], cwd=work, capture_output=True, text=True, timeout=timeout,
                          env=env, stdin=subprocess.DEVNULL)


def path(*names):
    return os.path.join(work, *names)


def read(name):
    with open(path(name), "rb") as f:
        return f.read()


def write(name, data):
    with open(path(name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def strays(folder=work):
    return [n for n in os.listdir(folder) if ".deform-tmp-" in n or ".deform-bak-" in n]


# --- .gltf + .bin: the .gltf cannot be written (a folder by that name): the previous .bin stays as it was ---
for command in (["export", "--builtin", "--format", "gltf"], ["bake", "--builtin", "--target", "0.3,1.2,0.4"]):
    label = command[0]
    write(f"{label}.bin", b"the previous buffer")
    os.makedirs(path(f"{label}.gltf"))
    r = run(*command, "--out", f"{label}.gltf")
    check(r.returncode == 2, f"{label} into a folder named .gltf: exit {r.returncode}: {r.stderr}")
    check(f"{label}.gltf" in r.stderr, f"{label}: the message does not name the .gltf: {r.stderr}")
    check(read(f"{label}.bin") == b"the previous buffer", f"{label}: the previous .bin was changed")
    check(strays() == [], f"{label}: temporary files left: {strays()}")
    # Once the name is free the pair lands, replacing the previous .bin.
    os.rmdir(path(f"{label}.gltf"))
    r = run(*command, "--out", f"{label}.gltf")
    check(r.returncode == 0, f"{label}: exit {r.returncode}: {r.stderr}")
    check(read(f"{label}.bin") != b"the previous buffer" and os.path.isfile(path(f"{label}.gltf")),
          f"{label}: the pair did not land")
    check(strays() == [], f"{label}: temporary files left after success: {strays()}")

# --- a native export into an existing folder whose OBJ cannot be written: no file of the set changes ---
r = run("export", "--builtin", "--out", "native")
check(r.returncode == 0, f"export native: exit {r.returncode}: {r.stderr}")
names = sorted(os.listdir(path("native")))
obj = [n for n in names if n.endswith(".obj")]
check(len(obj) == 1, f"export native wrote {names}")
if len(obj) == 1:
    before = {}
    for n in names:
        if not n.endswith(".obj"):
            write(os.path.join("native", n), "previous " + n)
            before[n] = read(os.path.join("native", n))
    os.remove(path("native", obj[0]))
    os.makedirs(path("native", obj[0]))  # the OBJ's name is a folder: its rename must fail
    r = run("export", "--builtin", "--out", "native")
    check(r.returncode == 2, f"export native over a folder named {obj[0]}: exit {r.returncode}: {r.stderr}")
    after = {n: read(os.path.join("native", n)) for n in before}
    check(after == before, "export native: a failed export changed files of the previous set")
    check(strays(path("native")) == [] and strays() == [], "export native: temporary files left")
    check(sorted(os.listdir(path("native"))) == names,
          f"export native: the folder now holds {os.listdir(path('native'))}")

# --- exit codes: 1 for the environment, 2 for usage and input ---
if os.path.exists("/dev/full"):
    r = run("weights", "--builtin", "--out", "/dev/full")
    check(r.returncode == 1, f"weights --out /dev/full (a full disk): exit {r.returncode}: {r.stderr}")
    check("/dev/full" in r.stderr, f"weights --out /dev/full: the message does not name it: {r.stderr}")
os.mkfifo(path("nobody_reads.skw"))
start = time.monotonic()
r = run("weights", "--builtin", "--out", "nobody_reads.skw", timeout=60)
check(r.returncode == 1 and "no process reads" in r.stderr, f"--out a FIFO without a reader: exit {r.returncode}: "
      f"{r.stderr}")
check(time.monotonic() - start < 30, "--out a FIFO without a reader: the run waited for one")

r = run("ik", "--builtin", "--effector", "hand_l", "--target", "3e38,3e38,3e38")
check(r.returncode == 2 and "--target" in r.stderr and r.stdout == "",
      f"ik --target 3e38,3e38,3e38: exit {r.returncode}, stdout {r.stdout!r}, stderr {r.stderr}")
check("null" not in r.stdout, "ik printed null")

r = run("export", "--builtin", "--out", "rig")  # a skeleton to weight degenerate meshes with
sk = [n for n in os.listdir(path("rig")) if n.endswith(".sk")] if r.returncode == 0 else []
check(len(sk) == 1, f"export for a skeleton: exit {r.returncode}: {r.stderr}")
if sk:
    for label, coordinate, why in (("coincident", "1 1 1", "no size"), ("huge", None, "too large")):
        points = ["v 1 1 1"] * 3 if coordinate else ["v 3e38 3e38 3e38", "v -3e38 -3e38 -3e38", "v 3e38 -3e38 0"]
        write(f"{label}.obj", "\n".join(points) + "\nf 1 2 3\n")
        r = run("weights", f"{label}.obj", "--skeleton", os.path.join("rig", sk[0]), "--method", "voxel",
                "--out", f"{label}.skw")
        check(r.returncode == 2 and why in r.stderr, f"voxel weights on {label} points: exit {r.returncode}: "
              f"{r.stderr}")
        check(not os.path.exists(path(f"{label}.skw")), f"voxel weights on {label} points wrote weights")

# --- a dangling link as --out: followed, the file it names created, the link kept ---
os.makedirs(path("real"))
os.symlink("real/made.skw", path("link.skw"))
r = run("weights", "--builtin", "--out", "link.skw")
check(r.returncode == 0, f"weights --out a dangling link: exit {r.returncode}: {r.stderr}")
check(os.path.islink(path("link.skw")) and os.path.isfile(path("real", "made.skw")),
      "weights --out a dangling link: the link was replaced, or its target not created")


# --- the import worker: gone within seconds of its parent's kill -9, and stops itself at its CPU limit ---
def children_of(pid):
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(entry))
    return found


def alive(pid):  # a zombie waiting for init to reap it has ended
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


if worker:
    # A glTF mesh named "a\\ " (backslash, blank) with two one-triangle primitives of two materials: the exported OBJ
    # reads back with both triangles and both materials (the name used to continue its line onto the next statement).
    triangle = ('{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], '
                '"max": [1, 1, 0]}')
    write("named.gltf", '{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0,'
          ' "name": "n\\\\ "}], "meshes": [{"name": "a\\\\ ", "primitives": [{"attributes": {"POSITION": 0}, '
          '"material": 0}, {"attributes": {"POSITION": 0}, "material": 1}]}], "materials": [{"name": "red\\\\ "}, '
          '{"name": "blue\\\\"}], "accessors": [' + triangle + '], "bufferViews": [{"buffer": 0, "byteLength": 36}],'
          ' "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,'
          'AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}')
    r = run("export", "named.gltf", "--out", "named")
    check(r.returncode == 0, f"export of a mesh named 'a\\ ': exit {r.returncode}: {r.stderr}")
    objs = [n for n in os.listdir(path("named")) if n.endswith(".obj")] if r.returncode == 0 else []
    if objs:
        r = run("info", os.path.join("named", objs[0]))
        info = json.loads(r.stdout) if r.returncode == 0 else {}
        check(info.get("triangles") == 2, f"the OBJ of a mesh named 'a\\ ' reads back with {info.get('triangles')} "
              "triangles, not 2")
        used = {s.get("material") for s in info.get("submeshes", [])}
        check(len(used) == 2, f"the OBJ of a mesh named 'a\\ ' reads back with materials {used}")

    spinning = dict(os.environ, DEFORM_IMPORT_WORKER_TEST_SPIN="1", DEFORM_IMPORT_WORKER=worker)
    write("slow.gltf", '{"asset": {"version": "2.0"}}')
    parent = subprocess.Popen([deform, "info", "slow.gltf"], cwd=work, env=spinning, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    spawned = []
    deadline = time.monotonic() + 30
    while not spawned and time.monotonic() < deadline:
        spawned = children_of(parent.pid)
        time.sleep(0.05)
    check(len(spawned) == 1, f"the import worker was not seen under deform (children: {spawned})")
    time.sleep(0.5)  # the worker is past its start (prctl) and spinning
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    if spawned:
        deadline = time.monotonic() + 5
        while alive(spawned[0]) and time.monotonic() < deadline:
            time.sleep(0.05)
        if alive(spawned[0]):
            failures.append("the import worker outlived its parent's kill -9 by 5 s")
            os.kill(spawned[0], signal.SIGKILL)

    # Run by itself (no parent to stop it), the worker ends at its CPU limit: 1 s, SIGXCPU (SIGKILL a second later).
    start = time.monotonic()
    try:
        r = subprocess.run([worker, "--max-cpu-seconds", "1", "--", path("slow.gltf")], env=spinning,
                           capture_output=True, timeout=20)
        check(r.returncode in (-signal.SIGXCPU, -signal.SIGKILL),
              f"a spinning worker at its CPU limit: exit {r.returncode}")
        check(time.monotonic() - start < 10, "a spinning worker ran far past its 1 s CPU limit")
    except subprocess.TimeoutExpired:
        failures.append("a spinning worker with a 1 s CPU limit still ran after 20 s")

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("outputs: every set landed whole or not at all; exit codes, links and the worker as documented")
