// Animation clips and pose blending: sampling, blending with masks, additive layers, root motion.
#include <string>
#include <vector>

#include "common.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"

namespace deform_python {

void bind_animation(py::module_& m) {
  py::class_<deform::Animation>(m, "Animation", "An imported clip: per-bone tracks (deform::Animation).")
      .def_readonly("name", &deform::Animation::name)
      .def_readonly("duration", &deform::Animation::duration, "seconds")
      .def_readwrite("loop", &deform::Animation::loop, "sampling wraps time when True, clamps it otherwise")
      .def_property_readonly(
          "morph_channel_targets",
          [](const deform::Animation& clip) {
            std::vector<std::int32_t> targets;
            for (const deform::MorphChannel& c : clip.morph_channels) targets.push_back(c.target);
            return targets;
          },
          "The morph targets the clip animates, one per morph channel.")
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
}

// deform/runtime/blending.hpp, docs/animation.md.
void bind_blending(py::module_& m) {
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
}

}  // namespace deform_python
