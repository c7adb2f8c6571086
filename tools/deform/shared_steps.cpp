#include "shared_steps.hpp"

#include <cmath>
#include <filesystem>

#include "cli.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
namespace cli {

model_loading::LoadedModel load_rig_model(const deform::RigModel& named, const std::string& rig_path,
                                          const deform::ReferencePolicy& policy) {
  model_loading::ModelRequest request;
  request.references = policy;
  if (!named.builtin) {
    if (named.obj.empty()) throw deform::Error::in_file(rig_path, "key 'model'", "the rig names no model");
    // Each is confined before it is opened; the paths keep the rig's spelling (they name the files in messages).
    deform::resolve_referenced_file(rig_path, named.obj, "key 'model.obj'", policy);
    deform::resolve_referenced_file(rig_path, named.skeleton, "key 'model.skeleton'", policy);
    deform::resolve_referenced_file(rig_path, named.weights, "key 'model.weights'", policy);
    const std::filesystem::path folder = std::filesystem::path(rig_path).parent_path();
    request.path = (folder / named.obj).string();
    request.skeleton = (folder / named.skeleton).string();
    request.weights = (folder / named.weights).string();
  }
  model_loading::LoadedModel loaded = model_loading::load_model(request);
  for (const std::string& message : loaded.warnings) note(message);
  return loaded;
}

// Render-vertex normals of the deformed points: n' ∝ cof(J)·n with J = ∂Q/∂(u,v,w) · diag(size)⁻¹ (as `deform ffd`).
std::vector<glm::vec3> ffd_normals(const deform::Mesh& mesh, const deform::BezierLattice& lattice,
                                   const std::vector<bool>& deformed) {
  const deform::LatticeFrame& frame = lattice.frame();
  const glm::vec3 size(frame.u_axis.x, frame.v_axis.y, frame.w_axis.z);
  std::vector<glm::vec3> normals = mesh.vertex_normals;
  for (std::size_t r = 0; r < normals.size() && r < mesh.vertex_point.size(); ++r) {
    const std::uint32_t p = mesh.vertex_point[r];
    if (!deformed[p]) continue;
    glm::mat3 j = lattice.jacobian(frame.to_lattice(mesh.positions[p]));
    for (int a = 0; a < 3; ++a) j[a] /= size[a];
    const glm::mat3 cofactor(glm::cross(j[1], j[2]), glm::cross(j[2], j[0]), glm::cross(j[0], j[1]));
    const glm::vec3 n = cofactor * normals[r];
    const float length = glm::length(n);
    if (length > 0.0f && std::isfinite(length)) normals[r] = n / length;
  }
  return normals;
}

}  // namespace cli
