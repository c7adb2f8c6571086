// Skeletons and poses: bone lookup by id or name, DOF limits, Euler angles, the bind pose.
#include <string>
#include <vector>

#include "common.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform_python {

std::int32_t resolve_bone(const deform::Skeleton& skeleton, const py::object& bone) {
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

void bind_skeleton(py::module_& m) {
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
            const deform::DofLimits& l = s.bone(resolve_bone(s, bone)).limits;
            return py::make_tuple(py::make_tuple(l.min.x, l.min.y, l.min.z), py::make_tuple(l.max.x, l.max.y, l.max.z));
          },
          py::arg("bone"), "(min, max) Euler limits in degrees (X, Y, Z) of a bone (id or name).")
      .def(
          "within_limits",
          [](const deform::Skeleton& s, const deform::Pose& pose, const py::object& bone, float slack) {
            const std::int32_t id = resolve_bone(s, bone);
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
            const glm::vec3 set = s.set_euler(pose, resolve_bone(s, bone), to_vec3(degrees, "degrees"), clamp);
            return py::make_tuple(set.x, set.y, set.z);
          },
          py::arg("pose"), py::arg("bone"), py::arg("degrees"), py::arg("clamp") = true,
          "Sets a bone's rotation in `pose` from Euler X·Y·Z degrees, clamped into its limits unless clamp=False; "
          "returns the angles set.");
}

}  // namespace deform_python
