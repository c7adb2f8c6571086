// deform_web: the rubber-arm character in a browser (WebGL2), compiled with emscripten. The built-in character with
// a lattice on every limb: click a point of the character or the floor and the nearest hand or foot reaches for it by
// IK, stretching elastically when it is out of reach; drag and the target follows; release and the limb springs back.
// The built-in clips play with the jiggle (the lattices' inertia, the ponytail's spring chain). What deforms is the
// libdeform facade (deform::Character), as in the native viewer (samples/viewer); this file draws it with the samples'
// renderers (framework/render.hpp, GLSL ES 3.0 here) and turns the canvas' mouse events into calls. The panel is HTML
// (index.html): its controls call web_set(name, value); web_state() reports what the page shows as JSON (the panel's
// status line and the browser test, tests/web).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "render.hpp"  // the GL header first

#include <emscripten/emscripten.h>
#include <emscripten/html5.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/picking.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "shapes.hpp"

namespace {

constexpr const char* canvas_id = "#canvas";

glm::vec3 heat(float t) {  // 0 blue, 0.5 green, 1 red (the native viewer's lattice colours)
  t = std::clamp(t, 0.0f, 1.0f);
  return t < 0.5f ? glm::mix(glm::vec3(0.2f, 0.4f, 1.0f), glm::vec3(0.2f, 1.0f, 0.3f), 2.0f * t)
                  : glm::mix(glm::vec3(0.2f, 1.0f, 0.3f), glm::vec3(1.0f, 0.2f, 0.1f), 2.0f * t - 1.0f);
}

// The mouse as the canvas' callbacks leave it between two frames (CSS pixels, which are the canvas' pixels: the page
// sizes its drawing buffer to its CSS size).
struct Mouse {
  glm::vec2 at{0.0f}, last{0.0f};
  bool left = false, right = false, middle = false, shift = false;
  bool pressed = false, released = false;  // since the last frame
  float scroll = 0.0f;
};

class WebViewer {
 public:
  WebViewer()
      : model_(deform::builtin_character()),
        rig_(deform::builtin_full_rig(model_)),
        clips_(deform::builtin_clips(model_)) {
    rebuild_character();
    const deform::Mesh& mesh = model_.mesh;
    renderer_.create(model_.mesh);  // the viewer's own copy: it outlives every character rebuild_character() makes
    constexpr int texture_size = 512;
    const std::vector<std::uint8_t> pixels = deform::builtin_texture(texture_size);
    renderer_.set_texture_rgb(0, texture_size, texture_size, pixels.data());
    render_positions_.resize(mesh.vertex_count());

    rest_bounds_ = deform::compute_bounds(mesh.positions);
    const glm::vec3 size = rest_bounds_.max - rest_bounds_.min;
    const float extent = std::max({size.x, size.y, size.z});
    floor_mesh_ = sample::make_floor(extent * 4.0f, 16);
    ball_mesh_ = sample::make_sphere(extent * 0.025f, 12, 24, glm::vec3(1.0f, 0.55f, 0.1f));
    floor_renderer_.create(floor_mesh_);
    upload_static(floor_renderer_, floor_mesh_);
    ball_renderer_.create(ball_mesh_);
    upload_static(ball_renderer_, ball_mesh_);
    overlay_.create();
    floor_y_ = rest_bounds_.min.y;
    fit_camera(1.6f);
  }

  Mouse& mouse() { return mouse_; }

  // One animation frame: the canvas' size, the input since the last frame, the clip, the character, the picture.
  void frame(float dt) {
    double css_w = 0.0, css_h = 0.0;
    emscripten_get_element_css_size(canvas_id, &css_w, &css_h);
    const glm::ivec2 size(std::max(1, int(css_w)), std::max(1, int(css_h)));
    if (size != size_) {
      emscripten_set_canvas_element_size(canvas_id, size.x, size.y);
      if (size_.x == 0) fit_camera(float(size.x) / float(size.y));
      size_ = size;
    }
    sample::Input in;
    in.mouse = mouse_.at;
    in.mouse_delta = mouse_.at - mouse_.last;
    in.left_down = mouse_.left, in.left_pressed = mouse_.pressed, in.left_released = mouse_.released;
    in.right_down = mouse_.right, in.middle_down = mouse_.middle, in.shift = mouse_.shift;
    in.scroll = mouse_.scroll;
    mouse_.last = mouse_.at;
    mouse_.pressed = mouse_.released = false;
    mouse_.scroll = 0.0f;
    camera_.handle(in, size_);
    handle_mouse(in);

    if (clip_ >= 0) {
      // The pose now and where it heads a millisecond later, so that the lattices' inertia and the spring chains
      // follow the motion between frames; then the reach again, on this frame's pose (as the native viewer does).
      constexpr float lead = 1e-3f;
      const deform::Animation& clip = clips_[std::size_t(clip_)];
      const float rate = playing_ ? speed_ : 0.0f;
      clip_time_ = clip.local_time(clip_time_ + dt * rate);
      sample_clip(clip_time_, pose_);
      sample_clip(clip_time_ + lead * rate, later_);
      (void)character_->set_pose(pose_, later_, lead);
      if (reaching_) last_reach_ = character_->reach(effector_, target_);
    }
    if (cut_) {  // a new clip or character: the pose jumps, which a zero step takes as a cut, not motion
      (void)character_->update(0.0f);
      cut_ = false;
    }
    const double start = emscripten_get_now();
    (void)character_->update(dt);
    const auto normals = character_->normals();
    deform_ms_ = 0.9f * deform_ms_ + 0.1f * float(emscripten_get_now() - start);
    draw(normals);
  }

  // The panel's controls (index.html); an unknown name or a value out of range changes nothing.
  void set(std::string_view name, float v) {
    if (!std::isfinite(v)) return;
    if (name == "clip") select_clip(int(v) >= -1 && int(v) < int(clips_.size()) ? int(v) : -1);
    else if (name == "playing") playing_ = v != 0.0f;
    else if (name == "speed") speed_ = std::clamp(v, 0.0f, 2.0f);
    else if (name == "jiggle") jiggle_ = v != 0.0f, apply_motion();
    else if (name == "inertia") inertia_ = std::clamp(v, 0.0f, 1.0f), apply_motion();
    else if (name == "stiffness") stiffness_ = std::clamp(v, 5.0f, 1000.0f), apply_elastic();
    else if (name == "damping") damping_ = std::clamp(v, 0.0f, 2.0f), apply_elastic();
    else if (name == "max_stretch") {
      max_stretch_ = std::clamp(v, 0.0f, 10.0f);
      (void)character_->set_max_stretch(max_stretch_);
    } else if (name == "volume") shape_.volume = std::clamp(v, 0.0f, 1.0f), apply_shape();
    else if (name == "dqs")
      character_->settings.skinning = v != 0.0f ? deform::SkinningMethod::dqs : deform::SkinningMethod::lbs;
    else if (name == "skeleton") show_skeleton_ = v != 0.0f;
    else if (name == "lattices") show_lattices_ = v != 0.0f;
    else if (name == "bare") bare_ = v != 0.0f;  // the character alone: no floor, ball or overlays (pixel tests)
    else if (name == "camera") fit_camera(aspect());
    else if (name == "reset") rebuild_character();
  }

  float get(std::string_view name) const {
    if (name == "clip") return float(clip_);
    if (name == "stiffness") return stiffness_;
    if (name == "damping") return damping_;
    if (name == "inertia") return inertia_;
    if (name == "max_stretch") return max_stretch_;
    if (name == "volume") return shape_.volume;
    if (name == "stretch") return character_->stretch();
    return std::numeric_limits<float>::quiet_NaN();
  }

  // What the page shows, as JSON: the panel's status line and the browser test's checks. The effector's pixel is
  // where the reaching hand (or foot) is drawn, from the canvas' top-left.
  const char* state() {
    const glm::vec3 hand = effector_ >= 0 ? character_->bone_position(effector_) : glm::vec3(0.0f);
    const glm::vec4 viewport(0.0f, 0.0f, float(size_.x), float(size_.y));
    const glm::vec3 pixel = glm::project(hand, camera_.view(), camera_.projection(aspect()), viewport);
    const std::string clip = clip_ >= 0 ? clips_[std::size_t(clip_)].name : std::string("none");
    // Where the left hand's wrist is drawn (the browser test presses there to grab the arm).
    const std::int32_t hand_l = character_->skeleton().find("hand_l");
    const glm::vec3 wrist = glm::project(hand_l >= 0 ? character_->bone_position(hand_l) : glm::vec3(0.0f),
                                         camera_.view(), camera_.projection(aspect()), viewport);
    std::snprintf(state_, sizeof state_,
                  "{\"frames\": %d, \"reaching\": %s, \"effector\": \"%s\", \"stretch\": %.4f, \"residual\": %.4f, "
                  "\"effector_pixel\": [%.1f, %.1f], \"hand_l_pixel\": [%.1f, %.1f], \"clip\": \"%s\", "
                  "\"clip_time\": %.3f, \"deform_ms\": %.3f, "
                  "\"points\": %zu, \"bones\": %zu, \"lattices\": %zu, \"canvas\": [%d, %d]}",
                  frames_, reaching_ ? "true" : "false",
                  effector_ >= 0 ? character_->skeleton().bone(effector_).name.c_str() : "",
                  double(character_->stretch()), double(last_reach_.residual), double(pixel.x),
                  double(float(size_.y) - pixel.y), double(wrist.x), double(float(size_.y) - wrist.y), clip.c_str(),
                  double(clip_time_), double(deform_ms_), model_.mesh.point_count(), model_.skeleton.bone_count(),
                  character_->deformers().lattice_count(), size_.x, size_.y);
    return state_;
  }

 private:
  float aspect() const { return size_.y > 0 ? float(size_.x) / float(size_.y) : 1.0f; }

  // The camera on the standing character from a little above and to its right, its box within 80% of the view.
  void fit_camera(float aspect) {
    const glm::vec3 size = rest_bounds_.max - rest_bounds_.min;
    camera_ = sample::OrbitCamera{};
    camera_.target = 0.5f * (rest_bounds_.min + rest_bounds_.max);
    camera_.yaw = 0.35f;
    camera_.pitch = 0.12f;
    const float tan_y = std::tan(0.5f * camera_.fov_y);
    camera_.distance =
        0.5f * size.z + std::max(0.5f * size.y / (0.8f * tan_y), 0.5f * size.x / (0.8f * tan_y * aspect));
    camera_.floor = floor_y_ + 0.01f * size.y;
  }

  void rebuild_character() {
    deform::Rig rig = rig_;
    if (stiffness_ <= 0.0f && !rig.lattices.empty()) {  // the rig's springs, the first time
      stiffness_ = rig.lattices.front().elastic.oscillator.stiffness;
      damping_ = rig.lattices.front().elastic.oscillator.damping_ratio;
    }
    character_ = std::make_unique<deform::Character>(model_, rig);
    triangle_points_.resize(model_.mesh.triangles.size());
    for (std::size_t i = 0; i < model_.mesh.triangles.size(); ++i)
      triangle_points_[i] = model_.mesh.vertex_point[model_.mesh.triangles[i]];
    (void)character_->update(0.0f);
    bvh_.build(character_->positions(), triangle_points_);
    bind_pose_ = character_->skeleton().bind_pose();
    pose_ = later_ = bind_pose_;  // sized once: sample_clip copies into them
    reaching_ = false;
    effector_ = -1;
    if (max_stretch_ < 0.0f) max_stretch_ = character_->rig().max_stretch;
    (void)character_->set_max_stretch(max_stretch_);
    apply_elastic();
    apply_shape();
    apply_motion();
    if (clip_ < 0) (void)character_->set_pose(bind_pose_);
    cut_ = true;
  }

  void select_clip(int clip) {
    clip_ = clip;
    clip_time_ = 0.0f;
    if (clip_ < 0) (void)character_->set_pose(bind_pose_);
    cut_ = true;
    apply_motion();
  }

  // The clip at time t over the bind pose (bones without a channel keep it). No allocation: `into` is sized.
  void sample_clip(float t, deform::Pose& into) const {
    std::copy(bind_pose_.rotations.begin(), bind_pose_.rotations.end(), into.rotations.begin());
    std::copy(bind_pose_.translations.begin(), bind_pose_.translations.end(), into.translations.begin());
    deform::SamplingJob sampling;
    sampling.animation = &clips_[std::size_t(clip_)];
    sampling.time = t;
    sampling.rotations = into.rotations;
    sampling.translations = into.translations;
    (void)sampling.run();  // cannot fail: the built-in clips are made for this skeleton
  }

  // The jiggle: the lattices lag behind their bones while a clip plays; on a still body none, so that a reach is the
  // plain rubber arm. The rig's gravity on the lattices is kept.
  void apply_motion() {
    const float inertia = clip_ >= 0 && jiggle_ ? inertia_ : 0.0f;
    for (std::size_t l = 0; l < character_->deformers().lattice_count(); ++l) {
      deform::LatticeMotion motion = character_->deformers().spec(l).motion;
      motion.inertia = inertia;
      character_->deformers().set_motion(l, motion);
    }
  }

  void apply_elastic() {
    for (std::size_t l = 0; l < character_->deformers().lattice_count(); ++l) {
      deform::ElasticSettings s = character_->deformers().spec(l).elastic;
      s.oscillator.stiffness = stiffness_;
      s.oscillator.damping_ratio = damping_;
      character_->deformers().set_elastic(l, s);
    }
  }

  void apply_shape() {
    for (std::size_t l = 0; l < character_->deformers().lattice_count(); ++l)
      character_->deformers().set_shape(l, shape_);
  }

  // The nearest scene point under the mouse: the character's current triangles (through the BVH) or the floor.
  std::optional<glm::vec3> pick(glm::vec2 pixel) {
    const deform::Ray ray =
        deform::ray_from_pixel(camera_.view(), camera_.projection(aspect()), pixel, glm::vec4(0, 0, size_.x, size_.y));
    std::optional<glm::vec3> best;
    float best_distance = std::numeric_limits<float>::infinity();
    bvh_.refit(character_->positions());
    const deform::RayHit hit = bvh_.intersect(ray);
    if (hit.hit) best = ray.origin + hit.distance * ray.direction, best_distance = hit.distance;
    if (std::abs(ray.direction.y) > 1e-6f) {
      const float t = (floor_y_ - ray.origin.y) / ray.direction.y;
      if (t > 0.0f && t < best_distance) best = ray.origin + t * ray.direction;
    }
    return best;
  }

  void begin_reach(glm::vec3 target) {
    const std::int32_t limb = deform::nearest_reach_effector(*character_, target);
    if (limb < 0) return;
    effector_ = limb;
    target_ = target;
    last_reach_ = character_->reach(effector_, target_);
    reaching_ = last_reach_.status.ok();
  }

  void release() {
    if (reaching_) character_->release();
    reaching_ = false;
  }

  void handle_mouse(const sample::Input& in) {
    if (in.left_pressed && !in.shift) {
      if (const auto p = pick(in.mouse)) {
        begin_reach(*p);
        drag_depth_ = glm::dot(*p - camera_.eye(), glm::normalize(camera_.target - camera_.eye()));
      }
    } else if (in.left_down && reaching_ && in.mouse_delta != glm::vec2(0.0f)) {
      // Drag: the target slides on the plane facing the camera at the depth first clicked.
      const deform::Ray ray = deform::ray_from_pixel(camera_.view(), camera_.projection(aspect()), in.mouse,
                                                     glm::vec4(0, 0, size_.x, size_.y));
      const glm::vec3 forward = glm::normalize(camera_.target - camera_.eye());
      const float along = glm::dot(ray.direction, forward);
      if (along > 1e-4f) {
        target_ = ray.origin + ray.direction * (drag_depth_ - glm::dot(ray.origin - camera_.eye(), forward)) / along;
        last_reach_ = character_->reach(effector_, target_);
      }
    }
    if (in.left_released) release();
  }

  static void upload_static(sample::MeshRenderer& r, const deform::Mesh& m) {
    std::vector<glm::vec3> positions(m.vertex_count());
    for (std::size_t v = 0; v < m.vertex_count(); ++v) positions[v] = m.positions[m.vertex_point[v]];
    r.upload(positions, m.vertex_normals);
  }

  void draw(std::span<const glm::vec3> normals) {
    ++frames_;
    glViewport(0, 0, size_.x, size_.y);
    glClearColor(0.16f, 0.18f, 0.22f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    const glm::mat4 view = camera_.view(), projection = camera_.projection(aspect());
    const glm::vec3 eye = camera_.eye();
    const glm::mat4 identity(1.0f);
    if (!bare_) floor_renderer_.draw(glm::translate(identity, glm::vec3(0.0f, floor_y_, 0.0f)), view, projection, eye);

    const deform::Mesh& mesh = character_->model().mesh;
    const auto points = character_->positions();
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) render_positions_[v] = points[mesh.vertex_point[v]];
    renderer_.upload(render_positions_, normals);
    renderer_.draw(identity, view, projection, eye);
    if (bare_) return;
    if (reaching_) ball_renderer_.draw(glm::translate(identity, target_), view, projection, eye);

    // The reaching limb's lattices (or the last one's), coloured by how far each control point is carried along
    // the bone by the stretch; the skeleton on top.
    if (show_lattices_ && effector_ >= 0) {
      const deform::DeformerHierarchy& deformers = character_->deformers();
      for (std::size_t l = 0; l < deformers.lattice_count(); ++l) {
        if (!on_limb(deformers.spec(l).bone)) continue;
        const auto cps = character_->control_points(l);
        const glm::ivec3 n = deformers.spec(l).degree + 1;
        const float stretch = deformers.stretch(l) / std::max(1e-6f, deformers.length(l));
        auto at = [&](int i, int j, int k) { return cps[std::size_t(i + n.x * (j + n.y * k))]; };
        for (int k = 0; k < n.z; ++k)
          for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
              const glm::vec3 c = heat(0.5f + stretch * float(i) / float(std::max(1, n.x - 1)));
              overlay_.point(at(i, j, k), c, 5.0f);
              if (i + 1 < n.x) overlay_.line(at(i, j, k), at(i + 1, j, k), c);
              if (j + 1 < n.y) overlay_.line(at(i, j, k), at(i, j + 1, k), c);
              if (k + 1 < n.z) overlay_.line(at(i, j, k), at(i, j, k + 1), c);
            }
      }
      overlay_.flush(projection * view, false);
    }
    if (show_skeleton_) {
      const deform::Skeleton& sk = character_->skeleton();
      for (std::size_t b = 0; b < sk.bone_count(); ++b) {
        const glm::vec3 head = character_->bone_position(std::int32_t(b));
        const std::int32_t parent = sk.bone(std::int32_t(b)).parent;
        if (parent >= 0) overlay_.line(character_->bone_position(parent), head, glm::vec3(1.0f, 0.9f, 0.3f));
        overlay_.point(head, std::int32_t(b) == effector_ ? glm::vec3(1, 0.3f, 0.2f) : glm::vec3(1), 6.0f);
      }
    }
    if (reaching_) overlay_.point(target_, glm::vec3(1.0f, 0.5f, 0.0f), 12.0f);
    overlay_.flush(projection * view, true);
  }

  // True when `bone` is the effector or one of the bones above it that carry a lattice, up to the first without
  // one (hand, forearm and upper arm, not the spine).
  bool on_limb(std::int32_t bone) const {
    const deform::DeformerHierarchy& deformers = character_->deformers();
    for (std::int32_t b = effector_; b >= 0; b = character_->skeleton().bone(b).parent) {
      bool carries = false;
      for (std::size_t l = 0; l < deformers.lattice_count(); ++l) carries |= deformers.spec(l).bone == b;
      if (!carries) return false;
      if (b == bone) return true;
    }
    return false;
  }

  deform::Model model_;
  deform::Rig rig_;
  std::vector<deform::Animation> clips_;
  std::unique_ptr<deform::Character> character_;
  sample::MeshRenderer renderer_, floor_renderer_, ball_renderer_;
  sample::OverlayRenderer overlay_;
  sample::OrbitCamera camera_;
  deform::Mesh floor_mesh_, ball_mesh_;
  deform::Bounds rest_bounds_;
  deform::TriangleBvh bvh_;
  std::vector<std::uint32_t> triangle_points_;
  std::vector<glm::vec3> render_positions_;
  deform::Pose bind_pose_, pose_, later_;
  deform::ReachResult last_reach_;
  deform::StretchShape shape_;
  Mouse mouse_;
  glm::ivec2 size_{0};
  glm::vec3 target_{0.0f};
  std::int32_t effector_ = -1;
  int clip_ = -1, frames_ = 0;
  float clip_time_ = 0.0f, speed_ = 1.0f, inertia_ = 1.0f, stiffness_ = 0.0f, damping_ = 0.0f, max_stretch_ = -1.0f;
  float floor_y_ = 0.0f, drag_depth_ = 1.0f, deform_ms_ = 0.0f;
  bool reaching_ = false, playing_ = true, jiggle_ = true, cut_ = true, show_skeleton_ = false, show_lattices_ = true;
  bool bare_ = false;
  char state_[640] = {};
};

WebViewer* viewer = nullptr;
double last_frame_ms = 0.0;

EM_BOOL on_mouse(int type, const EmscriptenMouseEvent* e, void*) {
  Mouse& m = viewer->mouse();
  if (type != EMSCRIPTEN_EVENT_MOUSEUP) m.at = glm::vec2(float(e->targetX), float(e->targetY));  // (up: the page's)
  m.shift = e->shiftKey;
  const bool down = type == EMSCRIPTEN_EVENT_MOUSEDOWN;
  if (type == EMSCRIPTEN_EVENT_MOUSEDOWN || type == EMSCRIPTEN_EVENT_MOUSEUP) {
    if (e->button == 0) {
      if (down && !m.left) m.pressed = true;
      if (!down && m.left) m.released = true;
      m.left = down;
    }
    if (e->button == 1) m.middle = down;
    if (e->button == 2) m.right = down;
  }
  return EM_TRUE;
}

EM_BOOL on_wheel(int, const EmscriptenWheelEvent* e, void*) {
  viewer->mouse().scroll -= float(e->deltaY > 0.0 ? 1 : e->deltaY < 0.0 ? -1 : 0);
  return EM_TRUE;
}

// A frame longer than 0.1 s (a hidden tab, a stall) is simulated as 0.1 s, never as one big jump of the springs.
void animation_frame() {
  const double now = emscripten_get_now();
  const float dt = last_frame_ms > 0.0 ? std::min(0.1f, float(now - last_frame_ms) / 1000.0f) : 1.0f / 60.0f;
  last_frame_ms = now;
  viewer->frame(dt);
}

}  // namespace

extern "C" {
EMSCRIPTEN_KEEPALIVE void web_set(const char* name, float value) {
  if (viewer && name) viewer->set(name, value);
}
EMSCRIPTEN_KEEPALIVE float web_get(const char* name) {
  return viewer && name ? viewer->get(name) : std::numeric_limits<float>::quiet_NaN();
}
EMSCRIPTEN_KEEPALIVE const char* web_state() { return viewer ? viewer->state() : "{}"; }
}

int main() {
  EmscriptenWebGLContextAttributes attributes;
  emscripten_webgl_init_context_attributes(&attributes);
  attributes.majorVersion = 2;  // WebGL2: OpenGL ES 3.0, GLSL ES 3.00
  attributes.minorVersion = 0;
  attributes.antialias = EM_TRUE;
  attributes.preserveDrawingBuffer = EM_TRUE;  // screenshots of the canvas between frames
  const EMSCRIPTEN_WEBGL_CONTEXT_HANDLE context = emscripten_webgl_create_context(canvas_id, &attributes);
  if (context <= 0) {
    std::fprintf(stderr, "deform_web: this browser gives no WebGL2 context (%d)\n", int(context));
    return 1;
  }
  emscripten_webgl_make_context_current(context);
  try {
    viewer = new WebViewer();  // lives as long as the page
  } catch (const deform::Error& e) {
    std::fprintf(stderr, "deform_web: %s\n", e.what());
    return 1;
  }
  emscripten_set_mousedown_callback(canvas_id, nullptr, EM_FALSE, on_mouse);
  emscripten_set_mousemove_callback(canvas_id, nullptr, EM_FALSE, on_mouse);
  // Released anywhere on the page: a drag that leaves the canvas still lets go.
  emscripten_set_mouseup_callback(EMSCRIPTEN_EVENT_TARGET_DOCUMENT, nullptr, EM_FALSE, on_mouse);
  emscripten_set_wheel_callback(canvas_id, nullptr, EM_FALSE, on_wheel);
  emscripten_set_main_loop(animation_frame, 0, false);  // requestAnimationFrame
  return 0;
}
