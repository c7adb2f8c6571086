# Blender's bone heat ("With Automatic Weights") on the bind meshes weights_study exports, for the side-by-side study
# in docs/weights.md. Run by blender_study.sh as
#
#   blender --background --factory-startup --python blender_heat.py -- DIR
#
# For each DIR/NAME.bind.json (weights_study --blender-export DIR): builds the mesh (vertex order kept), makes its
# normals consistent and outward as a rigger does before binding (Mesh > Normals > Recalculate Outside; the faces it
# turns are counted and reported), builds an armature of the bones as given (head, tail, parent; "deform": false bones get use_deform off, so that Blender
# weights only the deforming bones), parents the mesh with ARMATURE_AUTO, and writes each vertex's group weights
# to DIR/NAME.blender.json (atomically), with Blender's version and the seconds the parenting took.
import json
import os
import sys
import time

import bpy


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for armature in list(bpy.data.armatures):
        bpy.data.armatures.remove(armature)


def recalculate_outside(body):
    """Mesh > Normals > Recalculate Outside on every face of `body`; returns how many faces it turned round.

    Blender's bone heat takes a vertex's normal as it is: on a mesh wound inwards its visibility test fails for every
    bone. Riggers make normals consistent before binding; a mesh already wound outwards is left as it was.
    """
    mesh = body.data
    before = [p.normal.copy() for p in mesh.polygons]
    bpy.ops.object.select_all(action="DESELECT")
    body.select_set(True)
    bpy.context.view_layer.objects.active = body
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.normals_make_consistent(inside=False)
    bpy.ops.object.mode_set(mode="OBJECT")
    mesh.update()
    return sum(1 for p, n in zip(mesh.polygons, before) if p.normal.dot(n) < 0.0)


def bind(path):
    with open(path) as f:
        data = json.load(f)
    clear_scene()
    mesh = bpy.data.meshes.new("mesh")
    mesh.from_pydata([tuple(v) for v in data["vertices"]], [], [tuple(t) for t in data["triangles"]])
    mesh.update()
    if len(mesh.vertices) != len(data["vertices"]):
        raise RuntimeError(f"{path}: Blender kept {len(mesh.vertices)} of {len(data['vertices'])} vertices")
    body = bpy.data.objects.new("body", mesh)
    bpy.context.scene.collection.objects.link(body)
    flipped = recalculate_outside(body)

    armature = bpy.data.armatures.new("rig")
    rig = bpy.data.objects.new("rig", armature)
    bpy.context.scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    edit = []
    for b in data["bones"]:
        bone = armature.edit_bones.new(b["name"])
        bone.head = b["head"]
        bone.tail = b["tail"]
        bone.use_deform = bool(b["deform"])
        edit.append(bone)
    for b, bone in zip(data["bones"], edit):
        if b["parent"] >= 0:
            bone.parent = edit[b["parent"]]
            bone.use_connect = False
    bpy.ops.object.mode_set(mode="OBJECT")
    if len(armature.bones) != len(data["bones"]):
        raise RuntimeError(f"{path}: Blender kept {len(armature.bones)} of {len(data['bones'])} bones")

    bpy.ops.object.select_all(action="DESELECT")
    body.select_set(True)
    rig.select_set(True)
    bpy.context.view_layer.objects.active = rig
    start = time.perf_counter()
    bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    seconds = time.perf_counter() - start

    names = {g.index: g.name for g in body.vertex_groups}
    weights = []
    for v in mesh.vertices:
        weights.append({names[g.group]: g.weight for g in v.groups if g.weight > 0.0})
    unweighted = sum(1 for w in weights if not w)
    out = {
        "model": data["model"],
        "blender": bpy.app.version_string,
        "seconds": seconds,
        "unweighted_vertices": unweighted,
        "faces_turned_outwards": flipped,
        "weights": weights,
    }
    target = path[: -len(".bind.json")] + ".blender.json"
    with open(target + ".tmp", "w") as f:
        json.dump(out, f)
    os.replace(target + ".tmp", target)
    print(
        f"{data['model']}: {flipped} of {len(mesh.polygons)} faces turned outwards, {seconds:.3f} s, "
        f"{unweighted} of {len(weights)} vertices unweighted",
        flush=True,
    )


def main():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    if len(argv) != 1:
        raise SystemExit("usage: blender --background --python blender_heat.py -- DIR")
    directory = argv[0]
    names = sorted(n for n in os.listdir(directory) if n.endswith(".bind.json"))
    if not names:
        raise SystemExit(f"{directory}: no .bind.json (run weights_study --blender-export {directory} first)")
    for name in names:
        bind(os.path.join(directory, name))


main()
