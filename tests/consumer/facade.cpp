// An engine that links deform::deform and drives the facade: the built-in character reaches and stretches. The
// quick start at the top of deform/character/character.hpp, with the facade's one include and nothing else.
#include <cstdio>

#include <deform/deform.hpp>

int main() {
  deform::Character hero = deform::make_builtin_character();  // extras: the built-in model and its rig
  const deform::ReachResult reach = hero.reach(hero.skeleton().find("hand_l"), {1.6f, 1.5f, 0.3f});
  for (int frame = 0; frame < 120; ++frame)
    if (!hero.update(1.0f / 60.0f)) return 1;
  std::printf("facade: reach %s, stretch %.3f\n", reach.status.reason(), hero.stretch());
  return reach.status && hero.stretch() > 0.0f ? 0 : 1;
}
