# Blender's Corrective Smooth modifier (its Delta Mush) on the inputs corrective_smooth.py exports, for the
# comparison in docs/skinning.md ("Against Blender's Corrective Smooth"). Run by blender_study.sh as
#
#   blender --background --factory-startup --python blender_corrective_smooth.py -- DIR
#
# Reads DIR/input.json: the bind points, the point triangles, the step, the iteration counts and, per pose, the
# LBS-skinned points. Builds the mesh from the bind points (vertex order kept, so the rest is the bind mesh: the
# modifier's rest_source ORCO reads the mesh's own positions, the basis shape key), gives the skinned points as a
# second shape key at value 1 (so the modifier's input is libdeform's LBS to the bit: only the smoothing is
# compared), and evaluates Corrective Smooth (smooth_type SIMPLE, factor = step, scale 1, no vertex group, boundary
# not pinned) at each iteration count, and once with use_only_smooth (the smoothing alone). Writes DIR/blender.json
# (atomically) with Blender's version.
import json
import os
import sys

import bpy


def evaluated_points(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    points = [list(v.co) for v in mesh.vertices]
    evaluated.to_mesh_clear()
    return points


def main(folder):
    with open(os.path.join(folder, "input.json")) as f:
        data = json.load(f)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    mesh = bpy.data.meshes.new("body")
    mesh.from_pydata([tuple(p) for p in data["points"]], [], [tuple(t) for t in data["triangles"]])
    mesh.update()
    if len(mesh.vertices) != len(data["points"]) or len(mesh.polygons) != len(data["triangles"]):
        raise RuntimeError(f"Blender kept {len(mesh.vertices)} of {len(data['points'])} points and "
                           f"{len(mesh.polygons)} of {len(data['triangles'])} triangles")
    body = bpy.data.objects.new("body", mesh)
    bpy.context.scene.collection.objects.link(body)
    body.shape_key_add(name="Basis", from_mix=False)
    posed = body.shape_key_add(name="posed", from_mix=False)
    posed.value = 1.0

    smooth = body.modifiers.new("mush", "CORRECTIVE_SMOOTH")
    smooth.smooth_type = "SIMPLE"
    smooth.rest_source = "ORCO"
    smooth.factor = data["step"]
    smooth.scale = 1.0
    smooth.use_pin_boundary = False

    results = {}
    for name, points in data["poses"].items():
        for i, p in enumerate(points):
            posed.data[i].co = p
        for iterations in data["iterations"]:
            smooth.iterations = iterations
            smooth.use_only_smooth = False
            results[f"{name}/{iterations}"] = evaluated_points(body)
            smooth.use_only_smooth = True
            results[f"{name}/{iterations}/smooth"] = evaluated_points(body)
    out = {"blender": bpy.app.version_string, "edges": len(mesh.edges), "results": results}
    target = os.path.join(folder, "blender.json")
    with open(target + ".tmp", "w") as f:
        json.dump(out, f)
    os.replace(target + ".tmp", target)
    print(f"Blender {bpy.app.version_string}: wrote {target}")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1])
