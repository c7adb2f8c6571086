#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'simulate' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command simulate_command = {"simulate", "reach, stretch, release: the elastic curve over time", "usage: deform simulate ...\n", run};

}  // namespace cli
