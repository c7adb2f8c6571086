#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'skin' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command skin_command = {"skin", "deform a mesh by a pose (LBS or DQS)", "usage: deform skin ...\n", run};

}  // namespace cli
