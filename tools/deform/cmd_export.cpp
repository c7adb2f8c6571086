#include "cli.hpp"

namespace cli {
namespace {

int run(const std::vector<std::string>&) {
  note("'export' is not available in this build yet");
  return exit_failure;
}

}  // namespace

const Command export_command = {"export", "write an imported model as OBJ + MTL + .sk + .skw", "usage: deform export ...\n", run};

}  // namespace cli
