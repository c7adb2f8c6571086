// Pose-space correctives (deform/runtime/pose_driver.hpp, deform/offline/pose_driver.hpp): a corrective shape from a
// sculpt, the pose driver that turns shapes on near their poses, and the Character's hook.
#include <string>
#include <vector>

#include "common.hpp"
#include "deform/character/character.hpp"
#include "deform/offline/pose_driver.hpp"

namespace deform_python {

namespace {

deform::RbfKernel kernel_of(const std::string& name) {
  if (name == "gaussian") return deform::RbfKernel::gaussian;
  if (name == "inverse_multiquadric") return deform::RbfKernel::inverse_multiquadric;
  throw deform::Error::invalid_argument("kernel", "expected \"gaussian\" or \"inverse_multiquadric\"");
}

}  // namespace

void bind_correctives(py::module_& m) {
  py::class_<deform::PoseDriverBinding>(m, "PoseDriver",
                                        "An RBF from driver bones' rotations to shape weights (bind_pose_driver).")
      .def_property_readonly("shape_count", [](const deform::PoseDriverBinding& d) { return d.shape_count; })
      .def_property_readonly("pose_count", [](const deform::PoseDriverBinding& d) { return d.pose_count(); })
      .def_readonly("radius", &deform::PoseDriverBinding::radius)
      .def_readonly("bones", &deform::PoseDriverBinding::bones)
      .def(
          "weights",
          [](const deform::PoseDriverBinding& d, const deform::Pose& pose) {
            py::array_t<float> out(static_cast<py::ssize_t>(d.shape_count));
            deform::PoseDriverJob job;
            job.binding = &d;
            job.rotations = pose.rotations;
            job.weights = std::span<float>(out.mutable_data(), d.shape_count);
            check(job.validate());
            check(job.run());
            return out;
          },
          py::arg("pose"), "The shapes' weights at `pose` (float32, one per shape).");

  m.def(
      "bind_pose_driver",
      [](const deform::Skeleton& skeleton, const py::list& bones, const std::vector<deform::Pose>& samples,
         const FloatArray& targets, const std::string& kernel, float radius, float twist_weight, float regularization,
         bool clamp) {
        std::vector<std::int32_t> ids;
        for (const py::handle bone : bones)
          ids.push_back(resolve_bone(skeleton, py::reinterpret_borrow<py::object>(bone)));
        if (targets.ndim() != 2 || static_cast<std::size_t>(targets.shape(0)) != samples.size())
          throw deform::Error::invalid_argument("targets", "expected an array of shape (samples, shapes)");
        deform::PoseDriverSettings settings;
        settings.kernel = kernel_of(kernel);
        settings.radius = radius;
        settings.twist_weight = twist_weight;
        settings.regularization = regularization;
        settings.clamp = clamp;
        return deform::bind_pose_driver(
            skeleton, ids, samples, std::span<const float>(targets.data(), static_cast<std::size_t>(targets.size())),
            static_cast<std::size_t>(targets.shape(1)), settings);
      },
      py::arg("skeleton"), py::arg("bones"), py::arg("samples"), py::arg("targets"), py::arg("kernel") = "gaussian",
      py::arg("radius") = 0.0f, py::arg("twist_weight") = 1.0f, py::arg("regularization") = 0.0f,
      py::arg("clamp") = true,
      "Solves a pose driver: `bones` (names or ids) read from each of the sample Poses, `targets` (samples, shapes) "
      "their shapes' weights; kernel \"gaussian\" or \"inverse_multiquadric\", radius 0 picks it (docs/skinning.md, "
      "\"Pose-space correctives\"). Raises deform.Error naming what is wrong.");
  m.def(
      "add_corrective",
      [](deform::Model& model, const FloatArray& palette, const FloatArray& sculpted, float tolerance,
         const std::string& name) {
        const std::vector<glm::mat4> matrices = matrices_in(palette);
        model.morph_targets.push_back(
            deform::corrective_from_sculpt(model, matrices, as_vec3(sculpted, "sculpted"), tolerance, name));
        return model.morph_targets.size() - 1;
      },
      py::arg("model"), py::arg("palette"), py::arg("sculpted"), py::arg("tolerance") = 0.0f,
      py::arg("name") = "corrective",
      "Appends to the model the morph target that puts its points at `sculpted` (N, 3) under linear blend skinning by "
      "`palette` (B, 4, 4, as forward_kinematics or Character.palette give it); returns the target's index. Build "
      "the Character after adding it.");
}

}  // namespace deform_python
