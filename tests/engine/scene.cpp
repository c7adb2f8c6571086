// The engine's scene (tests/engine/CMakeLists.txt), through libdeform's public API only: the built-in character
// reaches for a far point with its left hand (IK, then the arm stretches elastically to cover the rest), is
// released (the stretch springs back, a damped oscillation), then walks (the built-in walk clip, every lattice with
// its body part's tuned inertia: the flesh jiggles, the ponytail swings), at a fixed 60 frames per second.
//
//   engine_scene OUT.txt
//
// Writes the positions (one per mesh point) and the normals (one per render vertex) of the frames in `kept` to
// OUT.txt, atomically, as text: the same scene compiled for another target (aarch64, Windows, WebAssembly) is
// compared with x86-64's by compare_scene.py. Fails (exit 1, naming what) when the scene is not what it says: the
// arm must be stretched while reaching, back to its length once released and settled, and every value finite.
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <exception>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"

namespace {

constexpr int rate = 60;                      // frames per second
constexpr int release_frame = 60;             // released after 1 s of reaching
constexpr int walk_frame = 150;               // walks from 2.5 s (1.5 s after the release: settled)
constexpr int last_frame = 240;               // 1.5 s of walking
const glm::vec3 far_point{1.6f, 1.5f, 0.3f};  // beyond the left arm's reach from the bind pose
// Stretching (the overshoot), held, springing back, settled, walking (the first steps, then in stride).
constexpr int kept[] = {15, 60, 70, 90, 150, 165, 200, 240};

struct SceneError : std::exception {
  explicit SceneError(std::string text) : what_(std::move(text)) {}
  const char* what() const noexcept override { return what_.c_str(); }
  std::string what_;
};

void check(deform::Status status, const char* what) {
  if (!status) throw SceneError(std::string(what) + ": " + status.reason());
}

void append(std::string& out, const char* tag, glm::vec3 v) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw SceneError(std::string("a ") + (tag[0] == 'p' ? "position" : "normal") + " is not finite");
  char line[96];
  // 9 significant digits: a float read back is the same float.
  const int n = std::snprintf(line, sizeof line, "%s %.9g %.9g %.9g\n", tag, double(v.x), double(v.y), double(v.z));
  out.append(line, std::size_t(n));
}

// The clip at `seconds` and a millisecond later, so that the lattices and the ponytail feel its motion
// (Character::set_pose with a lead, as the deform CLI and the viewer play clips).
void pose_walk(deform::Character& hero, const deform::Animation& walk, float seconds, deform::Pose& now,
               deform::Pose& later, const deform::Pose& bind) {
  constexpr float lead = 1e-3f;
  for (deform::Pose* pose : {&now, &later}) {
    *pose = bind;
    deform::SamplingJob job;
    job.animation = &walk;
    job.time = pose == &now ? seconds : seconds + lead;
    job.rotations = pose->rotations;
    job.translations = pose->translations;
    check(job.run(), "sampling the walk");
  }
  check(hero.set_pose(now, later, lead), "posing the walk");
}

std::string run() {
  deform::Model model = deform::builtin_character();
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& spec : rig.lattices)  // the tuned jiggle (builtin_rig keeps the inertia at 0)
    spec.motion = deform::default_lattice_motion(deform::builtin_body_part(spec.name));
  const deform::Animation walk = deform::builtin_walk(model);
  deform::Character hero(std::move(model), rig);
  const std::int32_t hand = hero.skeleton().find("hand_l");
  const deform::Pose bind = hero.skeleton().bind_pose();
  deform::Pose now = bind, later = bind;

  const deform::ReachResult reach = hero.reach(hand, far_point);
  check(reach.status, "reaching");
  if (!(reach.stretch > 0.1f)) throw SceneError("the far point asks for no stretch: it is not far");
  check(hero.update(0.0f), "the first frame");

  std::string out =
      "# libdeform engine scene: the built-in character reaching for (1.6, 1.5, 0.3), released at "
      "frame " +
      std::to_string(release_frame) + ", walking from frame " + std::to_string(walk_frame) + ", " +
      std::to_string(rate) + " frames per second\n";
  // How far the hand is from the point: held (the stretch covers what IK left), and settled after the release
  // (back to what IK alone reached: reach.residual).
  float held_gap = 0.0f, settled_gap = 0.0f;
  const auto gap = [&] { return glm::length(hero.bone_position(hand) - far_point); };
  const float dt = 1.0f / float(rate);
  std::size_t next = 0;
  for (int frame = 1; frame <= last_frame; ++frame) {
    if (frame >= walk_frame) pose_walk(hero, walk, float(frame - walk_frame) * dt, now, later, bind);
    check(hero.update(dt), "a frame");
    if (frame == release_frame) {
      held_gap = gap();
      hero.release();
    }
    if (frame == walk_frame - 1) settled_gap = gap();
    if (next < std::size(kept) && frame == kept[next]) {
      ++next;
      const auto positions = hero.positions();
      const auto normals = hero.normals();
      out += "frame " + std::to_string(frame) + " positions " + std::to_string(positions.size()) + " normals " +
             std::to_string(normals.size()) + "\n";
      for (const glm::vec3& p : positions) append(out, "p", p);
      for (const glm::vec3& n : normals) append(out, "n", n);
    }
  }
  // The scene as described: the stretched arm holds the hand at the point (within a tenth of what IK left), and
  // released, the arm springs back to its length: the hand where IK alone put it (within 2% of that distance).
  std::printf(
      "reach: IK left %.4f m, stretch asked %.4f m; the hand %.4f m from the point at frame %d, %.4f m at "
      "frame %d; %zu frames kept\n",
      double(reach.residual), double(reach.stretch), double(held_gap), release_frame, double(settled_gap),
      walk_frame - 1, std::size(kept));
  if (!(held_gap < 0.1f * reach.residual)) throw SceneError("the stretched arm does not hold the hand at the point");
  if (!(std::abs(settled_gap - reach.residual) < 0.02f * reach.residual))
    throw SceneError("released, the arm has not sprung back to its length");
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: engine_scene OUT.txt\n");
    return 2;
  }
  try {
    deform::write_file_atomic(argv[1], run());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "engine_scene: %s\n", e.what());
    return 1;
  }
  return 0;
}
