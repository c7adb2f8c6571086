// The weight tools at a click: each runs offline on the character's weights (never per frame), and the character is
// bound again with the result (model.cpp's rebind_weights), keeping its rig, settings and clip.
#include "weights.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <utility>

#include "deform/io/sk.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/runtime/error.hpp"
#include "model.hpp"

namespace viewer {
namespace {

const char* mirror_modes[] = {"flip", "positive-to-negative", "negative-to-positive"};

std::size_t most_influences(const deform::SkinWeights& weights) {
  std::size_t most = 0;
  for (std::size_t p = 0; p < weights.size(); ++p) most = std::max(most, deform::influence_count(weights, p));
  return most;
}

// The tool's result, or a deform::Error (the tool's refusal) thrown; `done` says what it did beyond its name.
deform::SkinWeights apply(const ViewerState& state, const WeightTool& tool, std::string& done) {
  const deform::Model& model = state.base_model;
  deform::SkinWeights weights = model.weights;
  char text[160];
  switch (tool.kind) {
    case WeightTool::Kind::heat: {
      // The bones the model's own weights use deform (`deform weights --deform-bones used`): a rig's IK goals and
      // helper bones, which no artist weights, stay unweighted.
      deform::HeatWeightsOptions options;
      options.heat = tool.value;
      options.deforming = deform::weighted_bones(state.own_weights, model.skeleton.bone_count());
      if (std::find(options.deforming.begin(), options.deforming.end(), 1) == options.deforming.end())
        options.deforming.clear();
      deform::WeightsResult result = deform::compute_heat_weights(model.mesh, model.skeleton, options);
      for (const std::string& w : result.warnings) std::fprintf(stderr, "warning: automatic weights: %s\n", w.c_str());
      std::snprintf(text, sizeof text, "%zu warnings (stderr)", result.warnings.size());
      if (!result.warnings.empty()) done = text;
      return std::move(result.weights);
    }
    case WeightTool::Kind::normalize: deform::normalize_weights(weights); return weights;
    case WeightTool::Kind::prune:
      std::snprintf(text, sizeof text, "%zu influences removed", deform::prune_weights(weights, tool.value));
      done = text;
      return weights;
    case WeightTool::Kind::limit:
      std::snprintf(text, sizeof text, "%zu points lost influences", deform::limit_influences(weights, tool.count));
      done = text;
      return weights;
    case WeightTool::Kind::smooth: {
      // As `deform weights-edit --smooth`: as many influences kept as the weights had, at least four.
      deform::SmoothWeightsOptions options;
      options.iterations = tool.count;
      options.factor = tool.value;
      options.max_influences = int(std::max<std::size_t>(most_influences(weights), deform::max_influences));
      deform::smooth_weights(weights, model.mesh, options);
      return weights;
    }
    case WeightTool::Kind::mirror: {
      deform::MirrorWeightsOptions options;
      options.mode = tool.mirror == 1   ? deform::MirrorMode::from_positive
                     : tool.mirror == 2 ? deform::MirrorMode::from_negative
                                        : deform::MirrorMode::flip;
      deform::MirrorWeightsResult result = deform::mirror_weights(weights, model.mesh, model.skeleton, options);
      std::snprintf(text, sizeof text, "axis %c, %zu bone pairs, %zu points", char('x' + result.axis),
                    result.bone_pairs, result.points);
      done = text;
      return std::move(result.weights);
    }
    case WeightTool::Kind::revert: return state.own_weights;
  }
  return weights;
}

}  // namespace

std::string describe(const WeightTool& tool) {
  char text[96];
  switch (tool.kind) {
    case WeightTool::Kind::heat: std::snprintf(text, sizeof text, "heat weights (heat %g)", double(tool.value)); break;
    case WeightTool::Kind::normalize: return "normalize";
    case WeightTool::Kind::prune: std::snprintf(text, sizeof text, "prune below %g", double(tool.value)); break;
    case WeightTool::Kind::limit: std::snprintf(text, sizeof text, "limit to %d", tool.count); break;
    case WeightTool::Kind::smooth:
      std::snprintf(text, sizeof text, "smooth %d passes x%g", tool.count, double(tool.value));
      break;
    case WeightTool::Kind::mirror: return std::string("mirror ") + mirror_modes[std::clamp(tool.mirror, 0, 2)];
    case WeightTool::Kind::revert: return "revert to the model's weights";
  }
  return text;
}

bool run_weight_tool(ViewerState& state, const WeightTool& tool) {
  std::string done;
  try {
    rebind_weights(state, apply(state, tool, done));
  } catch (const deform::Error& e) {  // the tool's refusal, or the rig's with the new weights: nothing changed
    state.weights_message = describe(tool) + " refused: " + e.what();
    state.weights_refused = true;
    ++state.weight_tools_refused;
    return false;
  }
  char most[64];
  std::snprintf(most, sizeof most, "at most %zu influences", most_influences(state.base_model.weights));
  state.weights_message = describe(tool) + ": " + (done.empty() ? std::string() : done + ", ") + most;
  state.weights_refused = false;
  ++state.weight_tools_run;
  // The panel's controls take the settings last run (--weights-tool's among them).
  if (tool.kind == WeightTool::Kind::heat) state.heat_tool = tool;
  if (tool.kind == WeightTool::Kind::prune) state.prune_tool = tool;
  if (tool.kind == WeightTool::Kind::limit) state.limit_tool = tool;
  if (tool.kind == WeightTool::Kind::smooth) state.smooth_tool = tool;
  return true;
}

void run_option_weight_tools(ViewerState& state) {
  for (const WeightTool& tool : state.options.weight_tools)
    if (!run_weight_tool(state, tool))
      std::fprintf(stderr, "deform_viewer: --weights-tool %s; the weights are kept\n", state.weights_message.c_str());
  if (!state.options.save_weights.empty()) {
    try {
      deform::write_skw(state.options.save_weights, state.base_model.weights);
    } catch (const std::exception& e) {
      fail("--save-weights: " + std::string(e.what()));
    }
  }
}

}  // namespace viewer
