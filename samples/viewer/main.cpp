// deform_viewer: the rubber-arm character on screen. Click a point of the scene: the nearest arm reaches for it by
// IK and, when it is out of reach, stretches elastically; let go and it springs back. Everything deforming is the
// libdeform facade (deform::Character); this file only draws it and turns mouse and keys into calls.
//
//   deform_viewer [MODEL [--skeleton S.sk] [--weights W.skw] [--rig R.json]] [--clip NAME|#N [--inertia F]]
//                 [--blend NAME|#N [--blend-weight W]] [--morph NAME:W[,...]] [--prop P.obj]... [--gpu] [--dqs]
//                 [--skinning lbs|dqs|ddm] [--mush N]
//                 [--up y|z] [--lattices none|active|all]
//   deform_viewer --screenshot out.png --frames N [--reach X,Y,Z --at F] [--release-at F] [--pole X,Y,Z]
//
// Clips (the built-in character's walk, an imported file's clips) play with secondary motion: each frame samples
// the clip now and a millisecond later (Character::set_pose(pose, later, lead)), so the lattices' inertia and the
// rig's spring chains follow the motion between frames; a reach is solved again on every frame's pose. A second
// clip blends with the first (deform::BlendingJob, the panel's "blend with" and its weight), following the first
// clip's phase so that clips of different lengths (a walk and a run) stay in step.
//
// Morph targets (an imported file's blend shapes) morph the character (Character::set_morph_weights): each target's
// weight follows the playing clip's morph channels (blended like the poses with a second clip), else its default;
// the panel shows each weight as a slider, and moving one (or --morph NAME:W) holds it until "follow the clip".
//
// Deformation on the GPU (--gpu, the panel or G; OpenGL 4.3): the character only poses on the CPU
// (Character::settings.deform_on_cpu = false); deform::GpuSkinning skins it into the vertex buffer from the palette and
// deform::GpuLatticeFields::apply_into adds the lattices' carried points and fields there. --up z stands a
// Z-up model upright by turning its scene node; imported files say their up axis themselves where Assimp reads it.
//
// Framing: the camera fits the box of what plays (the bind pose, or the poses of the playing clip sampled when the
// model loads), so a clip that stands a character elsewhere than its bind pose keeps it in frame; C fits it again.
// The lattice overlay draws the active limb's lattices (reaching, or under the mouse), all of them on request (L).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "framework.hpp"  // epoxy before any other GL header

#include <GLFW/glfw3.h>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <imgui.h>

#include "deform/character/character.hpp"
#include "deform/deform.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/gpu/skinning.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/picking.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "model_loading.hpp"
#include "scene.hpp"
#include "shapes.hpp"
#include "options.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using viewer::fail;
using viewer::Options;

// Which lattices the overlay draws: none, the active limb's (the one reaching, else the one a click at the mouse
// would move, else the one that reached last), or all (with a dozen lattices they cage the whole body).
enum class LatticeDisplay { none, active, all };

// The rotation that stands a model whose up direction is `up` (a unit basis vector) upright, +Y.
glm::quat upright(glm::vec3 up) {
  const glm::vec3 y(0.0f, 1.0f, 0.0f);
  if (glm::dot(up, y) > 0.5f) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  if (glm::dot(up, y) < -0.5f) return glm::angleAxis(glm::pi<float>(), glm::vec3(1.0f, 0.0f, 0.0f));
  return glm::angleAxis(glm::half_pi<float>(), glm::normalize(glm::cross(up, y)));
}

// The model the options name (model_loading: the CLI loads the same way); an OBJ without --weights gets automatic
// weights. Exits with a message when the options name no loadable model.
model_loading::LoadedModel load(const Options& o) {
  const bool is_obj = o.model.size() > 4 &&
                      (o.model.substr(o.model.size() - 4) == ".obj" || o.model.substr(o.model.size() - 4) == ".OBJ");
  if (is_obj && o.skeleton.empty()) fail(o.model + ": an OBJ needs --skeleton S.sk");
  model_loading::LoadedModel loaded = model_loading::load_model(
      {.path = o.model, .skeleton = o.skeleton, .weights = o.weights, .automatic_weights = true, .references = {}});
  for (const std::string& w : loaded.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (o.up == 'y') loaded.up = glm::vec3(0.0f, 1.0f, 0.0f);
  if (o.up == 'z') loaded.up = glm::vec3(0.0f, 0.0f, 1.0f);
  return loaded;
}

glm::vec3 heat(float t) {  // 0 blue, 0.5 green, 1 red
  t = std::clamp(t, 0.0f, 1.0f);
  return t < 0.5f ? glm::mix(glm::vec3(0.2f, 0.4f, 1.0f), glm::vec3(0.2f, 1.0f, 0.3f), 2.0f * t)
                  : glm::mix(glm::vec3(0.2f, 1.0f, 0.3f), glm::vec3(1.0f, 0.2f, 0.1f), 2.0f * t - 1.0f);
}

// Marks "take the rig's elastic settings" until the first character is built.
deform::ElasticSettings unset_elastic() {
  deform::ElasticSettings s;
  s.oscillator.stiffness = 0.0f;
  return s;
}

glm::vec3 transform_point(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

// Everything the viewer shows and edits.
class Viewer {
 public:
  Viewer(const Options& options, sample::Window& window)
      : options_(options),
        window_(window),
        gpu_available_(window.has_compute() && deform::GpuBezierLattice::supported()) {
    model_loading::LoadedModel loaded = load(options);
    clips_ = std::move(loaded.clips);
    // A model with no clips of its own but the built-in character's bones (it, or its files in samples/data) gets the
    // built-in clips (idle, walk, run, wave); builtin_clips refuses any other skeleton, which then simply has none.
    if (clips_.empty() && !loaded.imported) {
      try {
        clips_ = deform::builtin_clips(loaded.model);
      } catch (const deform::Error&) {
      }
    }
    clip_names_.push_back("(none)");  // the panel's list, made once
    for (const deform::Animation& c : clips_) clip_names_.push_back(c.name.empty() ? "(unnamed)" : c.name.c_str());
    inertia_ = options.inertia;
    base_model_ = loaded.model;
    // The built-in character stretches whichever limb is nearest the click: its rig with lattices on every limb.
    rig_ = !options.rig.empty()
               ? deform::read_rig_json(options.rig, base_model_.skeleton, base_model_.mesh.point_count())
           : loaded.builtin ? deform::builtin_full_rig(loaded.model)
                            : model_loading::starting_rig(loaded);
    if (options.pole) pole_ = *options.pole, use_pole_ = true;
    lattice_display_ = options.lattices == 'n'   ? LatticeDisplay::none
                       : options.lattices == 'e' ? LatticeDisplay::all
                                                 : LatticeDisplay::active;
    if (options.swing_twist) reach_limits_ = deform::Character::JointLimits::swing_twist;
    rebuild_character();
    if (!options.weight_map.empty()) {
      weight_bone_ = base_model_.skeleton.find(options.weight_map);
      if (weight_bone_ < 0) fail("--weight-map: no bone '" + options.weight_map + "'");
    }
    // A clip by name, or "#N" for the N-th.
    auto find = [&](const std::string& name) {
      const int clip = name[0] == '#' ? std::atoi(name.c_str() + 1) : deform::find_clip(clips_, name);
      if (clip < 0 || clip >= int(clips_.size())) fail(loaded.source + ": no clip '" + name + "'");
      return clip;
    };
    if (!options.clip.empty()) select_clip(find(options.clip));  // play a clip from the start
    if (!options.blend_clip.empty()) {
      if (options.clip.empty()) fail("--blend needs --clip");
      blend_clip_ = find(options.blend_clip);
    }
    blend_weight_ = options.blend_weight;
    for (const auto& [name, weight] : options.morphs) {
      bool found = false;
      for (std::size_t k = 0; k < base_model_.morph_targets.size(); ++k)
        if (base_model_.morph_targets[k].name == name) morph_held_[k] = 1, morph_hold_[k] = weight, found = true;
      if (!found) fail(loaded.source + ": --morph: no morph target '" + name + "'");
    }

    // The scene (the thesis' version 1): the world holds the floor, the character and the props. The character node
    // (moved and turned from the panel) holds the model node, which stands the model upright (its up axis onto +Y)
    // and is the model's own space; the target ball is its child, so moving the character carries its target along.
    world_node_ = scene_.add("world");
    floor_node_ = scene_.add("floor", world_node_);
    character_node_ = scene_.add("character", world_node_);
    model_node_ = scene_.add("model", character_node_);
    up_ = loaded.up;
    scene_.node(model_node_).rotation = upright(up_);
    ball_node_ = scene_.add("target", model_node_, glm::vec3(0.0f), glm::vec3(1.0f));
    std::vector<glm::vec3> standing(base_model_.mesh.positions);  // framing, floor and props see the upright model
    for (glm::vec3& p : standing) p = scene_.node(model_node_).rotation * p;
    const deform::Bounds b = deform::compute_bounds(standing);
    const float height = std::max(1e-3f, b.max.y - b.min.y);
    const float extent = std::max({b.max.x - b.min.x, height, b.max.z - b.min.z});
    scene_.node(floor_node_).translation = glm::vec3(0.5f * (b.min.x + b.max.x), b.min.y, 0.5f * (b.min.z + b.max.z));
    // What each clip shows, sampled once here: the box around its skinned poses (upright), which the camera frames,
    // and the lowest any point reaches, where the floor goes, not the bind pose's lowest point: an imported file's
    // bind pose can stand elsewhere than its animated stance (mrfixit.iqm's idle crouches below its bind pose's
    // feet; a glTF character can lie on its back until its clip stands it up), and the character must stand on the
    // floor, never sink into it, and stay in frame.
    rest_bounds_ = b;
    floor_height_ = 0.01f * height;
    for (const deform::Animation& clip : clips_) {
      clip_bounds_.push_back(model_loading::posed_bounds(base_model_, clip, scene_.node(model_node_).rotation));
      clip_floors_.push_back(clip_bounds_.back().min.y);
    }
    floor_mesh_ = sample::make_floor(extent * 4.0f, 16);
    ball_mesh_ = sample::make_sphere(extent * 0.025f, 12, 24, glm::vec3(1.0f, 0.55f, 0.1f));
    for (const std::string& path : options.props) {
      props_.push_back(std::make_unique<deform::Mesh>(deform::read_obj(path)));
      prop_nodes_.push_back(
          scene_.add(path, world_node_, glm::vec3(extent * 0.6f * float(props_.size()), b.min.y, 0.0f)));
    }
    place_floor();  // --clip and --blend chose clips before the floor existed
    scene_.update();
    fit_camera();
    pick_radius_ = extent;

    floor_renderer_.create(floor_mesh_);
    upload_static(floor_renderer_, floor_mesh_);
    ball_renderer_.create(ball_mesh_);
    upload_static(ball_renderer_, ball_mesh_);
    for (auto& prop : props_) {
      prop_renderers_.push_back(std::make_unique<sample::MeshRenderer>());
      prop_renderers_.back()->create(*prop);
      upload_static(*prop_renderers_.back(), *prop);
    }
    overlay_.create();
    scene_.update();
    if (options.dqs) character_->settings.skinning = deform::SkinningMethod::dqs;
    ddm_ = options.ddm;
    mush_iterations_ = options.mush;
    apply_mush();
    if (options.gpu) {
      if (gpu_available_) set_gpu(true);
      else std::fprintf(stderr, "deform_viewer: --gpu: %s; deforming on the CPU\n", gpu_missing().c_str());
    }
  }

  bool gpu_lattices() const { return gpu_; }
  // The floor's height, and the lowest height of the character as drawn now (both along the upright +Y).
  float floor_y() const { return scene_.node(floor_node_).translation.y; }
  float lowest_y() const {
    float lowest = std::numeric_limits<float>::infinity();
    for (const glm::vec3& p : character_->positions()) lowest = std::min(lowest, glm::dot(p, up_));
    return lowest;
  }
  glm::vec3 up() const { return up_; }
  // The lattices drawn in the last frame (the overlay; 0 with --bare).
  int lattices_shown() const {
    return options_.bare || lattice_display_ == LatticeDisplay::none
               ? 0
               : int(std::count(lattice_shown_.begin(), lattice_shown_.end(), char(1)));
  }
  // The image row (from the top) of the floor under the point drawn lowest on the screen, through the camera: the
  // row of the silhouette's lowest pixels when the character stands on the floor, below it when the character
  // floats, above it when it sinks (headless pixel tests). Projects every point: for the headless summary only.
  float floor_row() const {
    const glm::ivec2 size = window_.framebuffer_size();
    const glm::mat4 view = camera_.view(), projection = camera_.projection(window_.aspect());
    const glm::vec4 viewport(0.0f, 0.0f, float(size.x), float(size.y));
    glm::vec3 lowest(0.0f);
    float lowest_window_y = std::numeric_limits<float>::infinity();
    for (const glm::vec3& p : character_->positions()) {
      const glm::vec3 world = transform_point(character_world(), p);
      const float window_y = glm::project(world, view, projection, viewport).y;
      if (window_y < lowest_window_y) lowest_window_y = window_y, lowest = world;
    }
    lowest.y = floor_y();
    return float(size.y) - glm::project(lowest, view, projection, viewport).y;
  }
  // The morph weights as applied now, comma-separated (the headless summary).
  std::string morph_weights_text() const {
    std::string text;
    for (const float w : character_->morph_weights()) {
      char number[32];
      std::snprintf(number, sizeof number, "%s%.6g", text.empty() ? "" : ", ", double(w));
      text += number;
    }
    return text;
  }

  void frame(float dt) {
    const sample::Input& in = window_.input();
    camera_.handle(in, window_.framebuffer_size());
    handle_keys(in.key_pressed);
    handle_mouse(in);
    place_floor();
    if (clip_ >= 0) {
      // The pose now and where it heads a millisecond later (paused: nowhere, so the still body gets no velocity);
      // then the reach again, on this frame's pose.
      constexpr float lead = 1e-3f;
      const deform::Animation& clip = clips_[std::size_t(clip_)];
      const float rate = playing_ ? speed_ : 0.0f;
      clip_time_ = clip.local_time(clip_time_ + dt * rate);  // kept within the clip: a small float stays precise
      sample_clip(clip_time_, pose_);
      sample_clip(clip_time_ + lead * rate, later_);
      character_->set_pose(pose_, later_, lead);
      // The reach again, on this frame's pose: a reach held so follows its target smoothly (Character::reach).
      if (reaching_) last_reach_ = character_->reach(effector_, target_);
    }
    apply_morph_weights();
    if (cut_) {  // a new clip, a rebuilt character: the pose jumps, which a zero step takes as a cut, not motion
                 // (a reach that begins or ends is one the character takes care of itself)
      character_->update(0.0f);
      cut_ = false;
    }
    const auto start = Clock::now();
    character_->update(dt);
    const auto normals = gpu_ ? std::span<const glm::vec3>{} : character_->normals();
    deform_ms_ = 0.9f * deform_ms_ + 0.1f * std::chrono::duration<float, std::milli>(Clock::now() - start).count();
    draw(normals);
  }

  // Headless scripting: reach for a world point, let go.
  void reach_world(glm::vec3 world_target) { begin_reach(world_target); }
  void release() {
    if (reaching_) character_->release();
    reaching_ = false;
  }
  // A frame that took `took` seconds was simulated as `simulated` (the main loop's clamp): the panel says so.
  void frame_clamped(float took, float simulated) {
    long_frame_ms_ = 1000.0f * took;
    long_frame_simulated_ms_ = 1000.0f * simulated;
    long_frame_at_ = Clock::now();
  }
  glm::vec3 effector_position() const {
    return effector_ >= 0 ? transform_point(character_world(), character_->bone_position(effector_)) : glm::vec3(0.0f);
  }

  // The panel: a few lines of status, then collapsible sections, the most used open (display, clip, elastic
  // lattices). It sizes itself to what is open, never taller than the window (then it scrolls), so that it fits an
  // 800-pixel-high window with its default sections open.
  void panel(float frame_ms) {
    if (options_.bare) return;
    const glm::ivec2 size = window_.framebuffer_size();
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSizeConstraints(ImVec2(330, 0), ImVec2(330, std::max(100.0f, float(size.y) - 20.0f)));
    ImGui::Begin("libdeform", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    // What the panel hides on the left, for the next fit of the camera (none when collapsed or moved elsewhere).
    const ImVec2 panel_at = ImGui::GetWindowPos(), panel_size = ImGui::GetWindowSize();
    panel_right_ =
        !ImGui::IsWindowCollapsed() && panel_at.x < 0.3f * float(size.x) ? panel_at.x + panel_size.x + 10.0f : 0.0f;
    ImGui::Text("%s: %zu points, %zu bones", base_model_.name.c_str(), base_model_.mesh.point_count(),
                base_model_.skeleton.bone_count());
    ImGui::Text("frame %.2f ms, deformation %.3f ms", frame_ms, deform_ms_);
    // A frame longer than the clamp is simulated short: say so for a while rather than show it as slow motion.
    if (Clock::now() - long_frame_at_ < std::chrono::seconds(2))
      ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "frame took %.0f ms: simulated %.0f ms", long_frame_ms_,
                         long_frame_simulated_ms_);
    ImGui::TextDisabled("click: reach, right drag: orbit, C: camera");
    if (reaching_ || character_->stretch() != 0.0f)
      ImGui::Text("stretch %.3f, residual %.3f", character_->stretch(), last_reach_.residual);

    if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
      ImGui::Checkbox("skeleton", &show_skeleton_);
      ImGui::SameLine();
      // The lattices of the limb in use only (reaching, else under the mouse), or every one (L cycles the three).
      bool shown = lattice_display_ != LatticeDisplay::none, all = lattice_display_ == LatticeDisplay::all;
      bool display_changed = ImGui::Checkbox("lattices", &shown);
      ImGui::SameLine();
      ImGui::BeginDisabled(!shown);
      display_changed |= ImGui::Checkbox("all lattices", &all);
      ImGui::EndDisabled();
      if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
        ImGui::SetTooltip("every lattice; else only the limb that reaches, or would reach from under the mouse (L)");
      if (display_changed)
        lattice_display_ = !shown ? LatticeDisplay::none : all ? LatticeDisplay::all : LatticeDisplay::active;
      // The weight map: one bone's skin weight at every point, blue (low) to red (1); points without it undrawn.
      const deform::Skeleton& sk = character_->skeleton();
      std::vector<std::string> keys{"(none)"};
      for (std::size_t b = 0; b < sk.bone_count(); ++b) keys.push_back(sk.key(std::int32_t(b)));
      std::vector<const char*> names;
      for (const std::string& k : keys) names.push_back(k.c_str());
      int selected = weight_bone_ + 1;
      if (ImGui::Combo("weights of", &selected, names.data(), int(names.size()))) weight_bone_ = selected - 1;
    }

    if (!clips_.empty() && ImGui::CollapsingHeader("Clip", ImGuiTreeNodeFlags_DefaultOpen)) {
      int selected = clip_ + 1;
      if (ImGui::Combo("clip", &selected, clip_names_.data(), int(clip_names_.size()))) select_clip(selected - 1);
      ImGui::BeginDisabled(clip_ < 0);
      if (ImGui::Button(playing_ ? "pause" : "play")) playing_ = !playing_;
      ImGui::SameLine();
      ImGui::Text("%.2f s", clip_ >= 0 ? clip_time_ : 0.0f);
      ImGui::SliderFloat("speed", &speed_, 0.0f, 2.0f, "%.2fx", ImGuiSliderFlags_AlwaysClamp);
      // A second clip blended with the first by weight, following its phase (BlendingJob).
      int with = blend_clip_ + 1;
      if (ImGui::Combo("blend with", &with, clip_names_.data(), int(clip_names_.size()))) blend_clip_ = with - 1;
      ImGui::BeginDisabled(blend_clip_ < 0);
      ImGui::SliderFloat("blend", &blend_weight_, 0.0f, 1.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
      ImGui::EndDisabled();
      // The jiggle: the lattices lag behind their bones while the clip plays, each part's tuned inertia times the
      // slider (DeformerHierarchy::set_inertia_scale): at 1 the tuned jiggle, limbs keeping their length.
      bool motion = ImGui::Checkbox("jiggle", &jiggle_);
      ImGui::SameLine();
      ImGui::BeginDisabled(!jiggle_);
      ImGui::SetNextItemWidth(140.0f);
      motion |= ImGui::SliderFloat("inertia", &inertia_, 0.0f, 1.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
      ImGui::EndDisabled();
      if (motion) apply_motion();
      ImGui::EndDisabled();
    }

    char title[64];
    std::snprintf(title, sizeof title, "Elastic lattices (%zu)###lattices", character_->deformers().lattice_count());
    if (ImGui::CollapsingHeader(title, ImGuiTreeNodeFlags_DefaultOpen)) {
      bool changed = ImGui::SliderFloat("stiffness k", &elastic_.oscillator.stiffness, 5.0f, 1000.0f, "%.0f",
                                        ImGuiSliderFlags_Logarithmic);
      changed |= ImGui::SliderFloat("damping ratio", &elastic_.oscillator.damping_ratio, 0.0f, 2.0f);
      int integrator = elastic_.integrator == deform::Integrator::verlet;
      changed |= ImGui::RadioButton("exact", &integrator, 0);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("frame-rate independent");
      ImGui::SameLine();
      changed |= ImGui::RadioButton("Verlet, constant Kd", &integrator, 1);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("the seed's integrator");
      elastic_.integrator = integrator ? deform::Integrator::verlet : deform::Integrator::exact;
      if (changed) apply_elastic();
      if (ImGui::SliderInt("lattice degree", &degree_, 1, 6)) rebuild_character();
      // The rubber's shape: a limb never shorter than `min length` of its rest, its cross-section thinning as it
      // stretches (volume 1: the volume kept) and bulging as it shortens.
      bool shaped = ImGui::SliderFloat("volume", &shape_.volume, 0.0f, 1.0f);
      shaped |= ImGui::SliderFloat("min length", &shape_.min_length_fraction, 0.0f, 1.0f);
      if (shaped) apply_shape();
      if (ImGui::SliderFloat("max stretch", &max_stretch_, 0.0f, 10.0f)) apply_reach_settings();
    }

    if (ImGui::CollapsingHeader("Skinning and GPU")) {
      // LBS and DQS are Character::settings.skinning; DDM binds Direct Delta Mush, which takes precedence over it.
      int method = ddm_ ? 2 : character_->settings.skinning == deform::SkinningMethod::dqs;
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
          character_->settings.skinning = method ? deform::SkinningMethod::dqs : deform::SkinningMethod::lbs;
        ddm_ = method == 2;
        apply_mush();
      }
      if (ImGui::SliderInt("Delta Mush iterations", &mush_iterations_, 0, 50)) apply_mush();
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("smoothing after the lattices, detail kept; 0: off; CPU only");
      bool gpu = gpu_;
      ImGui::BeginDisabled(!gpu_available_);
      if (ImGui::Checkbox("GPU deformation", &gpu)) set_gpu(gpu);
      ImGui::EndDisabled();
      if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) {
        ImGui::SetTooltip("%s", gpu_available_ ? "skinning and Bezier fields in compute shaders, into the vertex "
                                                 "buffer; the CPU only poses (deformation time: the CPU's part)"
                                               : gpu_missing().c_str());
      }
    }

    if (ImGui::CollapsingHeader("Reach")) {
      ImGui::Checkbox("escape IK stalls", &character_->settings.ik.escape_stalls);
      ImGui::SliderInt("IK iterations", &character_->settings.ik.max_iterations, 1, 256);
      int solver = reach_solver_ == deform::Character::ReachSolver::two_bone;
      bool reach_changed = ImGui::RadioButton("CCD chain", &solver, 0);
      ImGui::SameLine();
      reach_changed |= ImGui::RadioButton("two-bone limb", &solver, 1);
      reach_solver_ = solver ? deform::Character::ReachSolver::two_bone : deform::Character::ReachSolver::ccd;
      ImGui::BeginDisabled(!solver);
      reach_changed |= ImGui::SliderFloat("soften", &soften_, 0.0f, 1.0f);
      ImGui::EndDisabled();
      reach_changed |= ImGui::Checkbox("pole", &use_pole_);
      ImGui::SameLine();
      ImGui::TextDisabled("(shift+click places it)");
      reach_changed |= ImGui::DragFloat3("pole at", &pole_.x, 0.01f);
      bool swing_twist = character_->settings.reach_limits == deform::Character::JointLimits::swing_twist;
      if (ImGui::Checkbox("swing-twist limits", &swing_twist)) {
        reach_limits_ =
            swing_twist ? deform::Character::JointLimits::swing_twist : deform::Character::JointLimits::euler;
        reach_changed = true;
      }
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "each joint of the reach chain limited by a twist range and a swing cone (drawn in cyan)\n"
            "made from its Euler limits, instead of the Euler box");
      if (reach_changed) apply_reach_settings();
    }

    if (character_->morph_target_count() > 0) {  // the morph targets' weights: the clip's, unless held here
      // Open by default for a handful of targets (they are then what the model is about); a long list starts closed.
      std::snprintf(title, sizeof title, "Morph targets (%zu)###morphs", character_->morph_target_count());
      if (ImGui::CollapsingHeader(title, character_->morph_target_count() <= 8 ? ImGuiTreeNodeFlags_DefaultOpen : 0)) {
        if (ImGui::SmallButton("follow the clip")) std::fill(morph_held_.begin(), morph_held_.end(), char(0));
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("every weight from the playing clip again (else its default)");
        const std::vector<deform::MorphTarget>& targets = character_->model().morph_targets;
        for (std::size_t k = 0; k < targets.size(); ++k) {
          ImGui::PushID(int(k));
          bool held = morph_held_[k] != 0;
          float weight = character_->morph_weights()[k];
          if (ImGui::Checkbox("##held", &held)) morph_held_[k] = held, morph_hold_[k] = weight;
          if (ImGui::IsItemHovered()) ImGui::SetTooltip("held: the slider's weight; else the clip's (or the default)");
          ImGui::SameLine();
          const std::string label = targets[k].name.empty() ? "target " + std::to_string(k) : targets[k].name;
          if (ImGui::SliderFloat(label.c_str(), &weight, 0.0f, 1.0f, "%.2f")) {
            morph_held_[k] = 1;
            morph_hold_[k] = weight;
            apply_morph_weights();
          }
          if (ImGui::IsItemHovered() && !targets[k].mesh.empty()) ImGui::SetTooltip("mesh %s", targets[k].mesh.c_str());
          ImGui::PopID();
        }
      }
    }

    deform::SpringChains& springs = character_->springs();
    std::snprintf(title, sizeof title, "Spring chains (%zu)###springs", springs.chain_count());
    if (springs.chain_count() > 0 && ImGui::CollapsingHeader(title)) {  // drawn in green with the skeleton
      for (std::size_t c = 0; c < springs.chain_count(); ++c) {
        // Tuned in the viewer's copy of the rig, so a rebuilt character keeps the settings; clamped, since
        // set_settings throws on a value out of range (a ctrl+click can type one).
        deform::SpringChainSpec& spec = rig_.spring_chains[c];
        float gravity = glm::length(spec.gravity);
        ImGui::PushID(int(c));
        ImGui::TextDisabled("%s", spec.name.c_str());
        bool tuned = ImGui::SliderFloat("frequency", &spec.frequency, 0.1f, 10.0f, "%.2f Hz",
                                        ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
        tuned |= ImGui::SliderFloat("damping", &spec.damping_ratio, 0.0f, 2.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp);
        if (ImGui::SliderFloat("gravity", &gravity, 0.0f, 20.0f, "%.2f m/s2", ImGuiSliderFlags_AlwaysClamp)) {
          spec.gravity = -gravity * up_;  // pulls toward the model's down
          tuned = true;
        }
        if (tuned) springs.set_settings(c, spec);
        ImGui::PopID();
      }
    }

    if (ImGui::CollapsingHeader("Scene")) SceneEdit("character", character_node_);
    ImGui::End();
  }

 private:
  void SceneEdit(const char* label, int node) {
    sample::SceneNode& n = scene_.node(node);
    ImGui::PushID(label);
    ImGui::DragFloat3("position", &n.translation.x, 0.01f);
    float yaw = glm::degrees(glm::eulerAngles(n.rotation).y);
    if (ImGui::SliderFloat("turn", &yaw, -180.0f, 180.0f))
      n.rotation = glm::angleAxis(glm::radians(yaw), glm::vec3(0, 1, 0));
    ImGui::PopID();
  }

  std::string gpu_missing() const {
    const int version = epoxy_gl_version();
    return "needs OpenGL 4.3 compute shaders; this context is OpenGL " + std::to_string(version / 10) + "." +
           std::to_string(version % 10) + " (" + window_.renderer_name() + ")";
  }

  // The whole deformation on the GPU (on) or the CPU (off): the character only poses, GpuSkinning skins from its
  // palette and GpuLatticeFields adds its lattices, all in the renderer's vertex buffer (whose UVs stay as created).
  void set_gpu(bool on) {
    if (on && (ddm_ || mush_iterations_ > 0)) {  // GpuSkinning is LBS or DQS, and the GPU path has no Delta Mush
      std::fprintf(stderr, "deform_viewer: Direct Delta Mush and Delta Mush are CPU stages; deforming on the CPU\n");
      on = false;
    }
    if (on && character_->morph_target_count() > 0) {  // GpuSkinning skins the bind positions, not the morphed ones
      std::fprintf(stderr,
                   "deform_viewer: the model has morph targets, which the GPU path does not apply; "
                   "deforming on the CPU\n");
      on = false;
    }
    gpu_ = on && gpu_available_;
    gpu_fields_.clear();
    gpu_skinning_.release();
    if (gpu_) {
      const deform::Mesh& mesh = character_->model().mesh;
      const auto normals = character_->bind_normals();
      gpu_bind_normals_.resize(mesh.vertex_count());
      for (std::size_t r = 0; r < mesh.vertex_count(); ++r) gpu_bind_normals_[r] = normals[mesh.vertex_point[r]];
      deform::GpuSkinningBind bind;
      bind.positions = mesh.positions;
      bind.bone_indices = character_->model().weights.bones;
      bind.bone_weights = character_->model().weights.weights;
      bind.vertex_point = mesh.vertex_point;
      bind.normals = gpu_bind_normals_;
      bind.bone_count = character_->skeleton().bone_count();
      deform::Status status = gpu_skinning_.create(bind);
      if (status) status = gpu_fields_.create(character_->deformers(), mesh.vertex_point, true);
      if (!status) {
        std::fprintf(stderr, "deform_viewer: GPU deformation refused: %s; deforming on the CPU\n", status.reason());
        gpu_fields_.clear();
        gpu_skinning_.release();
        gpu_ = false;
      }
    }
    character_->settings.deform_on_cpu = !gpu_;
  }

  // The deformed points as drawn: the character's, or with the GPU deformation, read back from the vertex buffer
  // (for picking and the weight map only: a GPU-to-CPU copy, not done for drawing).
  std::span<const glm::vec3> drawn_points() {
    if (!gpu_) return character_->positions();
    const deform::Mesh& mesh = character_->model().mesh;
    constexpr deform::GpuVertexLayout layout{};
    std::vector<float> data(mesh.vertex_count() * std::size_t(layout.floats_per_vertex));
    glBindBuffer(GL_ARRAY_BUFFER, renderer_->vertex_buffer());
    glGetBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(data.size() * sizeof(float)), data.data());
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    gpu_points_.resize(mesh.point_count());
    for (std::size_t r = 0; r < mesh.vertex_count(); ++r) {
      const float* p = data.data() + r * std::size_t(layout.floats_per_vertex) + layout.position_offset;
      gpu_points_[mesh.vertex_point[r]] = glm::vec3(p[0], p[1], p[2]);
    }
    return gpu_points_;
  }

  void rebuild_character() {
    deform::Rig rig = rig_;
    for (auto& spec : rig.lattices) {
      if (degree_ == 0) degree_ = spec.degree.x;
      spec.degree = glm::ivec3(degree_);
      if (elastic_.oscillator.stiffness <= 0.0f) elastic_ = spec.elastic;
      spec.elastic = elastic_.oscillator.stiffness > 0.0f ? elastic_ : spec.elastic;
    }
    if (degree_ == 0) degree_ = 3;
    if (elastic_.oscillator.stiffness <= 0.0f) elastic_ = deform::ElasticSettings{};
    try {
      character_ = std::make_unique<deform::Character>(base_model_, rig);
    } catch (const deform::Error& e) {
      // A rig made by default_rig() for an unusual model may not bind: the character still reaches, without stretch.
      if (!options_.rig.empty()) throw;
      std::fprintf(stderr, "warning: %s; reaching without elastic lattices\n", e.what());
      rig_ = deform::Rig{};
      character_ = std::make_unique<deform::Character>(base_model_, rig_);
    }
    const deform::Mesh& mesh = character_->model().mesh;
    triangle_points_.resize(mesh.triangles.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) triangle_points_[i] = mesh.vertex_point[mesh.triangles[i]];
    character_->update(0.0f);
    bvh_.build(character_->positions(), triangle_points_);
    renderer_ = std::make_unique<sample::MeshRenderer>();
    renderer_->create(mesh);
    // The in-memory built-in character names builtin.png without a folder: draw its texture from memory.
    if (options_.model.empty() && !mesh.materials.empty()) {
      const int size = 512;
      const std::vector<std::uint8_t> pixels = deform::builtin_texture(size);
      renderer_->set_texture_rgb(0, size, size, pixels.data());
    }
    reaching_ = false;
    effector_ = hovered_effector_ = -1;
    lattice_shown_.assign(character_->deformers().lattice_count(), 0);
    morph_held_.resize(character_->morph_target_count(), 0);  // kept over rebuilds: the panel's holds stay
    morph_hold_.resize(character_->morph_target_count(), 0.0f);
    morph_second_.resize(character_->morph_target_count(), 0.0f);
    apply_morph_weights();
    bind_pose_ = character_->skeleton().bind_pose();
    pose_ = later_ = first_ = second_ = bind_pose_;  // sized once: sample_clip copies into them
    cut_ = true;
    apply_motion();
    if (max_stretch_ < 0.0f) max_stretch_ = character_->rig().max_stretch;
    apply_shape();
    apply_reach_settings();
    apply_mush();
    set_gpu(gpu_);
  }

  // The Character's mush stages as the panel holds them: Direct Delta Mush as the skinning (ddm_) and Delta Mush
  // after the lattices (mush_iterations_). Binding allocates and takes a moment: only when a choice changes. Either
  // one turns the GPU deformation off, which has neither.
  void apply_mush() {
    if (ddm_ && character_->direct_delta_mush() == nullptr) character_->set_direct_delta_mush({});
    if (!ddm_) character_->clear_direct_delta_mush();
    const unsigned mushed = character_->delta_mush() ? character_->delta_mush()->iterations : 0u;
    if (unsigned(mush_iterations_) != mushed) character_->set_delta_mush({mush_iterations_, 0.5f, {}});
    if (gpu_ && (ddm_ || mush_iterations_ > 0)) set_gpu(false);
  }

  // The floor under what plays: the bind pose's lowest point with no clip, else the clip's floor, the lower of the
  // two clips' floors while a second one is blended in (a blend of two poses stays close to their range). Cheap:
  // called on every frame, as the panel can change the clips at any time. Before the scene exists it does nothing.
  void place_floor() {
    if (floor_node_ < 0) return;
    float floor = clip_ < 0 ? rest_bounds_.min.y : clip_floors_[std::size_t(clip_)];
    if (clip_ >= 0 && blend_clip_ >= 0 && blend_weight_ > 0.0f)
      floor = std::min(floor, clip_floors_[std::size_t(blend_clip_)]);
    scene_.node(floor_node_).translation.y = floor;
    camera_.floor = floor + floor_height_;
  }

  // The box the camera frames (upright model space): the playing clip's sampled poses (with a second clip blended
  // in, both clips'), else the bind pose.
  deform::Bounds framed_bounds() const {
    if (clip_ < 0) return rest_bounds_;
    deform::Bounds box = clip_bounds_[std::size_t(clip_)];
    if (blend_clip_ >= 0 && blend_weight_ > 0.0f) {
      box.min = glm::min(box.min, clip_bounds_[std::size_t(blend_clip_)].min);
      box.max = glm::max(box.max, clip_bounds_[std::size_t(blend_clip_)].max);
    }
    return box;
  }

  // The side the fitted camera looks from (its yaw): across the character's broad side, a little to its right. A
  // box longer than tall (a four-legged character, a bind pose lying down) is seen across its length. A standing
  // figure is seen across its bind pose's broader horizontal axis, its shoulders (or arms) broader than it is deep
  // whether it faces +Z as glTF's do or +X as IQM's do; the clip's box would mislead here, as a walk's stride is
  // deeper than its shoulders are broad. A bind pose lying down (CesiumMan's) that its clip stands up lies along the
  // axis that stands up: across the other one.
  float fitted_yaw(const deform::Bounds& framed) const {
    const glm::vec3 f = framed.max - framed.min, b = rest_bounds_.max - rest_bounds_.min;
    const float across_x = 0.35f, across_z = glm::half_pi<float>() - 0.35f;  // from +Z (a little +X), from +X
    if (f.y < std::max(f.x, f.z)) return f.x >= f.z ? across_x : across_z;
    if (b.y >= 0.5f * std::max(b.x, b.z)) return b.x >= b.z ? across_x : across_z;
    return b.x >= b.z ? across_z : across_x;
  }

  // The camera that frames what plays (framed_bounds, where the character node puts it) from a little above, on the
  // side fitted_yaw chooses: every corner of the box within `fill` of the view's height and width, the box centred
  // on the screen (right of the panel). Corners nearer the eye look bigger, so the distance is the largest any corner
  // needs (|offset across the view| / (tan(fov/2) · fill) in front of it) and the centre is found in a few passes.
  // `C` comes back here; choosing another clip in the panel refits while the camera has not been moved.
  void fit_camera() {
    const deform::Bounds local = framed_bounds();
    const glm::mat4 to_world = scene_.node(character_node_).world;
    glm::vec3 corners[8];
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 c((i & 1 ? local.max : local.min).x, (i & 2 ? local.max : local.min).y,
                        (i & 4 ? local.max : local.min).z);
      corners[i] = transform_point(to_world, c);
    }
    sample::OrbitCamera camera = camera_;  // its field of view and floor
    camera.yaw = fitted_yaw(local);
    camera.pitch = 0.12f;
    const glm::vec3 back(std::cos(camera.pitch) * std::sin(camera.yaw), std::sin(camera.pitch),
                         std::cos(camera.pitch) * std::cos(camera.yaw));  // target to eye
    const glm::vec3 right = glm::normalize(glm::cross(-back, glm::vec3(0.0f, 1.0f, 0.0f)));
    const glm::vec3 up = glm::cross(right, -back);
    constexpr float fill = 0.8f;
    // The panel over the left of the window (`hidden`, a share of its width): the box is made to fit the rest and
    // is drawn right of the panel (a lens shift), centred in the window when it is clear of the panel there.
    const float width = float(std::max(1, window_.framebuffer_size().x));
    const float hidden = options_.bare ? 0.0f : std::min(panel_right_, 0.5f * width) / width;
    const float tan_y = std::tan(0.5f * camera.fov_y), tan_x = tan_y * window_.aspect() * (1.0f - hidden);
    glm::vec3 centre = 0.5f * (corners[0] + corners[7]);
    float distance = 1e-3f;
    for (int pass = 0; pass < 4; ++pass) {
      distance = 1e-3f;
      for (const glm::vec3& c : corners) {
        const glm::vec3 o = c - centre;
        const float toward = glm::dot(o, back);
        distance = std::max({distance, toward + std::abs(glm::dot(o, up)) / (tan_y * fill),
                             toward + std::abs(glm::dot(o, right)) / (tan_x * fill)});
      }
      // The corners' extent on the screen (tangents from the eye), and the centre moved to its middle.
      glm::vec2 low(std::numeric_limits<float>::infinity()), high(-std::numeric_limits<float>::infinity());
      for (const glm::vec3& c : corners) {
        const glm::vec3 o = c - centre;
        const glm::vec2 seen = glm::vec2(glm::dot(o, right), glm::dot(o, up)) / (distance - glm::dot(o, back));
        low = glm::min(low, seen), high = glm::max(high, seen);
      }
      centre += (0.5f * (low.x + high.x) * right + 0.5f * (low.y + high.y) * up) * distance;
    }
    // The box's half width on the screen (NDC), then the shift that puts its left side a little right of the panel's
    // edge (NDC -1 + 2 · hidden), when centred it would be under the panel. It still ends within the window's right
    // edge: the box is at most `fill` of the free width.
    float half_width = 0.0f;
    for (const glm::vec3& c : corners) {
      const glm::vec3 o = c - centre;
      half_width = std::max(half_width, std::abs(glm::dot(o, right)) / (distance - glm::dot(o, back)));
    }
    half_width /= tan_y * window_.aspect();
    camera.shift_x = hidden > 0.0f ? std::max(0.0f, -1.0f + 2.0f * hidden + 0.1f * (1.0f - hidden) + half_width) : 0.0f;
    camera.target = centre;
    camera.distance = distance;
    camera_ = fitted_camera_ = camera;
  }

  bool camera_fitted() const {
    return camera_.target == fitted_camera_.target && camera_.distance == fitted_camera_.distance &&
           camera_.shift_x == fitted_camera_.shift_x && camera_.yaw == fitted_camera_.yaw &&
           camera_.pitch == fitted_camera_.pitch;
  }

  // Plays clip `clip` (-1: none, the bind pose) from its start.
  void select_clip(int clip) {
    const bool refit = floor_node_ >= 0 && camera_fitted();  // before the scene exists, the constructor fits
    clip_ = clip;
    clip_time_ = 0.0f;
    place_floor();
    if (refit) fit_camera();
    if (clip_ < 0) character_->set_pose(bind_pose_);
    cut_ = true;
    apply_motion();
  }

  // The clip at time t over the bind pose (bones without a channel keep it), blended with the second clip at the
  // same phase when one is chosen. No allocation: `into` and the scratch poses are sized.
  void sample_clip(float t, deform::Pose& into) {
    if (blend_clip_ < 0) {
      sample_one(clips_[std::size_t(clip_)], t, into);
      return;
    }
    const deform::Animation& first = clips_[std::size_t(clip_)];
    const deform::Animation& second = clips_[std::size_t(blend_clip_)];
    // The second clip's time at the first's phase (its own time when either has no length).
    const float t2 =
        first.duration > 0.0f && second.duration > 0.0f ? first.local_time(t) / first.duration * second.duration : t;
    sample_one(first, t, first_);
    sample_one(second, t2, second_);
    const deform::BlendLayer layers[] = {{first_.rotations, first_.translations, 1.0f - blend_weight_, {}},
                                         {second_.rotations, second_.translations, blend_weight_, {}}};
    deform::BlendingJob blend;
    blend.layers = layers;
    blend.rest_rotations = bind_pose_.rotations;
    blend.rest_translations = bind_pose_.translations;
    blend.rotations = into.rotations;
    blend.translations = into.translations;
    (void)blend.run();  // cannot fail: every pose has the skeleton's size, the weights are within [0, 1]
  }

  // The morph weights of this frame: the defaults, the playing clip's morph channels at its time (blended with the
  // second clip's at the same phase, by the blend weight, as the poses are), then the panel's held weights.
  void apply_morph_weights() {
    if (!character_ || character_->morph_target_count() == 0) return;
    character_->reset_morph_weights();
    if (clip_ >= 0) {
      const deform::Animation& first = clips_[std::size_t(clip_)];
      (void)character_->set_morph_weights(first, clip_time_);  // cannot fail: the clip was validated on loading
      if (blend_clip_ >= 0) {
        const deform::Animation& second = clips_[std::size_t(blend_clip_)];
        const float t2 = first.duration > 0.0f && second.duration > 0.0f
                             ? first.local_time(clip_time_) / first.duration * second.duration
                             : clip_time_;
        const std::vector<deform::MorphTarget>& targets = character_->model().morph_targets;
        for (std::size_t k = 0; k < targets.size(); ++k) morph_second_[k] = targets[k].default_weight;
        (void)deform::sample_morph_weights(second, t2, morph_second_);
        for (std::size_t k = 0; k < targets.size(); ++k) {
          const float w = (1.0f - blend_weight_) * character_->morph_weights()[k] + blend_weight_ * morph_second_[k];
          (void)character_->set_morph_weight(k, w);
        }
      }
    }
    for (std::size_t k = 0; k < morph_held_.size(); ++k)
      if (morph_held_[k]) (void)character_->set_morph_weight(k, morph_hold_[k]);
  }

  void sample_one(const deform::Animation& clip, float t, deform::Pose& into) const {
    std::copy(bind_pose_.rotations.begin(), bind_pose_.rotations.end(), into.rotations.begin());
    std::copy(bind_pose_.translations.begin(), bind_pose_.translations.end(), into.translations.begin());
    deform::SamplingJob sampling;
    sampling.animation = &clip;
    sampling.time = t;
    sampling.rotations = into.rotations;
    sampling.translations = into.translations;
    (void)sampling.run();  // cannot fail: the clips were validated against this skeleton when loaded
  }

  // The lattices' inertia: the panel's scale of each part's tuned inertia while a clip is chosen and jiggle is on,
  // else none, so a reach on a still body is the plain rubber arm. The rig's gravity on the lattices is kept.
  void apply_motion() { character_->deformers().set_inertia_scale(clip_ >= 0 && jiggle_ ? inertia_ : 0.0f); }

  // The panel's shape for every lattice (DeformerHierarchy::set_shape).
  void apply_shape() {
    try {
      for (std::size_t i = 0; i < character_->deformers().lattice_count(); ++i)
        character_->deformers().set_shape(i, shape_);
    } catch (const deform::Error& e) {
      std::fprintf(stderr, "warning: %s\n", e.what());
    }
  }

  // The panel's pole and stretch bound; a reach in progress is solved again with them.
  void apply_reach_settings() {
    character_->settings.reach_pole = pole_;
    character_->settings.use_reach_pole = use_pole_;
    character_->settings.reach_limits = reach_limits_;
    character_->settings.reach_solver = reach_solver_;
    character_->settings.reach_soften = soften_;
    character_->set_max_stretch(max_stretch_);
    if (reaching_) last_reach_ = character_->reach(effector_, target_);
  }

  void apply_elastic() {
    for (std::size_t i = 0; i < character_->deformers().lattice_count(); ++i) {
      deform::ElasticSettings s = character_->deformers().spec(i).elastic;
      s.oscillator = elastic_.oscillator;
      s.integrator = elastic_.integrator;
      if (s.integrator == deform::Integrator::verlet) s.springs = deform::NeighbourSprings{};  // exact only
      character_->deformers().set_elastic(i, s);
    }
  }

  static void upload_static(sample::MeshRenderer& r, const deform::Mesh& m) {
    std::vector<glm::vec3> positions(m.vertex_count());
    for (std::size_t v = 0; v < m.vertex_count(); ++v) positions[v] = m.positions[m.vertex_point[v]];
    r.upload(positions, m.vertex_normals);
  }

  // The model's space in the world (the character node, then the upright turn).
  glm::mat4 character_world() const { return scene_.node(model_node_).world; }

  void handle_keys(int key) {
    if (key == GLFW_KEY_D) {  // LBS, DQS, DDM, LBS again
      if (ddm_) {
        ddm_ = false;
        character_->settings.skinning = deform::SkinningMethod::lbs;
      } else if (character_->settings.skinning == deform::SkinningMethod::dqs) {
        ddm_ = true;
      } else {
        character_->settings.skinning = deform::SkinningMethod::dqs;
      }
      apply_mush();
    }
    if (key == GLFW_KEY_S) show_skeleton_ = !show_skeleton_;
    if (key == GLFW_KEY_L)  // active limb, all, none, active again
      lattice_display_ = lattice_display_ == LatticeDisplay::active ? LatticeDisplay::all
                         : lattice_display_ == LatticeDisplay::all  ? LatticeDisplay::none
                                                                    : LatticeDisplay::active;
    if (key == GLFW_KEY_R) rebuild_character();
    if (key == GLFW_KEY_G) set_gpu(!gpu_);
    if (key == GLFW_KEY_C) fit_camera();
  }

  // The nearest scene point under the mouse: the character's current triangles (through the BVH) or the floor.
  std::optional<glm::vec3> pick(glm::vec2 pixel) {
    const glm::ivec2 size = window_.framebuffer_size();
    const deform::Ray ray = deform::ray_from_pixel(camera_.view(), camera_.projection(window_.aspect()), pixel,
                                                   glm::vec4(0, 0, size.x, size.y));
    std::optional<glm::vec3> best;
    float best_distance = std::numeric_limits<float>::infinity();
    // The character's triangles live in its node's frame: carry the ray there.
    const glm::mat4 to_local = glm::inverse(character_world());
    deform::Ray local{transform_point(to_local, ray.origin), glm::vec3(to_local * glm::vec4(ray.direction, 0.0f))};
    bvh_.refit(drawn_points());
    const deform::RayHit hit = bvh_.intersect(local);
    if (hit.hit) {
      const glm::vec3 p = transform_point(character_world(), local.origin + hit.distance * local.direction);
      best_distance = glm::length(p - ray.origin);
      best = p;
    }
    const float floor_y = scene_.node(floor_node_).world[3].y;
    if (std::abs(ray.direction.y) > 1e-6f) {
      const float t = (floor_y - ray.origin.y) / ray.direction.y;
      if (t > 0.0f && t < best_distance) best = ray.origin + t * ray.direction;
    }
    return best;
  }

  void begin_reach(glm::vec3 world_target) {
    const glm::vec3 local = transform_point(glm::inverse(character_world()), world_target);
    // The nearest limb whose lattices stretch reaches (the rig's reach effector among them); without lattices, the
    // nearest hand.
    std::int32_t best = deform::nearest_reach_effector(*character_, local);
    if (best < 0) {
      float best_distance = std::numeric_limits<float>::infinity();
      const deform::Skeleton& sk = character_->skeleton();
      for (std::size_t b = 0; b < sk.bone_count(); ++b) {
        std::string name = sk.bone(std::int32_t(b)).name;
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        if (name.find("hand") == std::string::npos) continue;
        const float d = glm::length(character_->bone_position(std::int32_t(b)) - local);
        if (d < best_distance) best_distance = d, best = std::int32_t(b);
      }
    }
    if (best < 0) return;
    effector_ = best;
    target_ = local;
    last_reach_ = character_->reach(effector_, target_);
    if (!last_reach_.status.ok() && character_->rig().reach_effector >= 0) {
      effector_ = character_->rig().reach_effector;
      last_reach_ = character_->reach(effector_, target_);
    }
    reaching_ = last_reach_.status.ok();
  }

  void handle_mouse(const sample::Input& in) {
    // The limb a click would move, under a mouse that moves freely over the scene: its lattices are the active ones.
    // Not in headless runs, whose pictures must not depend on where the display's cursor happens to be.
    if (options_.screenshot.empty() && lattice_display_ == LatticeDisplay::active &&
        in.mouse_delta != glm::vec2(0.0f) && !in.left_down && !in.right_down && !in.middle_down) {
      const auto p = pick(in.mouse);
      hovered_effector_ =
          p ? deform::nearest_reach_effector(*character_, transform_point(glm::inverse(character_world()), *p)) : -1;
    }
    if (in.left_pressed && in.shift) {  // the pole: the point clicked, in the model's space
      if (const auto p = pick(in.mouse)) {
        pole_ = transform_point(glm::inverse(character_world()), *p);
        use_pole_ = true;
        apply_reach_settings();
      }
    } else if (in.left_pressed) {
      if (const auto p = pick(in.mouse)) {
        begin_reach(*p);
        drag_depth_ = glm::dot(*p - camera_.eye(), glm::normalize(camera_.target - camera_.eye()));
      }
    } else if (in.left_down && reaching_ && in.mouse_delta != glm::vec2(0.0f)) {
      // Drag: the target slides on the plane facing the camera at the depth first clicked.
      const glm::ivec2 size = window_.framebuffer_size();
      const deform::Ray ray = deform::ray_from_pixel(camera_.view(), camera_.projection(window_.aspect()), in.mouse,
                                                     glm::vec4(0, 0, size.x, size.y));
      const glm::vec3 forward = glm::normalize(camera_.target - camera_.eye());
      const float along = glm::dot(ray.direction, forward);
      if (along > 1e-4f) {
        target_ = transform_point(
            glm::inverse(character_world()),
            ray.origin + ray.direction * (drag_depth_ - glm::dot(ray.origin - camera_.eye(), forward)) / along);
        last_reach_ = character_->reach(effector_, target_);
      }
    } else if (in.left_released) {
      release();
    }
  }

  // The lattices to draw this frame (lattice_shown_): all, none, or the active limb's: the lattices on the effector
  // and on the bones above it up to the first bone without one (hand, forearm and upper arm, not the spine's). The
  // active limb is the one reaching, else the one a click at the mouse would move, else the one that reached last.
  // No allocation.
  void mark_shown_lattices() {
    const deform::DeformerHierarchy& deformers = character_->deformers();
    const bool all = lattice_display_ == LatticeDisplay::all;
    std::fill(lattice_shown_.begin(), lattice_shown_.end(), char(all));
    if (lattice_display_ != LatticeDisplay::active) return;
    const std::int32_t limb = reaching_ ? effector_ : hovered_effector_ >= 0 ? hovered_effector_ : effector_;
    bool found = false;
    for (std::int32_t b = limb; b >= 0; b = character_->skeleton().bone(b).parent) {
      bool here = false;
      for (std::size_t l = 0; l < deformers.lattice_count(); ++l)
        if (deformers.spec(l).bone == b) lattice_shown_[l] = 1, here = true;
      if (found && !here) break;
      found |= here;
    }
  }

  void draw(std::span<const glm::vec3> normals) {
    scene_.node(ball_node_).translation = target_;
    scene_.update();
    const glm::mat4 view = camera_.view(), projection = camera_.projection(window_.aspect());
    const glm::vec3 eye = camera_.eye();
    if (!options_.bare) {
      floor_renderer_.draw(scene_.node(floor_node_).world, view, projection, eye);
      for (std::size_t i = 0; i < props_.size(); ++i)
        prop_renderers_[i]->draw(scene_.node(prop_nodes_[i]).world, view, projection, eye);
    }

    const deform::Mesh& mesh = character_->model().mesh;
    if (gpu_) {
      // Only the palette and the lattices' control points travel; the vertices never leave the GPU.
      const GLuint vertex_buffer = renderer_->vertex_buffer();
      deform::Status status =
          gpu_skinning_.skin_into(character_->settings.skinning, character_->palette(), vertex_buffer);
      if (status) status = gpu_fields_.apply_into(character_->deformers(), vertex_buffer);
      if (!status) {
        std::fprintf(stderr, "deform_viewer: GPU deformation refused: %s; deforming on the CPU\n", status.reason());
        set_gpu(false);
      }
    }
    if (!gpu_) {
      render_positions_.resize(mesh.vertex_count());
      const auto points = character_->positions();
      for (std::size_t v = 0; v < mesh.vertex_count(); ++v) render_positions_[v] = points[mesh.vertex_point[v]];
      renderer_->upload(render_positions_, normals.empty() ? character_->normals() : normals);
    }
    renderer_->draw(character_world(), view, projection, eye);
    if (options_.bare) return;
    if (reaching_) ball_renderer_.draw(scene_.node(ball_node_).world, view, projection, eye);

    const glm::mat4 to_world = character_world();
    mark_shown_lattices();
    if (lattice_display_ != LatticeDisplay::none) {
      for (std::size_t l = 0; l < character_->deformers().lattice_count(); ++l) {
        if (!lattice_shown_[l]) continue;
        const auto cps = character_->control_points(l);
        const glm::ivec3 n = character_->deformers().spec(l).degree + 1;
        const float stretch = character_->deformers().stretch(l) / std::max(1e-6f, character_->deformers().length(l));
        auto at = [&](int i, int j, int k) {
          return transform_point(to_world, cps[std::size_t(i + n.x * (j + n.y * k))]);
        };
        for (int k = 0; k < n.z; ++k)
          for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
              // Control point i of a stretched lattice moves by stretch · i/l along the bone: colour by that.
              const glm::vec3 c = heat(0.5f + 0.5f * stretch * float(i) / float(std::max(1, n.x - 1)) * 2.0f);
              overlay_.point(at(i, j, k), c, 6.0f);
              if (i + 1 < n.x) overlay_.line(at(i, j, k), at(i + 1, j, k), c);
              if (j + 1 < n.y) overlay_.line(at(i, j, k), at(i, j + 1, k), c);
              if (k + 1 < n.z) overlay_.line(at(i, j, k), at(i, j, k + 1), c);
            }
      }
      overlay_.flush(projection * view, false);
    }
    if (weight_bone_ >= 0 && std::size_t(weight_bone_) < character_->skeleton().bone_count()) {
      const auto points = drawn_points();
      const deform::SkinWeights& w = character_->model().weights;
      for (std::size_t i = 0; i < points.size() && i < w.size(); ++i)
        for (int k = 0; k < deform::max_influences; ++k)
          if (w.weights[i][k] > 0.0f && w.bones[i][k] == weight_bone_)
            overlay_.point(transform_point(to_world, points[i]), heat(w.weights[i][k]), 5.0f);
      overlay_.flush(projection * view, false);
    }
    if (show_skeleton_) {
      const deform::Skeleton& sk = character_->skeleton();
      for (std::size_t b = 0; b < sk.bone_count(); ++b) {
        const glm::vec3 head = transform_point(to_world, character_->bone_position(std::int32_t(b)));
        const std::int32_t parent = sk.bone(std::int32_t(b)).parent;
        if (parent >= 0)
          overlay_.line(transform_point(to_world, character_->bone_position(parent)), head,
                        glm::vec3(1.0f, 0.9f, 0.3f));
        overlay_.point(head, std::int32_t(b) == effector_ ? glm::vec3(1, 0.3f, 0.2f) : glm::vec3(1, 1, 1), 7.0f);
      }
    }
    if (show_skeleton_) {  // the spring chains as simulated: first head, then each bone's tail
      const deform::SpringChains& springs = character_->springs();
      const glm::vec3 green(0.3f, 1.0f, 0.4f);
      for (std::size_t c = 0; c < springs.chain_count(); ++c) {
        const auto chain = springs.points(c);
        for (std::size_t i = 0; i < chain.size(); ++i) {
          const glm::vec3 p = transform_point(to_world, chain[i]);
          if (i > 0) overlay_.line(transform_point(to_world, chain[i - 1]), p, green);
          overlay_.point(p, green, 6.0f);
        }
      }
    }
    if (reaching_) overlay_.point(transform_point(to_world, target_), glm::vec3(1.0f, 0.5f, 0.0f), 12.0f);
    if (show_skeleton_ && !options_.bare) draw_swing_twist_cones(to_world);
    if (use_pole_ && !options_.bare) {  // the pole gizmo: a point, and a line to the chain's middle while reaching
      const glm::vec3 pole = transform_point(to_world, pole_);
      overlay_.point(pole, glm::vec3(0.9f, 0.2f, 0.9f), 11.0f);
      if (reaching_) {
        const deform::Skeleton& sk = character_->skeleton();
        const std::int32_t middle = sk.bone(effector_).parent;
        if (middle >= 0)
          overlay_.line(transform_point(to_world, character_->bone_position(middle)), pole,
                        glm::vec3(0.9f, 0.2f, 0.9f));
      }
    }
    overlay_.flush(projection * view, true);
  }

  // The swing cones of the reach chain's joints (Character::reach_swing_twist): from each joint's head, lines to the
  // cone's rim — the directions its bone may point in — turned by its parent's current rotation (the pose's; what the
  // lattices carry is left out).
  void draw_swing_twist_cones(const glm::mat4& to_world) {
    const std::span<const std::int32_t> chain = character_->reach_chain();
    if (chain.empty() || character_->reach_swing_twist(0) == nullptr) return;
    const deform::Skeleton& sk = character_->skeleton();
    const deform::Pose& pose = character_->pose();
    world_rotations_.resize(sk.bone_count());
    for (const std::int32_t b : sk.order()) {
      const std::int32_t parent = sk.bone(b).parent;
      world_rotations_[std::size_t(b)] = (parent >= 0 ? world_rotations_[std::size_t(parent)] : glm::quat(1, 0, 0, 0)) *
                                         pose.rotations[std::size_t(b)];
    }
    const glm::vec3 cyan(0.2f, 0.9f, 1.0f);
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      const deform::SwingTwistLimits* limits = character_->reach_swing_twist(k);
      if (limits == nullptr) continue;
      const std::int32_t parent = sk.bone(chain[k]).parent;
      const glm::quat frame = parent >= 0 ? world_rotations_[std::size_t(parent)] : glm::quat(1, 0, 0, 0);
      const glm::vec3 head = character_->bone_position(chain[k]);
      const float length = 0.6f * glm::length(sk.bone(chain[k + 1]).bind_translation);
      const glm::vec3 side = glm::cross(limits->axis, limits->reference);
      glm::vec3 previous(0.0f);
      constexpr int steps = 24;
      for (int i = 0; i <= steps; ++i) {
        const float phi = glm::two_pi<float>() * float(i) / float(steps);
        const glm::vec3 swing =
            limits->swing1 * std::cos(phi) * limits->reference + limits->swing2 * std::sin(phi) * side;
        const float angle = glm::length(swing);
        const glm::quat turn = angle > 1e-6f ? glm::angleAxis(angle, swing / angle) : glm::quat(1, 0, 0, 0);
        const glm::vec3 rim = transform_point(to_world, head + frame * (turn * limits->axis) * length);
        if (i > 0) overlay_.line(previous, rim, cyan);
        if (i % 6 == 0) overlay_.line(transform_point(to_world, head), rim, cyan);
        previous = rim;
      }
    }
  }

  const Options& options_;
  sample::Window& window_;
  deform::Model base_model_;
  deform::Rig rig_;
  std::vector<deform::Animation> clips_;
  std::unique_ptr<deform::Character> character_;
  std::unique_ptr<sample::MeshRenderer> renderer_;
  glm::vec3 up_{0.0f, 1.0f, 0.0f};  // the model's up direction, turned onto +Y by the model node
  const bool gpu_available_;
  bool gpu_ = false;  // skinning and lattices on the GPU
  deform::GpuSkinning gpu_skinning_;
  deform::GpuLatticeFields gpu_fields_;
  std::vector<glm::vec3> gpu_bind_normals_;  // the character's bind normals per render vertex (set_gpu)
  std::vector<glm::vec3> gpu_points_;        // drawn_points()' read back
  std::vector<std::uint32_t> triangle_points_;
  std::vector<glm::vec3> render_positions_;
  deform::TriangleBvh bvh_;
  sample::Scene scene_;
  int world_node_ = -1, floor_node_ = -1, character_node_ = -1, model_node_ = -1, ball_node_ = -1;
  std::vector<int> prop_nodes_;
  deform::Mesh floor_mesh_, ball_mesh_;
  std::vector<std::unique_ptr<deform::Mesh>> props_;
  sample::MeshRenderer floor_renderer_, ball_renderer_;
  std::vector<std::unique_ptr<sample::MeshRenderer>> prop_renderers_;
  sample::OverlayRenderer overlay_;
  sample::OrbitCamera camera_;
  sample::OrbitCamera fitted_camera_;  // the camera fit_camera() chose last (C fits again)
  float panel_right_ = 350.0f;         // pixels: the right edge of the panel over the window's left (0: none)
  deform::ElasticSettings elastic_ = unset_elastic();
  int degree_ = 0;
  bool ddm_ = false;         // Direct Delta Mush skinning (the panel's DDM, D, --skinning ddm)
  int mush_iterations_ = 0;  // Delta Mush after the lattices (the panel's slider, --mush); 0: off
  bool reaching_ = false, show_skeleton_ = true;
  LatticeDisplay lattice_display_ = LatticeDisplay::active;
  std::vector<char> lattice_shown_;     // per lattice: drawn this frame (lattice_display_; sized by rebuild)
  std::int32_t hovered_effector_ = -1;  // the limb a click at the mouse would move (-1: none)
  int weight_bone_ = -1;                // the bone whose weights the weight map shows; -1: none
  bool playing_ = true;
  deform::StretchShape shape_;        // the panel's rubber shape, for every lattice
  float max_stretch_ = -1.0f;         // the panel's stretch bound (-1: the rig's, taken at the first build)
  glm::vec3 pole_{0.0f, 0.0f, 1.0f};  // the reach pole, model space (--pole, the panel, shift+click)
  bool use_pole_ = false;
  deform::Character::JointLimits reach_limits_ = deform::Character::JointLimits::euler;
  deform::Character::ReachSolver reach_solver_ = deform::Character::ReachSolver::ccd;  // (two-bone: Euler limits only)
  float soften_ = 0.0f;
  std::vector<glm::quat> world_rotations_;  // draw_swing_twist_cones' scratch
  int clip_ = -1;
  Clock::time_point long_frame_at_{};  // the last frame longer than the clamp: when, how long, simulated as
  float long_frame_ms_ = 0.0f, long_frame_simulated_ms_ = 0.0f;
  std::vector<const char*> clip_names_;      // "(none)", then each clip's name (the panel's list)
  deform::Pose bind_pose_, pose_, later_;    // the clip sampled now and a millisecond later, over the bind pose
  deform::Pose first_, second_;              // the two clips of a blend, before blending (sample_clip's scratch)
  int blend_clip_ = -1;                      // the clip blended with clip_ (-1: none)
  float blend_weight_ = 0.5f;                // its weight; clip_ has 1 - blend_weight_
  float speed_ = 1.0f;                       // playback rate
  bool jiggle_ = true;                       // lattices with inertia while a clip plays
  float inertia_ = 1.0f;                     // the scale of each lattice's tuned inertia
  bool cut_ = true;                          // the next frame's pose is a jump, not motion (see frame())
  deform::Bounds rest_bounds_;               // the bind pose, upright: its floor, its framing
  std::vector<deform::Bounds> clip_bounds_;  // each clip's sampled poses, upright (posed_bounds)
  float floor_height_ = 0.0f;                // the eye's height above a floor
  std::vector<char> morph_held_;             // per morph target: the panel (or --morph) holds its weight
  std::vector<float> morph_hold_;            // ... at this weight
  std::vector<float> morph_second_;          // the blended second clip's morph weights (sized once)
  std::vector<float> clip_floors_;           // the floor under each clip (lowest_height)
  float clip_time_ = 0.0f, deform_ms_ = 0.0f, drag_depth_ = 1.0f, pick_radius_ = 1.0f;
  std::int32_t effector_ = -1;
  glm::vec3 target_{0.0f};
  deform::ReachResult last_reach_;
};

}  // namespace

int main(int argc, char** argv) {
  const Options options = viewer::parse_options(argc, argv);
  const bool headless = !options.screenshot.empty();
  sample::Window window;
  if (!window.open({"libdeform viewer", options.width, options.height, headless})) {
    std::fprintf(stderr, "deform_viewer: cannot open an OpenGL 3.3 window%s\n",
                 std::getenv("DISPLAY") ? "" : " (no DISPLAY: run under xvfb-run, or use --screenshot with xvfb-run)");
    return 1;
  }
  try {
    Viewer viewer(options, window);
    if (headless) {
      // Fixed 60 Hz steps: the same command gives the same picture.
      for (int f = 0; f < options.frames; ++f) {
        if (options.reach && f == options.reach_at) viewer.reach_world(*options.reach);
        if (f == options.release_at) viewer.release();
        window.begin_frame();
        viewer.frame(1.0f / 60.0f);
        viewer.panel(0.0f);
        if (f + 1 == options.frames) {
          if (!window.save_png(options.screenshot)) {
            std::fprintf(stderr, "deform_viewer: cannot write %s\n", options.screenshot.c_str());
            return 1;
          }
        }
        window.end_frame();
      }
      const glm::vec3 e = viewer.effector_position();
      const glm::vec3 up = viewer.up();
      std::printf(
          "{\"screenshot\": \"%s\", \"frames\": %d, \"renderer\": \"%s\", \"gpu_lattices\": %s, "
          "\"up\": [%g, %g, %g], \"effector\": [%.5f, %.5f, %.5f], \"floor\": %.6f, \"lowest\": %.6f, "
          "\"morph_weights\": [%s], \"lattices_shown\": %d, \"floor_row\": %.1f}\n",
          options.screenshot.c_str(), options.frames, window.renderer_name().c_str(),
          viewer.gpu_lattices() ? "true" : "false", double(up.x), double(up.y), double(up.z), e.x, e.y, e.z,
          double(viewer.floor_y()), double(viewer.lowest_y()), viewer.morph_weights_text().c_str(),
          viewer.lattices_shown(), double(viewer.floor_row()));
      return 0;
    }
    // A frame longer than max_dt (a stall, a dragged window) is simulated as max_dt, so a stall never lands as one
    // big jump of the clip and the springs; the panel reports each such frame instead of it passing as slow motion.
    constexpr float max_dt = 0.1f;
    auto last = Clock::now();
    float frame_ms = 16.0f;
    while (!window.should_close()) {
      const auto now = Clock::now();
      const float took = std::chrono::duration<float>(now - last).count();
      const float dt = std::min(max_dt, took);
      last = now;
      frame_ms = 0.95f * frame_ms + 0.05f * took * 1000.0f;
      window.begin_frame();
      if (window.input().key_pressed == GLFW_KEY_ESCAPE) break;
      if (took > max_dt) viewer.frame_clamped(took, dt);
      viewer.frame(dt);
      viewer.panel(frame_ms);
      window.end_frame();
    }
  } catch (const deform::Error& e) {
    std::fprintf(stderr, "deform_viewer: %s\n", e.what());
    return 2;
  }
  return 0;
}
