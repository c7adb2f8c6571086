#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'info' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command info_command = {"info", "inspect a .sk skeleton or a mesh", "usage: deform info ...\n", run};

}  // namespace cli
