#pragma once
// The ImGui panel (panel.cpp): a few lines of status, then collapsible sections (display, clip, elastic lattices,
// skinning and GPU, reach, morph targets, spring chains, scene), each a function of its own.
#include "state.hpp"

namespace viewer {

// The panel for this frame (nothing with --bare); `frame_ms` is the frame time shown.
void panel(ViewerState& state, float frame_ms);
// A frame that took `took` seconds was simulated as `simulated` (the main loop's clamp): the panel says so.
void note_long_frame(ViewerState& state, float took, float simulated);

}  // namespace viewer
