#pragma once
// The weight tools (weights.cpp): automatic weights again and `deform weights-edit`'s tools (normalise, prune, limit,
// smooth, mirror) run on the character's weights at a click of the panel's "Weights" section or from --weights-tool,
// the character bound again with the result, so the weight map shows it at once.
#include <string>

#include "state.hpp"

namespace viewer {

// What `tool` is, in the panel's words ("smooth 2 passes x0.5").
std::string describe(const WeightTool& tool);

// Runs `tool` on the character's current weights (heat: on its mesh and skeleton; revert: the model's own) and binds
// the character again with the result (rebind_weights). Offline work: it allocates and may take a moment (heat on a
// large mesh). Returns false when the tool (or the rig, with the new weights) refuses: the weights and the character
// are then unchanged. Either way state.weights_message says what happened or why, for the panel.
bool run_weight_tool(ViewerState& state, const WeightTool& tool);

// The options' tools in order (a refusal is reported on stderr and the next tool runs), then --save-weights; run
// once the character, the scene and the options' deformation settings are in place, as a click would find them.
// Exits (fail) when the weights cannot be written.
void run_option_weight_tools(ViewerState& state);

}  // namespace viewer
