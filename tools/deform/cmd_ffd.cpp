#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'ffd' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command ffd_command = {"ffd", "apply a Bezier-volume free-form deformation", "usage: deform ffd ...\n", run};

}  // namespace cli
