// Run by ctest in the sanitizer build only (tests/CMakeLists.txt): an accessor's index precondition is checked there.
// Reading lattice 0 of a hierarchy with none must stop the program with libstdc++'s assertion; reaching the end
// means the check is off, and precondition_checked.cmake, which runs it, then fails the test.
#include <cstdio>

#include "deform/runtime/hierarchy.hpp"

int main() {
  const deform::DeformerHierarchy empty;
  std::printf("bone %d\n", static_cast<int>(empty.spec(0).bone));
  return 0;
}
