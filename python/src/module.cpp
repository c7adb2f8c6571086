// The `deform` Python module: errors, models (loading, weights, export), skeletons and poses.
#include <cstring>
#include <exception>
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
#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/model.hpp"
#ifdef DEFORM_PYTHON_IMPORT
#include "deform/import/import.hpp"
#endif

namespace deform_python {
namespace {

py::object error_type;  // deform.Error, set once at import

void raise(const std::string& what, py::object kind, py::object message, py::object file, py::object line,
           py::object byte, py::object element) {
  py::object instance = error_type(what);
  instance.attr("kind") = std::move(kind);
  instance.attr("message") = std::move(message);
  instance.attr("file") = std::move(file);
  instance.attr("line") = std::move(line);
  instance.attr("byte") = std::move(byte);
  instance.attr("element") = std::move(element);
  PyErr_SetObject(error_type.ptr(), instance.ptr());
}

py::object or_none(const std::string& s) { return s.empty() ? py::object(py::none()) : py::object(py::str(s)); }

void translate(std::exception_ptr pointer) {
  try {
    if (pointer) std::rethrow_exception(pointer);
  } catch (const deform::Error& e) {
    const char* kind = e.kind() == deform::Error::Kind::input      ? "input"
                       : e.kind() == deform::Error::Kind::argument ? "argument"
                                                                   : "environment";
    const py::object position = py::int_(e.position());
    raise(e.what(), py::str(kind), py::str(e.message()), or_none(e.file()),
          e.where() == deform::Error::Where::line ? position : py::none(),
          e.where() == deform::Error::Where::byte ? position : py::none(), or_none(e.element()));
  } catch (const StatusFailure& failure) {
    raise(failure.reason, py::str("status"), py::str(failure.reason), py::none(), py::none(), py::none(), py::none());
  }
}

std::int32_t bone_id(const deform::Skeleton& skeleton, const py::object& bone) {
  if (py::isinstance<py::str>(bone)) {
    const std::string name = bone.cast<std::string>();
    const std::int32_t id = skeleton.find(name);
    if (id < 0) throw deform::Error::invalid_argument("bone '" + name + "'", "no bone of that name");
    return id;
  }
  const auto id = bone.cast<std::int64_t>();
  if (id < 0 || static_cast<std::size_t>(id) >= skeleton.bone_count())
    throw deform::Error::invalid_argument("bone " + std::to_string(id), "bone id out of range");
  return static_cast<std::int32_t>(id);
}

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

std::int32_t resolve_bone(const deform::Skeleton& skeleton, const py::object& bone) { return bone_id(skeleton, bone); }

}  // namespace deform_python

using namespace deform_python;

PYBIND11_MODULE(deform, m) {
  m.doc() =
      "libdeform on NumPy: skinning, IK, Bezier/B-spline lattices, elastic lattices and the Character.\n\n"
      "Arrays are float32. A C-contiguous float32 (N, 3) input is read in place; anything else is converted "
      "(one copy). Properties documented as views share memory with their object and keep it alive.";

  error_type = py::reinterpret_borrow<py::object>(
      PyErr_NewExceptionWithDoc("deform.Error",
                                "libdeform's error (deform::Error, or a refused per-frame call).\n\n"
                                "str(e) is libdeform's one-line message. Attributes: kind ('input': a file or data "
                                "is bad; 'argument': an argument is invalid; 'status': a per-frame call refused), "
                                "message (without the location), file, line (1-based, text formats), byte (offset, "
                                "binary formats), element ('bone 3', 'vertex 17'); None where they do not apply.",
                                PyExc_ValueError, nullptr));
  m.attr("Error") = error_type;
  py::register_exception_translator(&translate);

  // --- skeleton and pose ---
  py::class_<deform::Pose>(m, "Pose",
                           "Every bone's local rotation (quaternion x, y, z, w) and translation. `rotations` (B, 4) "
                           "and `translations` (B, 3) are writeable views of the pose's storage.")
      .def(py::init<>())
      .def_property_readonly("rotations",
                             [](py::object self) {
                               auto& p = self.cast<deform::Pose&>();
                               return view(p.rotations.empty() ? nullptr : &p.rotations[0].x, p.rotations.size(), 4,
                                           self, true);
                             })
      .def_property_readonly("translations",
                             [](py::object self) {
                               auto& p = self.cast<deform::Pose&>();
                               return vec3_view(p.translations, self, true);
                             })
      .def(
          "copy", [](const deform::Pose& p) { return p; }, "An independent copy.")
      .def("__len__", [](const deform::Pose& p) { return p.rotations.size(); });

  py::class_<deform::Skeleton>(m, "Skeleton")
      .def_property_readonly("bone_count", &deform::Skeleton::bone_count)
      .def("__len__", &deform::Skeleton::bone_count)
      .def_property_readonly("names",
                             [](const deform::Skeleton& s) {
                               std::vector<std::string> names;
                               for (const deform::Bone& b : s.bones()) names.push_back(b.name);
                               return names;
                             })
      .def_property_readonly(
          "parents",
          [](const deform::Skeleton& s) {
            py::array_t<std::int32_t> out(static_cast<py::ssize_t>(s.bone_count()));
            for (std::size_t i = 0; i < s.bone_count(); ++i) out.mutable_data()[i] = s.bones()[i].parent;
            return out;
          },
          "Parent id per bone, -1 for the root (a copy).")
      .def("find", &deform::Skeleton::find, py::arg("name"), "Bone id of `name`, -1 when none.")
      .def(
          "limits",
          [](const deform::Skeleton& s, const py::object& bone) {
            const deform::DofLimits& l = s.bone(bone_id(s, bone)).limits;
            return py::make_tuple(py::make_tuple(l.min.x, l.min.y, l.min.z), py::make_tuple(l.max.x, l.max.y, l.max.z));
          },
          py::arg("bone"), "(min, max) Euler limits in degrees (X, Y, Z) of a bone (id or name).")
      .def(
          "within_limits",
          [](const deform::Skeleton& s, const deform::Pose& pose, const py::object& bone, float slack) {
            const std::int32_t id = bone_id(s, bone);
            if (pose.rotations.size() != s.bone_count())
              throw deform::Error::invalid_argument("pose", "the pose does not have one entry per bone");
            const deform::DofLimits& limits = s.bone(id).limits;
            const glm::vec3 euler = deform::euler_within_limits(pose.rotations[static_cast<std::size_t>(id)], limits);
            return deform::within_limits(euler, limits, slack);
          },
          py::arg("pose"), py::arg("bone"), py::arg("slack") = 1e-3f,
          "Whether a bone's rotation in `pose` is within its Euler DOF limits (to `slack` degrees).")
      .def("bind_pose", &deform::Skeleton::bind_pose)
      .def_property_readonly(
          "bind_world", [](const deform::Skeleton& s) { return matrices_out(s.bind_world()); },
          "(B, 4, 4) bind world matrices, row-major (a copy).")
      .def(
          "set_euler",
          [](const deform::Skeleton& s, deform::Pose& pose, const py::object& bone, const FloatArray& degrees,
             bool clamp) {
            if (pose.rotations.size() != s.bone_count())
              throw deform::Error::invalid_argument("pose", "the pose does not have one entry per bone");
            const glm::vec3 set = s.set_euler(pose, bone_id(s, bone), to_vec3(degrees, "degrees"), clamp);
            return py::make_tuple(set.x, set.y, set.z);
          },
          py::arg("pose"), py::arg("bone"), py::arg("degrees"), py::arg("clamp") = true,
          "Sets a bone's rotation in `pose` from Euler X·Y·Z degrees, clamped into its limits unless clamp=False; "
          "returns the angles set.");

  // --- model ---
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
  m.def(
      "default_rig",
      [](const deform::Model& md, const py::object& effector) {
        return deform::default_rig(md, effector.is_none() ? -1 : bone_id(md.skeleton, effector));
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
            for (const py::object& bone : bones) chain.bones.push_back(bone_id(md.skeleton, bone));
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

  py::class_<deform::Animation>(m, "Animation", "An imported clip: per-bone tracks (deform::Animation).")
      .def_readonly("name", &deform::Animation::name)
      .def_readonly("duration", &deform::Animation::duration, "seconds")
      .def_readwrite("loop", &deform::Animation::loop, "sampling wraps time when True, clamps it otherwise")
      .def(
          "sample",
          [](const deform::Animation& clip, float time, deform::Pose& pose) {
            deform::SamplingJob job;
            job.animation = &clip;
            job.time = time;
            job.rotations = pose.rotations;
            job.translations = pose.translations;
            check(job.validate());
            check(job.run());
          },
          py::arg("time"), py::arg("pose"),
          "Writes the clip at `time` seconds into `pose` (bones without a track keep their values). Start from the "
          "skeleton's bind_pose().");

  // --- blending, additive layers, root motion (deform/runtime/blending.hpp, docs/animation.md) ---
  m.def(
      "blend",
      [](const py::list& layers, const deform::Pose& rest, float threshold, const py::list& additive) {
        std::vector<FloatArray> masks;  // keeps converted masks alive while the job reads them
        masks.reserve(layers.size() + additive.size());
        auto to_layers = [&](const py::list& items, const char* what) {
          std::vector<deform::BlendLayer> out;
          for (std::size_t i = 0; i < items.size(); ++i) {
            const auto item = items[i].cast<py::tuple>();
            const std::string element = std::string(what) + " " + std::to_string(i);
            if (item.size() != 2 && item.size() != 3)
              throw deform::Error::invalid_argument(element, "expected (pose, weight) or (pose, weight, mask)");
            const auto& pose = item[0].cast<const deform::Pose&>();
            deform::BlendLayer layer{pose.rotations, pose.translations, item[1].cast<float>(), {}};
            if (item.size() == 3 && !item[2].is_none()) {
              masks.push_back(item[2].cast<FloatArray>());
              const FloatArray& mask = masks.back();
              if (mask.ndim() != 1) throw deform::Error::invalid_argument(element, "mask: expected a 1-D array");
              layer.bone_weights = {mask.data(), static_cast<std::size_t>(mask.shape(0))};
            }
            out.push_back(layer);
          }
          return out;
        };
        const std::vector<deform::BlendLayer> normal = to_layers(layers, "layer");
        const std::vector<deform::BlendLayer> added = to_layers(additive, "additive layer");
        deform::Pose out = rest;
        deform::BlendingJob job;
        job.layers = normal;
        job.additive_layers = added;
        job.threshold = threshold;
        job.rest_rotations = rest.rotations;
        job.rest_translations = rest.translations;
        job.rotations = out.rotations;
        job.translations = out.translations;
        check(job.validate());
        check(job.run());
        return out;
      },
      py::arg("layers"), py::arg("rest"), py::arg("threshold") = 0.1f, py::arg("additive") = py::list(),
      "Blends poses by weight (deform::BlendingJob): `layers` and `additive` are lists of (pose, weight) or "
      "(pose, weight, mask), mask a (B,) array of per-bone weights. Returns a new Pose: the normalised weighted "
      "average (nlerp for rotations), the `rest` pose joining where the weights sum to less than `threshold`, then "
      "each additive (delta) pose applied with its weight.");
  m.def(
      "additive_delta",
      [](const deform::Pose& reference, const deform::Pose& pose) {
        deform::Pose out = pose;
        check(deform::additive_delta(reference.rotations, reference.translations, pose.rotations, pose.translations,
                                     out.rotations, out.translations));
        return out;
      },
      py::arg("reference"), py::arg("pose"),
      "The delta pose that turns `reference` into `pose` as an additive layer (q_ref^-1 q, t - t_ref).");
  m.def(
      "make_additive_clip",
      [](const deform::Animation& clip, const deform::Pose* reference) {
        return reference == nullptr ? deform::make_additive_clip(clip) : deform::make_additive_clip(clip, *reference);
      },
      py::arg("clip"), py::arg("reference") = nullptr,
      "An additive clip: the clip's keys as deltas from its first frame, or from `reference`. Sample it into a pose "
      "that starts as the identity.");
  m.def(
      "root_motion",
      [](const deform::Animation& clip, std::int32_t bone, float start, float end, const FloatArray& up,
         deform::Pose* pose) {
        deform::RootMotion motion;
        deform::RootMotionJob job;
        job.animation = &clip;
        job.bone = bone;
        job.from = start;
        job.to = end;
        job.up = to_vec3(up, "up");
        job.motion = &motion;
        if (pose != nullptr) {
          job.rotations = pose->rotations;
          job.translations = pose->translations;
        }
        check(job.validate());
        check(job.run());
        py::array_t<float> translation(3);
        for (int i = 0; i < 3; ++i) translation.mutable_data()[i] = motion.translation[i];
        return py::make_tuple(translation, motion.yaw);
      },
      py::arg("clip"), py::arg("bone"), py::arg("start"), py::arg("end"), py::arg("up") = std::vector<float>{0, 1, 0},
      py::arg("pose") = nullptr,
      "The root bone's motion over [start, end] seconds (deform::RootMotionJob, loops counted): (translation (3,), "
      "yaw in radians), the translation horizontal and in the frame at `start`. With `pose` (the clip sampled at "
      "`end`), also puts that bone in place there: no horizontal translation, the first frame's yaw.");

  bind_jobs(m);
  bind_lattices(m);
  bind_character(m);
  bind_weight_tools(m);
  bind_decomposition(m);
}
