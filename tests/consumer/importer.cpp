// An engine that asked for COMPONENTS import: the importer links and answers.
#include <cstdio>

#include <deform/import/import.hpp>

int main() {
  const bool ok = deform::is_importable("hero.glb") && !deform::is_importable("hero.sk");
  std::printf("import: %s\n", ok ? "ok" : "wrong");
  return ok ? 0 : 1;
}
