// deform ffd MESH --lattice L.json --out OUT.obj: a Bézier-volume free-form deformation (docs/cli.md).
#include <cmath>
#include <stdexcept>
#include <vector>

#include "cli.hpp"
#include "model_loading.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "deform/io/lattice_json.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
namespace cli {
namespace {

const char* const usage =
    "usage: deform ffd (MESH.obj | MODEL) --lattice L.json --out OUT.obj [--allow-outside DIR]...\n"
    "\n"
    "Deforms the mesh (an OBJ, or the bind-pose mesh of a MODEL an importer reads: glTF, FBX, ...) with an\n"
    "axis-aligned Bezier lattice. L.json:\n"
    "  {\"origin\": [x, y, z], \"size\": [sx, sy, sz], \"degree\": [l, m, n],\n"
    "   \"displacements\": [{\"index\": [i, j, k], \"offset\": [dx, dy, dz]}, ...], \"vertices\": [...]}\n"
    "Control point P_ijk rests at origin + (i/l*sx, j/m*sy, k/n*sz); degree defaults to [3, 3, 3]. A vertex is\n"
    "deformed when (p - origin) / size lies in [0, 1]^3 and, if \"vertices\" (0-based OBJ v indices) is given, it is\n"
    "listed; every other vertex is written unchanged. Normals of deformed vertices follow the lattice's Jacobian.\n"
    "OUT.obj keeps the v lines in order and the faces; it is written atomically.\n"
    "Prints {\"vertices\": N, \"deformed\": K, \"lattice\": {...}, \"output\": OUT.obj}.\n";

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"--lattice", "--out", "--allow-outside"}, {});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one MESH argument");
  const std::string mesh_path = args.positionals()[0];
  const std::string lattice_path = args.required("--lattice");
  const std::string out_path = args.required("--out");

  deform::Mesh mesh;
  deform::ObjNames names;                      // the input's `o`/`g` names and MTL files, written again as it had them
  if (model_loading::importable(mesh_path)) {  // an import's mesh in its bind pose
    model_loading::ModelRequest request;
    request.path = mesh_path;
    request.references = reference_policy(args);
    model_loading::LoadedModel loaded = model_loading::load_model(request);
    for (const std::string& w : loaded.warnings) note(w);
    mesh = std::move(loaded.model.mesh);
    names = std::move(loaded.names);
  } else {
    deform::Warnings warnings;
    mesh = deform::read_obj(mesh_path, &warnings, reference_policy(args), &names);
    for (const std::string& w : warnings.messages) note(w);
  }
  const deform::LatticeDocument doc = deform::read_lattice_json(lattice_path, mesh.point_count());
  const deform::BezierLattice& lattice = doc.lattice;

  // The rest lattice binds (so (u, v, w) are those of the undeformed mesh); the displaced points evaluate.
  const deform::BezierLattice rest(lattice.frame(), lattice.degree(), lattice_path);
  const deform::LatticeBinding binding = doc.has_vertices ? deform::bind_lattice(rest, mesh.positions, doc.vertices)
                                                          : deform::bind_lattice(rest, mesh.positions);
  std::vector<glm::vec3> positions = mesh.positions;
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = positions;
  if (!job.run()) throw std::runtime_error("internal error: the lattice evaluation rejected its arguments");

  std::vector<bool> deformed(mesh.point_count(), false);
  for (const std::uint32_t p : binding.vertices)
    if (p != deform::LatticeBinding::no_vertex) deformed[p] = true;
  const std::vector<glm::vec3> normals = ffd_normals(mesh, lattice, deformed);
  // The output names the input's MTL files (relative to its own folder), so it opens with its materials.
  deform::write_obj(out_path, mesh, positions, normals,
                    {.mtllib = deform::material_libraries_for(names, out_path), .submesh_names = names.submeshes});

  const deform::LatticeFrame& frame = lattice.frame();
  const glm::vec3 size(frame.u_axis.x, frame.v_axis.y, frame.w_axis.z);
  nlohmann::json lattice_json = {{"origin", to_json(frame.origin)},
                                 {"size", to_json(size)},
                                 {"degree", {lattice.degree().x, lattice.degree().y, lattice.degree().z}},
                                 {"control_points", lattice.point_count()},
                                 {"displacements", doc.displacement_count}};
  if (doc.has_vertices) lattice_json["vertices"] = doc.vertices.size();
  print_json({{"vertices", mesh.point_count()},
              {"deformed", binding.vertex_count},
              {"lattice", lattice_json},
              {"output", out_path}});
  return exit_ok;
}

}  // namespace

const Command ffd_command = {"ffd", "apply a Bezier-volume free-form deformation", usage, run};

}  // namespace cli
