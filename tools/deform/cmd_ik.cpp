#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'ik' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command ik_command = {"ik", "solve inverse kinematics for a bone chain", "usage: deform ik ...\n", run};

}  // namespace cli
