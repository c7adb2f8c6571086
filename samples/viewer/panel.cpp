// The ImGui panel, one function per section; each control calls into the model (model.hpp) or the scene (view.hpp).
#include "panel.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <imgui.h>

#include "model.hpp"
#include "view.hpp"
#include "weights.hpp"

namespace viewer {
namespace {

// The status lines: the model, the frame and deformation times, a frame longer than the clamp, the stretch.
void status_lines(ViewerState& state, float frame_ms) {
  const glm::ivec2 size = state.window.framebuffer_size();
  // What the panel hides on the left, for the next fit of the camera (none when collapsed or moved elsewhere).
  const ImVec2 panel_at = ImGui::GetWindowPos(), panel_size = ImGui::GetWindowSize();
  state.panel_right =
      !ImGui::IsWindowCollapsed() && panel_at.x < 0.3f * float(size.x) ? panel_at.x + panel_size.x + 10.0f : 0.0f;
  ImGui::Text("%s: %zu points, %zu bones", state.base_model.name.c_str(), state.base_model.mesh.point_count(),
              state.base_model.skeleton.bone_count());
  ImGui::Text("frame %.2f ms, deformation %.3f ms", frame_ms, state.deform_ms);
  // A frame longer than the clamp is simulated short: say so for a while rather than show it as slow motion.
  if (Clock::now() - state.long_frame_at < std::chrono::seconds(2))
    ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "frame took %.0f ms: simulated %.0f ms", state.long_frame_ms,
                       state.long_frame_simulated_ms);
  ImGui::TextDisabled("click: reach, right drag: orbit, C: camera");
  if (state.reaching || state.character->stretch() != 0.0f)
    ImGui::Text("stretch %.3f, residual %.3f", state.character->stretch(), state.last_reach.residual);
}

// Display: the skeleton, the lattices (the active limb's or all).
void display_section(ViewerState& state) {
  if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("skeleton", &state.show_skeleton);
    ImGui::SameLine();
    // The lattices of the limb in use only (reaching, else under the mouse), or every one (L cycles the three).
    bool shown = state.lattice_display != LatticeDisplay::none, all = state.lattice_display == LatticeDisplay::all;
    bool display_changed = ImGui::Checkbox("lattices", &shown);
    ImGui::SameLine();
    ImGui::BeginDisabled(!shown);
    display_changed |= ImGui::Checkbox("all lattices", &all);
    ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("every lattice; else only the limb that reaches, or would reach from under the mouse (L)");
    if (display_changed)
      state.lattice_display = !shown ? LatticeDisplay::none : all ? LatticeDisplay::all : LatticeDisplay::active;
  }
}

// Weights: the weight map (one bone's weights painted on the surface) and the tools that change the weights, each
// run at a click on the character's current weights, the character bound again with the result (weights.cpp); a
// tool's refusal is shown in red and changes nothing. Open from the start when the command line asked for a map or a
// tool.
void weights_section(ViewerState& state) {
  const bool asked = state.weight_bone >= 0 || !state.options.weight_tools.empty();
  if (!ImGui::CollapsingHeader("Weights", asked ? ImGuiTreeNodeFlags_DefaultOpen : 0)) return;
  const deform::Skeleton& sk = state.character->skeleton();
  std::vector<std::string> keys{"(none)"};
  for (std::size_t b = 0; b < sk.bone_count(); ++b) keys.push_back(sk.key(std::int32_t(b)));
  std::vector<const char*> names;
  for (const std::string& k : keys) names.push_back(k.c_str());
  int selected = state.weight_bone + 1;
  if (ImGui::Combo("weights of", &selected, names.data(), int(names.size()))) state.weight_bone = selected - 1;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the bone's weight painted on the surface: blue 0, green 0.5, red 1");
  std::optional<WeightTool> run;
  constexpr float slider = 150.0f;
  ImGui::SetNextItemWidth(slider);
  ImGui::SliderFloat("##heat", &state.heat_tool.value, 0.1f, 10.0f, "heat %.2f",
                     ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
  ImGui::SameLine();
  if (ImGui::Button("automatic")) run = state.heat_tool;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "bone heat weights again, with this heat constant (higher: sharper joints), on the bones\n"
        "the model's own weights use");
  ImGui::SetNextItemWidth(slider);
  ImGui::SliderFloat("##prune", &state.prune_tool.value, 0.0f, 0.5f, "below %.3f", ImGuiSliderFlags_AlwaysClamp);
  ImGui::SameLine();
  if (ImGui::Button("prune")) run = state.prune_tool;
  ImGui::SetNextItemWidth(slider);
  ImGui::SliderInt("##limit", &state.limit_tool.count, 1, 16, "%d influences", ImGuiSliderFlags_AlwaysClamp);
  ImGui::SameLine();
  if (ImGui::Button("limit")) run = state.limit_tool;
  ImGui::SetNextItemWidth(0.5f * slider - 4.0f);
  ImGui::SliderInt("##passes", &state.smooth_tool.count, 1, 100, "%d passes", ImGuiSliderFlags_AlwaysClamp);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(0.5f * slider - 4.0f);
  ImGui::SliderFloat("##factor", &state.smooth_tool.value, 0.05f, 1.0f, "x%.2f", ImGuiSliderFlags_AlwaysClamp);
  ImGui::SameLine();
  if (ImGui::Button("smooth")) run = state.smooth_tool;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("each pass: (1 - x) own weights + x the neighbours' mean");
  ImGui::TextUnformatted("mirror");
  static const char* const mirror_labels[] = {"flip", "+ to -", "- to +"};
  static const char* const mirror_tips[] = {"each point takes its mirror point's weights, sides swapped",
                                            "the positive side's weights, mirrored, onto the negative side",
                                            "the negative side's weights, mirrored, onto the positive side"};
  for (int m = 0; m < 3; ++m) {
    ImGui::SameLine();
    if (ImGui::Button(mirror_labels[m])) run = WeightTool{WeightTool::Kind::mirror, 0.0f, 0, m};
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s (by bone names: .L/.R, _l/_r, Left/Right)", mirror_tips[m]);
  }
  if (ImGui::Button("normalize")) run = WeightTool{WeightTool::Kind::normalize, 0.0f, 0, 0};
  ImGui::SameLine();
  if (ImGui::Button("revert")) run = WeightTool{WeightTool::Kind::revert, 0.0f, 0, 0};
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the model's own weights, as loaded");
  if (run) run_weight_tool(state, *run);
  if (!state.weights_message.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, state.weights_refused ? ImVec4(1.0f, 0.35f, 0.3f, 1.0f)
                                                               : ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
    ImGui::TextWrapped("%s", state.weights_message.c_str());
    ImGui::PopStyleColor();
  }
}

// Clip: which, play/pause, speed, the blended second clip and its weight, the jiggle and its inertia.
void clip_section(ViewerState& state) {
  if (!state.clips.empty() && ImGui::CollapsingHeader("Clip", ImGuiTreeNodeFlags_DefaultOpen)) {
    int selected = state.clip + 1;
    if (ImGui::Combo("clip", &selected, state.clip_names.data(), int(state.clip_names.size())))
      select_clip(state, selected - 1);
    ImGui::BeginDisabled(state.clip < 0);
    if (ImGui::Button(state.playing ? "pause" : "play")) state.playing = !state.playing;
    ImGui::SameLine();
    ImGui::Text("%.2f s", state.clip >= 0 ? state.clip_time : 0.0f);
    ImGui::SliderFloat("speed", &state.speed, 0.0f, 2.0f, "%.2fx", ImGuiSliderFlags_AlwaysClamp);
    // A second clip blended with the first by weight, following its phase (BlendingJob).
    int with = state.blend_clip + 1;
    if (ImGui::Combo("blend with", &with, state.clip_names.data(), int(state.clip_names.size())))
      state.blend_clip = with - 1;
    ImGui::BeginDisabled(state.blend_clip < 0);
    ImGui::SliderFloat("blend", &state.blend_weight, 0.0f, 1.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    ImGui::EndDisabled();
    // The jiggle: the lattices lag behind their bones while the clip plays, each part's tuned inertia times the
    // slider (DeformerHierarchy::set_inertia_scale): at 1 the tuned jiggle, limbs keeping their length.
    bool motion = ImGui::Checkbox("jiggle", &state.jiggle);
    ImGui::SameLine();
    ImGui::BeginDisabled(!state.jiggle);
    ImGui::SetNextItemWidth(140.0f);
    motion |= ImGui::SliderFloat("inertia", &state.inertia, 0.0f, 1.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
    ImGui::EndDisabled();
    if (motion) apply_motion(state);
    ImGui::EndDisabled();
  }
}

// Elastic lattices: stiffness, damping, integrator, degree (a rebuild), the rubber's shape, the stretch bound.
void lattices_section(ViewerState& state) {
  char title[64];
  std::snprintf(title, sizeof title, "Elastic lattices (%zu)###lattices", state.character->deformers().lattice_count());
  if (ImGui::CollapsingHeader(title, ImGuiTreeNodeFlags_DefaultOpen)) {
    bool changed = ImGui::SliderFloat("stiffness k", &state.elastic.oscillator.stiffness, 5.0f, 1000.0f, "%.0f",
                                      ImGuiSliderFlags_Logarithmic);
    changed |= ImGui::SliderFloat("damping ratio", &state.elastic.oscillator.damping_ratio, 0.0f, 2.0f);
    int integrator = state.elastic.integrator == deform::Integrator::verlet;
    changed |= ImGui::RadioButton("exact", &integrator, 0);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("frame-rate independent");
    ImGui::SameLine();
    changed |= ImGui::RadioButton("Verlet, constant Kd", &integrator, 1);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("the seed's integrator");
    state.elastic.integrator = integrator ? deform::Integrator::verlet : deform::Integrator::exact;
    if (changed) apply_elastic(state);
    if (ImGui::SliderInt("lattice degree", &state.degree, 1, 6)) rebuild_character(state);
    // The rubber's shape: a limb never shorter than `min length` of its rest, its cross-section thinning as it
    // stretches (volume 1: the volume kept) and bulging as it shortens.
    bool shaped = ImGui::SliderFloat("volume", &state.shape.volume, 0.0f, 1.0f);
    shaped |= ImGui::SliderFloat("min length", &state.shape.min_length_fraction, 0.0f, 1.0f);
    if (shaped) apply_shape(state);
    if (ImGui::SliderFloat("max stretch", &state.max_stretch, 0.0f, 10.0f)) apply_reach_settings(state);
  }
}

// Skinning and GPU: LBS, DQS or DDM, Delta Mush iterations, the GPU deformation.
void skinning_section(ViewerState& state) {
  if (ImGui::CollapsingHeader("Skinning and GPU")) {
    // LBS and DQS are Character::settings.skinning; DDM binds Direct Delta Mush, which takes precedence over it.
    int method = state.ddm ? 2 : state.character->settings.skinning == deform::SkinningMethod::dqs;
    bool method_changed = ImGui::RadioButton("LBS", &method, 0);
    ImGui::SameLine();
    method_changed |= ImGui::RadioButton("DQS", &method, 1);
    ImGui::SameLine();
    method_changed |= ImGui::RadioButton("DDM", &method, 2);
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("Direct Delta Mush: smooth bends without LBS's collapse; bound on first use, CPU only");
    }
    if (method_changed) {
      if (method < 2)
        state.character->settings.skinning = method ? deform::SkinningMethod::dqs : deform::SkinningMethod::lbs;
      state.ddm = method == 2;
      apply_mush(state);
    }
    if (ImGui::SliderInt("Delta Mush iterations", &state.mush_iterations, 0, 50)) apply_mush(state);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("smoothing after the lattices, detail kept; 0: off; CPU only");
    bool gpu = state.gpu;
    ImGui::BeginDisabled(!state.gpu_available);
    if (ImGui::Checkbox("GPU deformation", &gpu)) set_gpu(state, gpu);
    ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) {
      ImGui::SetTooltip("%s", state.gpu_available ? "skinning and Bezier fields in compute shaders, into the vertex "
                                                    "buffer; the CPU only poses (deformation time: the CPU's part)"
                                                  : gpu_missing(state).c_str());
    }
  }
}

// Levels of detail (--lod): the level shown, picked from the screen or chosen, and what each level deforms.
void lod_section(ViewerState& state) {
  if (!state.lod_levels || !ImGui::CollapsingHeader("Level of detail", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const char* choices[] = {"auto (height on screen)", "0: whole", "1", "2", "3"};
  int choice = state.lod_choice + 1;
  if (ImGui::Combo("level", &choice, choices, 5)) state.lod_choice = choice - 1;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("auto: level 1 below 1/2 of the window's height, 2 below 1/4, 3 below 1/8 (zoom out to see it)");
  if (!ImGui::BeginTable("levels", 6, ImGuiTableFlags_SizingFixedFit)) return;
  for (const char* heading : {"", "bones", "points", "triangles", "every", "deformers"})
    ImGui::TableSetupColumn(heading);
  ImGui::TableHeadersRow();
  for (std::size_t l = 0; l < 4; ++l) {
    const deform::Character::LevelCost cost = state.character->level_cost(l);
    const std::size_t triangles = state.lod_triangles[l].empty() ? state.character->model().mesh.triangle_count()
                                                                 : state.lod_triangles[l].size() / 3;
    ImGui::TableNextRow();
    ImGui::TableNextColumn(), ImGui::Text("%s%zu", int(l) == state.lod_drawn ? ">" : " ", l);
    ImGui::TableNextColumn(), ImGui::Text("%zu", cost.bones);
    ImGui::TableNextColumn(), ImGui::Text("%zu", cost.points);
    ImGui::TableNextColumn(), ImGui::Text("%zu", triangles);
    ImGui::TableNextColumn(), ImGui::Text("%u", unsigned(cost.update_interval));
    ImGui::TableNextColumn(), ImGui::Text("%s", cost.deformers ? "on" : "off");
  }
  ImGui::EndTable();
}

// Reach: the stall escape, iterations, solver, pole, swing-twist limits.
void reach_section(ViewerState& state) {
  if (ImGui::CollapsingHeader("Reach")) {
    ImGui::Checkbox("escape IK stalls", &state.character->settings.ik.escape_stalls);
    ImGui::SliderInt("IK iterations", &state.character->settings.ik.max_iterations, 1, 256);
    int solver = state.reach_solver == deform::Character::ReachSolver::two_bone;
    bool reach_changed = ImGui::RadioButton("CCD chain", &solver, 0);
    ImGui::SameLine();
    reach_changed |= ImGui::RadioButton("two-bone limb", &solver, 1);
    state.reach_solver = solver ? deform::Character::ReachSolver::two_bone : deform::Character::ReachSolver::ccd;
    ImGui::BeginDisabled(!solver);
    reach_changed |= ImGui::SliderFloat("soften", &state.soften, 0.0f, 1.0f);
    ImGui::EndDisabled();
    reach_changed |= ImGui::Checkbox("pole", &state.use_pole);
    ImGui::SameLine();
    ImGui::TextDisabled("(shift+click places it)");
    reach_changed |= ImGui::DragFloat3("pole at", &state.pole.x, 0.01f);
    bool swing_twist = state.character->settings.reach_limits == deform::Character::JointLimits::swing_twist;
    if (ImGui::Checkbox("swing-twist limits", &swing_twist)) {
      state.reach_limits =
          swing_twist ? deform::Character::JointLimits::swing_twist : deform::Character::JointLimits::euler;
      reach_changed = true;
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "each joint of the reach chain limited by a twist range and a swing cone (drawn in cyan)\n"
          "made from its Euler limits, instead of the Euler box");
    if (reach_changed) apply_reach_settings(state);
  }
}

// Morph targets: each weight as a slider, held when moved, "follow the clip" releases them.
void morph_section(ViewerState& state) {
  if (state.character->morph_target_count() > 0) {  // the morph targets' weights: the clip's, unless held here
    char title[64];
    // Open by default for a handful of targets (they are then what the model is about); a long list starts closed.
    std::snprintf(title, sizeof title, "Morph targets (%zu)###morphs", state.character->morph_target_count());
    if (ImGui::CollapsingHeader(title,
                                state.character->morph_target_count() <= 8 ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
      if (ImGui::SmallButton("follow the clip")) std::fill(state.morph_held.begin(), state.morph_held.end(), char(0));
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("every weight from the playing clip again (else its default)");
      const std::vector<deform::MorphTarget>& targets = state.character->model().morph_targets;
      // Targets a pose driver sets (a rig's correctives): each update() gives them their weight from the pose, so
      // they are shown as that weight, live, and cannot be held.
      std::vector<char> driven(targets.size(), 0);
      for (std::size_t d = 0; d < state.character->pose_driver_count(); ++d)
        for (const std::uint32_t t : state.character->pose_driver_targets(d)) driven[t] = 1;
      for (std::size_t k = 0; k < targets.size(); ++k) {
        ImGui::PushID(int(k));
        if (driven[k]) {
          const float weight = state.character->morph_weights()[k];
          char value[32];
          std::snprintf(value, sizeof value, "%.2f", double(weight));
          ImGui::ProgressBar(weight, ImVec2(ImGui::CalcItemWidth() + ImGui::GetFrameHeight(), 0.0f), value);
          ImGui::SameLine();
          ImGui::TextUnformatted((targets[k].name.empty() ? "target " + std::to_string(k) : targets[k].name).c_str());
          if (ImGui::IsItemHovered()) ImGui::SetTooltip("a corrective: its pose driver sets the weight from the pose");
          ImGui::PopID();
          continue;
        }
        bool held = state.morph_held[k] != 0;
        float weight = state.character->morph_weights()[k];
        if (ImGui::Checkbox("##held", &held)) state.morph_held[k] = held, state.morph_hold[k] = weight;
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("held: the slider's weight; else the clip's (or the default)");
        ImGui::SameLine();
        const std::string label = targets[k].name.empty() ? "target " + std::to_string(k) : targets[k].name;
        if (ImGui::SliderFloat(label.c_str(), &weight, 0.0f, 1.0f, "%.2f")) {
          state.morph_held[k] = 1;
          state.morph_hold[k] = weight;
          apply_morph_weights(state);
        }
        if (ImGui::IsItemHovered() && !targets[k].mesh.empty()) ImGui::SetTooltip("mesh %s", targets[k].mesh.c_str());
        ImGui::PopID();
      }
    }
  }
}

// Spring chains: each chain's frequency, damping and gravity.
void springs_section(ViewerState& state) {
  char title[64];
  deform::SpringChains& springs = state.character->springs();
  std::snprintf(title, sizeof title, "Spring chains (%zu)###springs", springs.chain_count());
  if (springs.chain_count() > 0 && ImGui::CollapsingHeader(title)) {  // drawn in green with the skeleton
    for (std::size_t c = 0; c < springs.chain_count(); ++c) {
      // Tuned in the viewer's copy of the rig, so a rebuilt character keeps the settings; clamped, since
      // set_settings throws on a value out of range (a ctrl+click can type one).
      deform::SpringChainSpec& spec = state.rig.spring_chains[c];
      float gravity = glm::length(spec.gravity);
      ImGui::PushID(int(c));
      ImGui::TextDisabled("%s", spec.name.c_str());
      bool tuned = ImGui::SliderFloat("frequency", &spec.frequency, 0.1f, 10.0f, "%.2f Hz",
                                      ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
      tuned |= ImGui::SliderFloat("damping", &spec.damping_ratio, 0.0f, 2.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
      if (ImGui::SliderFloat("gravity", &gravity, 0.0f, 20.0f, "%.2f m/s2", ImGuiSliderFlags_AlwaysClamp)) {
        spec.gravity = -gravity * state.up;  // pulls toward the model's down
        tuned = true;
      }
      if (tuned) springs.set_settings(c, spec);
      ImGui::PopID();
    }
  }
}

// Scene: where the character node stands and which way it turns.
void scene_edit(ViewerState& state, const char* label, int node) {
  sample::SceneNode& n = state.scene.node(node);
  ImGui::PushID(label);
  ImGui::DragFloat3("position", &n.translation.x, 0.01f);
  float yaw = glm::degrees(glm::eulerAngles(n.rotation).y);
  if (ImGui::SliderFloat("turn", &yaw, -180.0f, 180.0f))
    n.rotation = glm::angleAxis(glm::radians(yaw), glm::vec3(0, 1, 0));
  ImGui::PopID();
}

}  // namespace

// The panel: a few lines of status, then collapsible sections, the most used open (display, clip, elastic
// lattices). It sizes itself to what is open, never taller than the window (then it scrolls), so that it fits an
// 800-pixel-high window with its default sections open.
void panel(ViewerState& state, float frame_ms) {
  if (state.options.bare) return;
  const glm::ivec2 size = state.window.framebuffer_size();
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(330, 0), ImVec2(330, std::max(100.0f, float(size.y) - 20.0f)));
  ImGui::Begin("libdeform", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  status_lines(state, frame_ms);
  display_section(state);
  weights_section(state);
  clip_section(state);
  lattices_section(state);
  skinning_section(state);
  lod_section(state);
  reach_section(state);
  morph_section(state);
  springs_section(state);
  if (ImGui::CollapsingHeader("Scene")) scene_edit(state, "character", state.character_node);
  ImGui::End();
}

void note_long_frame(ViewerState& state, float took, float simulated) {
  state.long_frame_ms = 1000.0f * took;
  state.long_frame_simulated_ms = 1000.0f * simulated;
  state.long_frame_at = Clock::now();
}

}  // namespace viewer
