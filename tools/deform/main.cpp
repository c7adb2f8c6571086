// deform: the command-line front end of libdeform (docs/cli.md; fixed parts in docs/cli.md).
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "cli.hpp"
#include "deform/runtime/error.hpp"
#include "deform/version.hpp"

namespace {

const cli::Command* const commands[] = {&cli::info_command,         &cli::skin_command,    &cli::weights_command,
                                        &cli::weights_edit_command, &cli::ik_command,      &cli::ffd_command,
                                        &cli::simulate_command,     &cli::export_command,  &cli::bake_command,
                                        &cli::corrective_command,   &cli::simplify_command};

void print_usage(std::ostream& out) {
  out << "usage: deform [--help] [--version] COMMAND [ARGS...]\n\n"
         "libdeform " DEFORM_VERSION_STRING
         " command-line tool. Results are JSON on stdout; messages on stderr.\n"
         "Exit status: 0 success, 2 bad usage or invalid input, 1 any other failure (a full disk, permissions).\n"
         "\ncommands:\n";
  for (const cli::Command* c : commands) {
    std::string name = c->name;
    name.resize(14, ' ');
    out << "  " << name << c->summary << '\n';
  }
  out << "\n`deform COMMAND --help` describes one command.\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    print_usage(std::cerr);
    return cli::exit_invalid;
  }
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    print_usage(std::cout);
    return cli::exit_ok;
  }
  if (args[0] == "--version") {
    std::cout << "deform " DEFORM_VERSION_STRING "\n";
    return cli::exit_ok;
  }
  const cli::Command* command = nullptr;
  for (const cli::Command* c : commands)
    if (args[0] == c->name) command = c;
  if (!command) {
    std::cerr << "deform: unknown command '" << args[0] << "'\n";
    print_usage(std::cerr);
    return cli::exit_invalid;
  }
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  for (const std::string& a : rest)
    if (a == "--help" || a == "-h") {
      std::cout << command->usage;
      return cli::exit_ok;
    }
  try {
    return command->run(rest);
  } catch (const cli::UsageError& e) {
    std::cerr << "deform " << command->name << ": " << e.what() << "\n(see `deform " << command->name << " --help`)\n";
    return cli::exit_invalid;
  } catch (const deform::Error& e) {
    std::cerr << "deform " << command->name << ": " << e.what() << '\n';
    // What the system refused (a full disk, permissions) is not the user's input: 1, as any other failure.
    return e.kind() == deform::Error::Kind::environment ? cli::exit_failure : cli::exit_invalid;
  } catch (const std::bad_alloc&) {
    std::cerr << "deform " << command->name << ": out of memory\n";
    return cli::exit_failure;
  } catch (const std::exception& e) {
    std::cerr << "deform " << command->name << ": " << e.what() << '\n';
    return cli::exit_failure;
  }
}
