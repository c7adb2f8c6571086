// Forward kinematics, skinning (LBS, DQS, Direct Delta Mush), IK (CCD, FABRIK, two-bone) and the elastic lattice.
#include <cstring>
#include <optional>
#include <vector>

#include "common.hpp"
#include "deform/offline/direct_delta_mush.hpp"
#include "deform/runtime/direct_delta_mush.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"

namespace deform_python {

// glm matrices from (B, 4, 4) row-major float32 (a copy: glm stores columns).
std::vector<glm::mat4> matrices_in(const FloatArray& a) {
  if (a.ndim() != 3 || a.shape(1) != 4 || a.shape(2) != 4)
    throw deform::Error::invalid_argument("matrices", "expected an array of shape (B, 4, 4)");
  std::vector<glm::mat4> out(static_cast<std::size_t>(a.shape(0)));
  const float* src = a.data();
  for (std::size_t b = 0; b < out.size(); ++b)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out[b][c][r] = src[16 * b + static_cast<std::size_t>(4 * r + c)];
  return out;
}

namespace {

deform::SkinningMethod method_of(const std::string& name) {
  if (name == "lbs") return deform::SkinningMethod::lbs;
  if (name == "dqs") return deform::SkinningMethod::dqs;
  throw deform::Error::invalid_argument("method", "expected 'lbs' or 'dqs'");
}

using IndexArray = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>;

// Forward kinematics and skinning (LBS, DQS) by a palette.
void bind_skinning(py::module_& m) {
  m.def(
      "forward_kinematics",
      [](const deform::Skeleton& skeleton, const deform::Pose& pose) {
        std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
        deform::LocalToWorldJob job;
        job.skeleton = &skeleton;
        job.rotations = pose.rotations;
        job.translations = pose.translations;
        job.world = world;
        job.palette = palette;
        check(job.validate());
        check(job.run());
        return py::make_tuple(matrices_out(world), matrices_out(palette));
      },
      py::arg("skeleton"), py::arg("pose"),
      "(world, palette): (B, 4, 4) float32 row-major matrices (new arrays). world = each bone's model-space "
      "transform; palette = world · inverse bind world, what skin() takes.");

  m.def(
      "skin",
      [](const FloatArray& positions, const IndexArray& bone_indices, const FloatArray& bone_weights,
         const FloatArray& matrices, const std::string& method, std::optional<py::array> out) {
        const std::span<const glm::vec3> in = as_vec3(positions, "positions");
        if (bone_indices.ndim() != 2 || bone_indices.shape(1) != 4 ||
            static_cast<std::size_t>(bone_indices.shape(0)) != in.size())
          throw deform::Error::invalid_argument("bone_indices",
                                                "expected an array of shape (N, 4), N = len(positions)");
        if (rows_of(bone_weights, 4, "bone_weights") != in.size())
          throw deform::Error::invalid_argument("bone_weights",
                                                "expected an array of shape (N, 4), N = len(positions)");
        const std::vector<glm::mat4> palette = matrices_in(matrices);

        py::array_t<float> result;
        if (out) {
          result = py::array_t<float>::ensure(*out);
          if (!result || result.ptr() != out->ptr() || !(result.flags() & py::array::c_style) || !result.writeable() ||
              result.ndim() != 2 || result.shape(0) != static_cast<py::ssize_t>(in.size()) || result.shape(1) != 3)
            throw deform::Error::invalid_argument("out",
                                                  "expected a writeable C-contiguous float32 array of shape (N, 3)");
        } else {
          result = py::array_t<float>({static_cast<py::ssize_t>(in.size()), py::ssize_t{3}});
        }

        deform::SkinningJob job;
        job.method = method_of(method);
        job.bone_indices = {reinterpret_cast<const glm::u16vec4*>(bone_indices.data()), in.size()};
        job.bone_weights = {reinterpret_cast<const glm::vec4*>(bone_weights.data()), in.size()};
        job.in_positions = {positions.data(), 3 * in.size()};
        job.out_positions = {result.mutable_data(), 3 * in.size()};
        std::vector<deform::DualQuat> dual_quats(palette.size());
        std::vector<glm::mat3> scales(palette.size());
        if (job.method == deform::SkinningMethod::dqs) {
          bool has_scale = false;
          check(deform::compute_dual_quat_palette(palette, dual_quats, scales, has_scale));
          job.dual_quats = dual_quats;
          if (has_scale) job.scales = scales;
        } else {
          job.matrices = palette;
        }
        check(job.validate());
        {
          py::gil_scoped_release unlocked;
          check(job.run());
        }
        return result;
      },
      py::arg("positions"), py::arg("bone_indices"), py::arg("bone_weights"), py::arg("matrices"),
      py::arg("method") = "lbs", py::arg("out") = py::none(),
      "Skins (N, 3) bind positions by a palette of (B, 4, 4) row-major matrices (forward_kinematics' palette) with "
      "(N, 4) uint16 bone indices and (N, 4) float32 weights; method 'lbs' or 'dqs'. Returns a new (N, 3) array, or "
      "writes into `out` (a C-contiguous float32 (N, 3) array) and returns it. C-contiguous float32/uint16 inputs "
      "are read in place; the palette is copied (transposed to glm's layout), and converted per call for DQS.");
}

void bind_direct_delta_mush(py::module_& m) {
  py::class_<deform::DirectDeltaMushBinding, std::shared_ptr<deform::DirectDeltaMushBinding>>(
      m, "DirectDeltaMush",
      "Direct Delta Mush bound to a model (docs/skinning.md): bind_direct_delta_mush at construction (a sparse "
      "factorisation: call it at set-up), skin() per frame.")
      .def(py::init([](const deform::Model& model, int iterations, float step, float translation_blend,
                       float translation_step, float regularization, float prune) {
             const deform::DirectDeltaMushSettings settings{iterations,       step,           translation_blend,
                                                            translation_step, regularization, prune};
             return std::make_shared<deform::DirectDeltaMushBinding>(
                 deform::bind_direct_delta_mush(model.mesh, model.weights, settings));
           }),
           py::arg("model"), py::arg("iterations") = 4, py::arg("step") = 2.0f, py::arg("translation_blend") = 0.0f,
           py::arg("translation_step") = 0.5f, py::arg("regularization") = 0.05f, py::arg("prune") = 1e-3f,
           "Binds `model`'s rest points and weights; the settings as DirectDeltaMushSettings (deform.Error when out "
           "of range).")
      .def("__len__", &deform::DirectDeltaMushBinding::point_count)
      .def_property_readonly("influences", &deform::DirectDeltaMushBinding::influence_count,
                             "Influences kept over all points (after pruning).")
      .def(
          "skin",
          [](const deform::DirectDeltaMushBinding& binding, const FloatArray& matrices,
             std::optional<FloatArray> normals) -> py::object {
            const std::vector<glm::mat4> palette = matrices_in(matrices);
            const std::size_t n = binding.point_count();
            py::array_t<float> positions({static_cast<py::ssize_t>(n), py::ssize_t{3}});
            py::array_t<float> out_normals;
            deform::DirectDeltaMushJob job;
            job.binding = &binding;
            job.matrices = palette;
            job.out_positions = {reinterpret_cast<glm::vec3*>(positions.mutable_data()), n};
            if (normals) {
              job.in_normals = as_vec3(*normals, "normals");
              out_normals = py::array_t<float>({static_cast<py::ssize_t>(n), py::ssize_t{3}});
              job.out_normals = {reinterpret_cast<glm::vec3*>(out_normals.mutable_data()), n};
            }
            check(job.validate());
            {
              py::gil_scoped_release unlocked;
              check(job.run());
            }
            if (normals) return py::make_tuple(positions, out_normals);
            return positions;
          },
          py::arg("matrices"), py::arg("normals") = py::none(),
          "Skins the bound rest points by a palette of (B, 4, 4) row-major matrices (forward_kinematics' palette). "
          "Returns a new (N, 3) array, or (positions, normals) when `normals` (N, 3), one per point, is given.");
}

// IK (CCD, FABRIK, two-bone) on a pose, and the effector's position.
void bind_ik(py::module_& m) {
  py::class_<deform::IkResult>(m, "IkResult")
      .def_readonly("reached", &deform::IkResult::reached)
      .def_readonly("distance", &deform::IkResult::distance)
      .def_readonly("iterations", &deform::IkResult::iterations)
      .def("__repr__", [](const deform::IkResult& r) {
        return "IkResult(reached=" + std::string(r.reached ? "True" : "False") +
               ", distance=" + std::to_string(r.distance) + ", iterations=" + std::to_string(r.iterations) + ")";
      });

  m.def(
      "solve_ik",
      [](const deform::Skeleton& skeleton, deform::Pose& pose, const py::object& root, const py::object& effector,
         const FloatArray& target, const std::string& method, int max_iterations, float tolerance,
         std::optional<FloatArray> pole, float weight, bool limits, float soften) {
        if (pose.rotations.size() != skeleton.bone_count() || pose.translations.size() != skeleton.bone_count())
          throw deform::Error::invalid_argument("pose", "the pose does not have one entry per bone");
        deform::IkChain chain =
            deform::make_chain(skeleton, resolve_bone(skeleton, root), resolve_bone(skeleton, effector));
        if (!limits)
          for (auto& l : chain.limits) l = deform::EulerLimits{};
        deform::RigidTransform base;
        check(deform::chain_base(chain, pose.rotations, pose.translations, base));
        deform::IkResult result;
        const glm::vec3 goal = to_vec3(target, "target");
        if (method == "two_bone") {
          deform::TwoBoneIkJob job;
          job.chain = &chain;
          job.base = base;
          job.rotations = pose.rotations;
          job.translations = pose.translations;
          job.target = goal;
          if (pole) {
            job.pole = to_vec3(*pole, "pole");
            job.pole_kind = deform::PoleKind::point;
          }
          job.soften = soften;
          job.weight = weight;
          job.tolerance = tolerance;
          job.result = &result;
          check(job.validate());
          check(job.run());
        } else {
          deform::IkJob job;
          if (method == "ccd") {
            job.method = deform::IkMethod::ccd;
          } else if (method == "fabrik") {
            job.method = deform::IkMethod::fabrik;
          } else {
            throw deform::Error::invalid_argument("method", "expected 'ccd', 'fabrik' or 'two_bone'");
          }
          job.chain = &chain;
          job.base = base;
          job.rotations = pose.rotations;
          job.translations = pose.translations;
          job.target = goal;
          job.settings.max_iterations = max_iterations;
          job.settings.tolerance = tolerance;
          std::vector<double> scratch((job.scratch_size() + sizeof(double) - 1) / sizeof(double));
          job.scratch = std::as_writable_bytes(std::span<double>(scratch));
          std::uint32_t random_state = deform::ik_random_seed;
          job.random_state = &random_state;
          job.result = &result;
          if (pole) {
            job.pole = to_vec3(*pole, "pole");
            job.use_pole = true;
          }
          job.weight = weight;
          check(job.validate());
          check(job.run());
        }
        return result;
      },
      py::arg("skeleton"), py::arg("pose"), py::arg("root"), py::arg("effector"), py::arg("target"),
      py::arg("method") = "ccd", py::arg("max_iterations") = 64, py::arg("tolerance") = 1e-3f,
      py::arg("pole") = py::none(), py::arg("weight") = 1.0f, py::arg("limits") = true, py::arg("soften") = 0.0f,
      "Turns the chain root → effector (bone ids or names) of `pose` (changed in place) so that the effector's head "
      "reaches `target` (model space). method: 'ccd', 'fabrik' or 'two_bone' (exactly two joints: the effector's "
      "parent and grandparent, root = grandparent). pole: a model-space point the chain's middle bends toward. "
      "weight: blend with the input pose in [0, 1]. limits: keep the skeleton's Euler DOF limits (False: free "
      "joints; two_bone clamps its closed-form answer into them, which can move the effector off the target when "
      "the pole asks for a bend the joints do not allow). soften: two_bone's approach to full extension in [0, 1]. "
      "Returns IkResult.");

  m.def(
      "effector_position",
      [](const deform::Skeleton& skeleton, const deform::Pose& pose, const py::object& root,
         const py::object& effector) {
        const deform::IkChain chain =
            deform::make_chain(skeleton, resolve_bone(skeleton, root), resolve_bone(skeleton, effector));
        glm::vec3 p(0.0f);
        check(deform::effector_position(chain, pose.rotations, pose.translations, p));
        return py::make_tuple(p.x, p.y, p.z);
      },
      py::arg("skeleton"), py::arg("pose"), py::arg("root"), py::arg("effector"),
      "Model-space head of `effector` in `pose` (through the chain from `root`).");
}

void bind_elastic(py::module_& m) {
  py::class_<deform::ElasticLattice>(m, "ElasticLattice",
                                     "Points springing toward moving rest positions (a damped oscillator per point, "
                                     "optionally with neighbour springs on a grid).")
      .def(
          py::init([](const FloatArray& rest, float stiffness, float damping_ratio, float mass) {
            deform::ElasticSettings settings;
            settings.oscillator.stiffness = stiffness;
            settings.oscillator.damping_ratio = damping_ratio;
            settings.oscillator.mass = mass;
            deform::require_valid_settings(settings);
            return deform::ElasticLattice(as_vec3(rest, "rest"), settings);
          }),
          py::arg("rest"), py::arg("stiffness") = 150.0f, py::arg("damping_ratio") = 0.2f, py::arg("mass") = 1.0f,
          "Starts at rest on `rest` (N, 3) (copied). stiffness k > 0, damping_ratio >= 0 (< 1 under-damped), mass > 0.")
      .def(
          "step",
          [](deform::ElasticLattice& e, float dt, const FloatArray& rest) { check(e.step(dt, as_vec3(rest, "rest"))); },
          py::arg("dt"), py::arg("rest"),
          "Advances dt seconds with the points springing toward `rest` (N, 3), read in place. Raises deform.Error "
          "(kind 'status') on a wrong size or a bad dt, changing nothing.")
      .def(
          "reset", [](deform::ElasticLattice& e, const FloatArray& rest) { check(e.reset(as_vec3(rest, "rest"))); },
          py::arg("rest"), "Puts every point at rest on `rest`, with zero velocity.")
      .def("__len__", &deform::ElasticLattice::size)
      .def_property_readonly(
          "positions",
          [](py::object self) { return vec3_view(self.cast<deform::ElasticLattice&>().positions(), self, false); },
          "(N, 3) read-only view of the current positions (shares memory; updated by step()).")
      .def_property_readonly(
          "velocities",
          [](py::object self) { return vec3_view(self.cast<deform::ElasticLattice&>().velocities(), self, false); },
          "(N, 3) read-only view of the velocities.");
}

}  // namespace

std::string method_name(deform::SkinningMethod method) { return method == deform::SkinningMethod::lbs ? "lbs" : "dqs"; }
deform::SkinningMethod parse_method(const std::string& name) { return method_of(name); }

void bind_jobs(py::module_& m) {
  bind_skinning(m);
  bind_direct_delta_mush(m);
  bind_ik(m);
  bind_elastic(m);
}

}  // namespace deform_python
