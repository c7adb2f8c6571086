// elastic_arm: the thesis' headline behaviour through the Character facade, in a dozen calls. Every three seconds
// the left hand reaches for a point beyond its reach: IK turns the arm toward it and the elastic lattices stretch it
// the rest of the way; a second and a half later it lets go and the arm springs back with a damped oscillation.
#include <cmath>

#include "deform/character/character.hpp"
#include "deform/deform.hpp"
#include "deform/extras/builtin.hpp"
#include "sample_app.hpp"

int main(int argc, char** argv) {
  deform::Character hero = deform::make_builtin_character();  // the built-in rig: 3 elastic lattices on the left arm
  const std::int32_t hand = hero.skeleton().find("hand_l");
  const glm::vec3 targets[] = {{1.5f, 1.7f, 0.3f}, {1.1f, 2.1f, 0.6f}, {1.4f, 1.1f, 0.7f}};
  sample::PointMeshRenderer renderer;
  int last_phase = -1;

  return sample::run_sample(
      argc, argv, "libdeform: elastic arm", [&] { renderer.create(hero.model().mesh); },
      [&](const sample::Frame& f) {
        const int phase = int(f.time / 1.5f);  // even: reaching, odd: released
        if (phase != last_phase) {
          if (phase % 2 == 0) hero.reach(hand, targets[(phase / 2) % 3]);
          else hero.release();
          last_phase = phase;
        }
        hero.update(f.dt);
        renderer.draw(hero.positions(), f);
        if (phase % 2 == 0) f.overlay->point(targets[(phase / 2) % 3], glm::vec3(1.0f, 0.5f, 0.0f), 12.0f);
        for (std::size_t l = 0; l < hero.deformers().lattice_count(); ++l)
          for (const glm::vec3& p : hero.control_points(l)) f.overlay->point(p, glm::vec3(0.3f, 1.0f, 0.4f), 4.0f);
      });
}
