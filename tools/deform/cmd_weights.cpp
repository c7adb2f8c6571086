#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'weights' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command weights_command = {"weights", "compute automatic skin weights (.skw)", "usage: deform weights ...\n", run};

}  // namespace cli
