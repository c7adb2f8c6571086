// Models and their files, the built-in character's rigs and clips, rigs, automatic weights, import and export.
#include <cstring>
#include <filesystem>
#include <optional>
#include <memory>
#include <string>
#include <vector>

#include "common.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/model_files.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/io/sk.hpp"
#include "deform/offline/rig.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/model.hpp"
#ifdef DEFORM_PYTHON_IMPORT
#include "deform/import/import.hpp"
#endif
#ifdef DEFORM_PYTHON_SIMPLIFY
#include "deform/simplify/simplify.hpp"
#endif

namespace deform_python {
namespace {

// Weights from (N, 4) uint16 indices and (N, 4) float32 weights (copies).
deform::SkinWeights weights_from(const py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>& bones,
                                 const FloatArray& weights) {
  if (bones.ndim() != 2 || bones.shape(1) != 4)
    throw deform::Error::invalid_argument("bone_indices", "expected an array of shape (N, 4)");
  const std::size_t n = rows_of(weights, 4, "bone_weights");
  if (static_cast<std::size_t>(bones.shape(0)) != n)
    throw deform::Error::invalid_argument("bone_weights", "as many rows as bone_indices expected");
  deform::SkinWeights out;
  out.bones.resize(n);
  out.weights.resize(n);
  std::memcpy(out.bones.data(), bones.data(), n * sizeof(glm::u16vec4));
  std::memcpy(out.weights.data(), weights.data(), n * sizeof(glm::vec4));
  return out;
}

deform::AutoWeightsOptions weight_options(float falloff_power, float behind_head_penalty, float leaf_length,
                                          int max_influences, int smoothing_iterations) {
  deform::AutoWeightsOptions o;
  o.falloff_power = falloff_power;
  o.behind_head_penalty = behind_head_penalty;
  o.leaf_length = leaf_length;
  o.max_influences = max_influences;
  o.smoothing_iterations = smoothing_iterations;
  return o;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<deform::Model, std::shared_ptr<deform::Model>>(m, "Model",
                                                            "A mesh, its skeleton and skin weights. positions, "
                                                            "bone_indices and bone_weights are writeable views of the "
                                                            "model's storage.")
      .def_readwrite("name", &deform::Model::name)
      .def_property_readonly("skeleton",
                             [](py::object self) {
                               return py::cast(&self.cast<deform::Model&>().skeleton,
                                               py::return_value_policy::reference_internal, self);
                             })
      .def_property_readonly("point_count", [](const deform::Model& md) { return md.mesh.point_count(); })
      .def_property_readonly(
          "positions",
          [](py::object self) { return vec3_view(self.cast<deform::Model&>().mesh.positions, self, true); })
      .def_property_readonly(
          "triangles",
          [](const deform::Model& md) {
            const auto& t = md.mesh.triangles;
            py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(t.size() / 3), py::ssize_t{3}});
            for (std::size_t i = 0; i < t.size(); ++i) out.mutable_data()[i] = md.mesh.vertex_point[t[i]];
            return out;
          },
          "(T, 3) uint32 triangles as indices into positions (a new array; the mesh stores them "
          "over render vertices).")
      .def_property_readonly("vertex_count", [](const deform::Model& md) { return md.mesh.vertex_count(); })
      .def_property_readonly(
          "vertex_points", [](const deform::Model& md) { return copy_array(md.mesh.vertex_point, 1); },
          "(V,) uint32: the point of each render vertex (a point has several at UV and normal seams); "
          "Character.normals() and uvs are per render vertex, positions[vertex_points] their positions.")
      .def_property_readonly(
          "vertex_triangles", [](const deform::Model& md) { return copy_array(md.mesh.triangles, 3); },
          "(T, 3) uint32 triangles over render vertices, the mesh's own winding: what a renderer draws with "
          "uvs and Character.normals().")
      .def_property_readonly(
          "uvs",
          [](const deform::Model& md) -> py::object {
            const auto& uv = md.mesh.vertex_uvs;
            if (uv.empty()) return py::none();
            return copy_array(std::span<const float>(&uv[0].x, 2 * uv.size()), 2);
          },
          "(V, 2) float32 texture coordinates per render vertex, or None when the mesh has none.")
      .def_property_readonly("bone_indices",
                             [](py::object self) {
                               auto& w = self.cast<deform::Model&>().weights.bones;
                               return view(w.empty() ? nullptr : &w[0].x, w.size(), 4, self, true);
                             })
      .def_property_readonly("bone_weights",
                             [](py::object self) {
                               auto& w = self.cast<deform::Model&>().weights.weights;
                               return view(w.empty() ? nullptr : &w[0].x, w.size(), 4, self, true);
                             })
      .def(
          "set_weights",
          [](deform::Model& md, const py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>& bones,
             const FloatArray& weights) {
            deform::SkinWeights w = weights_from(bones, weights);
            if (w.size() != md.mesh.point_count())
              throw deform::Error::invalid_argument("bone_weights", "one row per mesh point expected");
            md.weights = std::move(w);
          },
          py::arg("bone_indices"), py::arg("bone_weights"), "Replaces the skin weights (copies the arrays).")
      .def(
          "copy", [](const deform::Model& md) { return md; }, "An independent copy.")
      .def(
          "save",
          [](const deform::Model& md, const std::string& obj, const std::string& sk, const std::string& skw) {
            deform::write_obj(obj, md.mesh, md.mesh.positions);
            deform::write_sk(sk, md.skeleton);
            deform::write_skw(skw, md.weights);
          },
          py::arg("obj"), py::arg("sk"), py::arg("skw"),
          "Writes the native files: the mesh as OBJ (without materials or `o`/`g` names: a Model holds geometry), the "
          "skeleton as .sk, the weights as .skw.");

  m.def(
      "load_model",
      [](const std::string& obj, const std::string& sk, const std::string& skw,
         const std::vector<std::string>& allow_outside) {
        deform::Warnings warnings;
        deform::ReferencePolicy policy;
        policy.allow_outside = allow_outside;
        auto model = std::make_shared<deform::Model>(
            deform::load_model(obj, sk, skw, &warnings, deform::max_influences, policy));
        return model;
      },
      py::arg("obj"), py::arg("sk"), py::arg("skw"), py::arg("allow_outside") = std::vector<std::string>{},
      "Loads a native model: OBJ mesh, .sk skeleton, .skw weights. The MTL files and textures the OBJ names are read "
      "only inside its folder or a folder of `allow_outside` (docs/security.md); any other raises ValueError.");
  m.def(
      "save_obj",
      [](const std::string& path, const deform::Model& md, std::optional<FloatArray> positions) {
        std::span<const glm::vec3> p = md.mesh.positions;
        if (positions) {
          p = as_vec3(*positions, "positions");
          if (p.size() != md.mesh.point_count())
            throw deform::Error::invalid_argument("positions", "one row per mesh point expected");
        }
        deform::write_obj(path, md.mesh, p);
      },
      py::arg("path"), py::arg("model"), py::arg("positions") = py::none(),
      "Writes the model's mesh as OBJ with the given (N, 3) positions (e.g. Character.positions), else its own.");
  m.def(
      "builtin_character", []() { return std::make_shared<deform::Model>(deform::builtin_character()); },
      "The built-in rigged humanoid (33 bones: the body's 29 and a ponytail's 4; 2,850 points; about 13 ms).");
}

void bind_rig(py::module_& m) {
  m.def(
      "default_rig",
      [](const deform::Model& md, const py::object& effector) {
        return deform::default_rig(md, effector.is_none() ? -1 : resolve_bone(md.skeleton, effector));
      },
      py::arg("model"), py::arg("effector") = py::none(),
      "Three lattices on the limb ending at `effector` (default: a hand).");
  m.def(
      "builtin_rig", [](const deform::Model& md) { return deform::builtin_rig(md); }, py::arg("model"),
      "The rig of the built-in character (three lattices on the left arm).");
  m.def(
      "builtin_full_rig", [](const deform::Model& md) { return deform::builtin_full_rig(md); }, py::arg("model"),
      "The built-in character's rig with lattices on every limb (both arms and both legs).");
  m.def(
      "builtin_clips", [](const deform::Model& md) { return deform::builtin_clips(md); }, py::arg("model"),
      "The built-in character's clips: idle, walk, run and wave (a list of Animation).");
  m.def(
      "read_rig",
      [](const std::string& path, const deform::Model& md) {
        return deform::read_rig_json(path, md.skeleton, md.mesh.point_count());
      },
      py::arg("path"), py::arg("model"), "Reads a rig JSON file for `model`.");
  py::class_<deform::Rig>(m, "Rig", "Lattices, springs and the reach chain of a Character.")
      .def_property_readonly("lattice_count", [](const deform::Rig& r) { return r.lattices.size(); })
      .def_property_readonly("lattice_names",
                             [](const deform::Rig& r) {
                               std::vector<std::string> names;
                               for (const auto& l : r.lattices) names.push_back(l.name);
                               return names;
                             })
      .def_readwrite("reach_effector", &deform::Rig::reach_effector)
      .def_readwrite("max_stretch", &deform::Rig::max_stretch)
      .def_property_readonly("spring_chain_names",
                             [](const deform::Rig& r) {
                               std::vector<std::string> names;
                               for (const auto& c : r.spring_chains) names.push_back(c.name);
                               return names;
                             })
      .def(
          "add_spring_chain",
          [](deform::Rig& r, const deform::Model& md, const std::string& name, const std::vector<py::object>& bones,
             float frequency, float damping_ratio, const std::optional<FloatArray>& gravity, float units_per_metre,
             float radius) {
            deform::SpringChainSpec chain;
            chain.name = name;
            for (const py::object& bone : bones) chain.bones.push_back(resolve_bone(md.skeleton, bone));
            chain.frequency = frequency;
            chain.damping_ratio = damping_ratio;
            chain.gravity = gravity ? to_vec3(*gravity, "gravity") : glm::vec3(0.0f);
            chain.units_per_metre = units_per_metre;
            chain.radius = radius;
            deform::require_valid_chain_settings(chain);
            r.spring_chains.push_back(std::move(chain));
          },
          py::arg("model"), py::arg("name"), py::arg("bones"), py::arg("frequency") = 2.0f,
          py::arg("damping_ratio") = 0.3f, py::arg("gravity") = py::none(), py::arg("units_per_metre") = 1.0f,
          py::arg("radius") = 0.0f,
          "Adds a spring chain over `bones` (ids or names of `model`'s skeleton, root first, each the parent of the "
          "next): frequency in Hz, damping ratio, gravity in m/s² (model space; default none). A Character built "
          "with the rig checks the bones and raises deform.Error for a chain it cannot bind.")
      .def(
          "save",
          [](const deform::Rig& r, const std::string& path, const deform::Model& md,
             const std::optional<std::string>& model_file) {
            deform::Rig saved = r;
            if (model_file) {  // the file names its model relative to its own folder, as the CLI reads it
              const std::filesystem::path folder = std::filesystem::absolute(path).parent_path();
              std::filesystem::path relative = std::filesystem::absolute(*model_file).lexically_relative(folder);
              if (relative.empty()) relative = std::filesystem::absolute(*model_file);
              saved.model = {};
              saved.model.file = relative.generic_string();
            }
            deform::write_rig_json(path, saved, md.skeleton);
          },
          py::arg("path"), py::arg("model"), py::arg("model_file") = py::none(),
          "Writes the rig as JSON. Its \"model\" key names the model the CLI loads with it (`deform simulate RIG`): "
          "`model_file` (the file import_model read, written relative to the rig's folder), or else what the rig "
          "says (\"builtin\" for builtin_rig()); without either the CLI needs the model on its command line.");
}

void bind_automatic_weights(py::module_& m) {
  m.def(
      "compute_automatic_weights",
      [](py::object target, const deform::Skeleton& skeleton, float falloff_power, float behind_head_penalty,
         float leaf_length, int max_influences, int smoothing_iterations) {
        const deform::AutoWeightsOptions o =
            weight_options(falloff_power, behind_head_penalty, leaf_length, max_influences, smoothing_iterations);
        deform::SkinWeights w;
        if (py::isinstance<deform::Model>(target)) {
          w = deform::compute_automatic_weights(target.cast<const deform::Model&>().mesh, skeleton, o);
        } else {
          const FloatArray points = target.cast<FloatArray>();
          w = deform::compute_automatic_weights(as_vec3(points, "points"), skeleton, o);
        }
        py::array_t<std::uint16_t> bones({static_cast<py::ssize_t>(w.size()), py::ssize_t{4}});
        py::array_t<float> weights({static_cast<py::ssize_t>(w.size()), py::ssize_t{4}});
        std::memcpy(bones.mutable_data(), w.bones.data(), w.size() * sizeof(glm::u16vec4));
        std::memcpy(weights.mutable_data(), w.weights.data(), w.size() * sizeof(glm::vec4));
        return py::make_tuple(bones, weights);
      },
      py::arg("mesh_or_points"), py::arg("skeleton"), py::arg("falloff_power") = 4.0f,
      py::arg("behind_head_penalty") = 2.0f, py::arg("leaf_length") = 1.0f, py::arg("max_influences") = 4,
      py::arg("smoothing_iterations") = 2,
      "Skin weights from bone distances: (bone_indices (N, 4) uint16, bone_weights (N, 4) float32), new arrays. "
      "Given a Model, smooths over its mesh; given (N, 3) points, by distance alone.");
}

// has_import says whether import_model and export_native exist (the build found Assimp).
void bind_import_export(py::module_& m) {
#ifdef DEFORM_PYTHON_IMPORT
  m.attr("has_import") = true;
  m.def(
      "import_model",
      [](const std::string& path, const std::vector<std::string>& allow_outside) {
        deform::ImportOptions options;
        options.references.allow_outside = allow_outside;
        deform::ImportedModel imported = deform::import_model_isolated(path, options);
        py::dict out;
        out["model"] = std::make_shared<deform::Model>(std::move(imported.model));
        out["rigged"] = imported.rigged;
        out["warnings"] = imported.warnings;
        out["clips"] = std::move(imported.clips);
        return out;
      },
      py::arg("path"), py::arg("allow_outside") = std::vector<std::string>{},
      "Imports glTF/FBX/Collada/X/... through Assimp in a separate process (deform::import_model_isolated; the "
      "files the model names are read only inside its folder or a folder of `allow_outside`, docs/security.md; the "
      "worker executable deform-import-worker is found through $DEFORM_IMPORT_WORKER, the build or the install). "
      "Returns a dict: model, rigged, warnings, clips (a list of Animation).");
  m.def(
      "export_native",
      [](const deform::Model& md, const std::string& folder) {
        const deform::ExportedFiles files = deform::export_native(md, folder);
        py::dict out;
        out["obj"] = files.obj;
        out["mtl"] = files.mtl;
        out["sk"] = files.sk;
        out["skw"] = files.skw;
        out["textures"] = files.textures;
        out["warnings"] = files.warnings;
        return out;
      },
      py::arg("model"), py::arg("folder"),
      "Writes the model as native files (OBJ + MTL + textures, .sk, .skw) into `folder`; returns their paths.");
#else
  m.attr("has_import") = false;
#endif
}

// has_simplify says whether simplify_levels exists (the build found meshoptimizer).
void bind_simplify(py::module_& m) {
#ifdef DEFORM_PYTHON_SIMPLIFY
  m.attr("has_simplify") = true;
  m.def(
      "simplify_levels",
      [](const deform::Model& md, const std::vector<float>& triangle_ratios, float max_error) {
        std::vector<deform::SimplifySettings> settings;
        for (const float ratio : triangle_ratios) settings.push_back({ratio, max_error});
        py::list out;
        for (const deform::MeshLevel& level : deform::simplify_levels(md, settings)) {
          py::array_t<std::uint32_t> points(static_cast<py::ssize_t>(level.points.size()));
          std::copy(level.points.begin(), level.points.end(), points.mutable_data());
          py::array_t<std::uint32_t> triangles({static_cast<py::ssize_t>(level.triangles.size() / 3), py::ssize_t{3}});
          for (std::size_t i = 0; i < level.triangles.size(); ++i)
            triangles.mutable_data()[i] = md.mesh.vertex_point[level.triangles[i]];
          py::dict d;
          d["points"] = points, d["triangles"] = triangles, d["error"] = level.error;
          d["vertex_triangles"] = copy_array(level.triangles, 3);
          out.append(d);
        }
        return out;
      },
      py::arg("model"), py::arg("triangle_ratios"), py::arg("max_error") = 0.05f,
      "Meshes for levels 1, 2, ... of a Character (deform::simplify_levels, meshoptimizer): level l keeps "
      "triangle_ratios[l - 1] of the whole mesh's triangles (decreasing; each level simplified from the one before, "
      "so they are nested), each collapse moving the surface at most max_error of the mesh's size. A list of dicts: "
      "points (uint32, the model's point ids the level keeps, the coarser levels' first: a Character level's "
      "`points`), triangles ((T, 3) uint32 over the model's points, as Model.triangles), vertex_triangles (the "
      "same triangles over the model's render vertices, as Model.vertex_triangles: what a renderer draws with uvs and "
      "Character.normals()), error (a bound on the "
      "level's distance from the whole mesh, a fraction of its size).");
#else
  m.attr("has_simplify") = false;
#endif
}

}  // namespace deform_python
