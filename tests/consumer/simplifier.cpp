// An engine that asked for COMPONENTS simplify: the built-in character's mesh simplified to a quarter.
#include <cstdio>

#include <deform/extras/builtin.hpp>
#include <deform/simplify/simplify.hpp>

int main() {
  const deform::Model model = deform::builtin_character();
  const deform::SimplifiedModel simple = deform::simplify_model(model, {0.25f, 0.05f});
  const bool ok = simple.model.mesh.triangle_count() < model.mesh.triangle_count() / 2 &&
                  simple.source_point.size() == simple.model.mesh.point_count();
  std::printf("simplify: %s\n", ok ? "ok" : "wrong");
  return ok ? 0 : 1;
}
