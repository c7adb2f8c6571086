// The weight tools (deform/offline/weight_tools.hpp) on a Model's weights, in place, and the bone selection.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/runtime/model.hpp"

namespace deform_python {

void bind_weight_tools(py::module_& m) {
  m.def(
      "glob_match",
      [](const std::string& pattern, const std::string& name) { return deform::glob_match(pattern, name); },
      py::arg("pattern"), py::arg("name"),
      "Whether a bone name matches a shell-style glob as a whole (*, ?, [abc], [a-z], [!abc], \\c; "
      "docs/weights.md). Raises deform.Error for an unclosed [ or a trailing \\.");
  m.def(
      "select_bones",
      [](const deform::Skeleton& skeleton, const std::vector<std::string>& include,
         const std::vector<std::string>& exclude) {
        const std::vector<std::uint8_t> mask = deform::select_bones(skeleton, include, exclude);
        py::array_t<std::uint8_t> out(static_cast<py::ssize_t>(mask.size()));
        std::copy(mask.begin(), mask.end(), out.mutable_data());
        return out;
      },
      py::arg("skeleton"), py::arg("include") = std::vector<std::string>{},
      py::arg("exclude") = std::vector<std::string>{},
      "The deforming-bone mask (uint8 per bone): bones matching a glob of `include` (all when empty) and none of "
      "`exclude`. Raises deform.Error naming a glob that matches no bone, or when no bone is left.");
  m.def(
      "mirrored_bone_name",
      [](const std::string& name, const std::vector<std::pair<std::string, std::string>>& pairs) {
        return deform::mirrored_bone_name(name, pairs);
      },
      py::arg("name"), py::arg("pairs") = std::vector<std::pair<std::string, std::string>>{},
      "The name of a bone's mirror partner (.L/.R, _l/_r, L_/R_, Left/Right swapped; or the given (A, B) text "
      "pairs), None for a middle bone.");
  m.def(
      "normalize_weights", [](deform::Model& model) { deform::normalize_weights(model.weights); }, py::arg("model"),
      "Scales each point's weights to sum 1 (in place).");
  m.def(
      "prune_weights",
      [](deform::Model& model, float threshold) { return deform::prune_weights(model.weights, threshold); },
      py::arg("model"), py::arg("threshold"),
      "Drops the influences below `threshold` (0 to 1) and renormalises, in place; a point keeps its strongest. "
      "Returns the number of influences removed.");
  m.def(
      "limit_influences",
      [](deform::Model& model, int count) { return deform::limit_influences(model.weights, count); }, py::arg("model"),
      py::arg("count"),
      "Keeps each point's `count` strongest influences, renormalised, in place. Returns the number of points that "
      "lost some.");
  m.def(
      "smooth_weights",
      [](deform::Model& model, int iterations, float factor, int max_influences) {
        deform::SmoothWeightsOptions o;
        o.iterations = iterations;
        o.factor = factor;
        o.max_influences = max_influences;
        deform::smooth_weights(model.weights, model.mesh, o);
      },
      py::arg("model"), py::arg("iterations") = 1, py::arg("factor") = 0.5f, py::arg("max_influences") = 4,
      "Smooths the weights over the model's surface, in place: each pass, (1 - factor) of a point's own weights "
      "plus `factor` of its neighbours' mean; points at the same position move together; then the strongest "
      "`max_influences` are kept.");
  m.def(
      "weight_gradient_energy",
      [](const deform::Model& model) { return deform::weight_gradient_energy(model.weights, model.mesh); },
      py::arg("model"),
      "Sum over the mesh's edges and the bones of the squared weight differences: what smooth_weights lowers.");
  m.def(
      "mirror_weights",
      [](deform::Model& model, const std::string& mode, const std::optional<std::string>& axis,
         std::optional<float> plane, std::optional<float> tolerance,
         const std::vector<std::pair<std::string, std::string>>& pairs) {
        deform::MirrorWeightsOptions o;
        if (mode == "flip") {
          o.mode = deform::MirrorMode::flip;
        } else if (mode == "positive-to-negative") {
          o.mode = deform::MirrorMode::from_positive;
        } else if (mode == "negative-to-positive") {
          o.mode = deform::MirrorMode::from_negative;
        } else {
          throw deform::Error::invalid_argument("mode '" + mode + "'",
                                                "expected flip, positive-to-negative or negative-to-positive");
        }
        if (axis) {
          if (*axis != "x" && *axis != "y" && *axis != "z")
            throw deform::Error::invalid_argument("axis '" + *axis + "'", "expected x, y or z");
          o.axis = (*axis)[0] - 'x';
        }
        o.plane = plane;
        if (tolerance) {
          if (!(*tolerance > 0.0f)) throw deform::Error::invalid_argument("tolerance", "must be > 0");
          o.tolerance = *tolerance;
        }
        o.name_pairs = pairs;
        deform::MirrorWeightsResult r = deform::mirror_weights(model.weights, model.mesh, model.skeleton, o);
        model.weights = std::move(r.weights);
        py::dict out;
        out["axis"] = std::string(1, static_cast<char>('x' + r.axis));
        out["plane"] = r.plane;
        out["bone_pairs"] = r.bone_pairs;
        out["points"] = r.points;
        return out;
      },
      py::arg("model"), py::arg("mode") = "flip", py::arg("axis") = py::none(), py::arg("plane") = py::none(),
      py::arg("tolerance") = py::none(), py::arg("pairs") = std::vector<std::pair<std::string, std::string>>{},
      "Mirrors the weights left <-> right, in place (docs/weights.md, \"Weight tools\"): mode 'flip', "
      "'positive-to-negative' or 'negative-to-positive'; axis 'x', 'y' or 'z' (default: found from the bone "
      "pairs). Returns {axis, plane, bone_pairs, points}. Raises deform.Error for a weighted bone without partner "
      "or a point without mirror.");
}

}  // namespace deform_python
