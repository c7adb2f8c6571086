#pragma once
// Steps that more than one command takes, written once.
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "model_loading.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"
namespace cli {

// The model a rig file names (`simulate`, `bake`), its paths taken relative to the rig file's folder; the loader's
// warnings go to stderr. Throws deform::Error naming the rig file when it names no model.
// The model's files are confined to the rig file's folder and `policy`'s (resolve_referenced_file), as any file a
// model names is.
model_loading::LoadedModel load_rig_model(const deform::RigModel& named, const std::string& rig_path,
                                          const deform::ReferencePolicy& policy = {});

// Render-vertex normals of a mesh deformed by `lattice` (`ffd`, `bake`): n' ∝ cof(J)·n with
// J = ∂Q/∂(u,v,w) · diag(size)⁻¹ at each deformed point's rest position (the mesh's own positions); the normals of
// points where `deformed` (one flag per point) is false are the mesh's. O(render vertices · lattice cost).
std::vector<glm::vec3> ffd_normals(const deform::Mesh& mesh, const deform::BezierLattice& lattice,
                                   const std::vector<bool>& deformed);

}  // namespace cli
