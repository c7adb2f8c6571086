// Links the installed libdeform and checks one real computation through its public API.
#include <cstdio>

#include <deform/error.hpp>
#include <deform/skeleton.hpp>
#include <deform/version.hpp>

int main() {
  const glm::quat q = deform::quat_from_euler(glm::vec3(0.0f, 0.0f, 90.0f));
  const glm::vec3 x = q * glm::vec3(1.0f, 0.0f, 0.0f);  // Rz(90°) takes +X to +Y
  std::printf("libdeform %s: Rz(90) * X = (%.3f, %.3f, %.3f)\n", DEFORM_VERSION_STRING, x.x, x.y, x.z);
  return (x.y > 0.999f && x.x < 1e-3f) ? 0 : 1;
}
