#pragma once
// Shared plumbing of the `deform` subcommands: argument parsing, JSON output, exit codes (docs/cli.md).
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace cli {

// Exit codes fixed by the CLI contract.
inline constexpr int exit_ok = 0;
inline constexpr int exit_failure = 1;  // any other failure
inline constexpr int exit_invalid = 2;  // bad usage or invalid input

// Bad usage: unknown flag, missing value, malformed number. main() prints it with the usage hint, exit 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Command-line arguments of one subcommand: positionals in order, `--flag value` options, `--switch` booleans.
// Each subcommand declares which flags take values and which are switches; anything else is a UsageError.
class Args {
 public:
  Args(std::vector<std::string> argv, std::vector<std::string> value_flags, std::vector<std::string> switch_flags);

  const std::vector<std::string>& positionals() const { return positionals_; }
  bool has(std::string_view flag) const;                          // a switch, or a value flag that was given
  std::optional<std::string> value(std::string_view flag) const;  // last occurrence
  std::vector<std::string> values(std::string_view flag) const;   // every occurrence, in order (a repeatable flag)
  std::string required(std::string_view flag) const;              // UsageError when missing
  bool help() const { return help_; }

 private:
  std::vector<std::string> positionals_;
  std::vector<std::pair<std::string, std::string>> values_;
  std::vector<std::string> switches_;
  bool help_ = false;
};

// "1.5,-2,3" -> vec3, a point in space; UsageError naming `what` on anything else (wrong count, non-finite, junk, a
// coordinate beyond 1e18, where distances overflow).
glm::vec3 parse_vec3(const std::string& text, std::string_view what);
double parse_number(const std::string& text, std::string_view what);
long long parse_integer(const std::string& text, std::string_view what, long long min, long long max);

// Prints one JSON document on stdout (the command's machine-readable result).
// One JSON document on stdout: keys sorted (print_json) or in the order built (print_json_in_order). A number that is
// not finite (nlohmann would print null) throws std::logic_error instead, before anything is printed.
void print_json(const nlohmann::json& document);
void print_json_in_order(const nlohmann::ordered_json& document);
// The same check for a document printed by other means.
void require_finite_json(const nlohmann::json& document);
void require_finite_json(const nlohmann::ordered_json& document);
// Prints a warning or note on stderr.
void note(const std::string& message);

nlohmann::json to_json(glm::vec3 v);

// A subcommand: run() returns the exit code; throws UsageError, deform::Error (both exit 2) or anything else (1).
struct Command {
  const char* name;
  const char* summary;
  const char* usage;  // full help text printed by `deform NAME --help`
  int (*run)(const std::vector<std::string>& args);
};

extern const Command info_command;
extern const Command skin_command;
extern const Command weights_command;
extern const Command weights_edit_command;
extern const Command corrective_command;
extern const Command ik_command;
extern const Command ffd_command;
extern const Command simulate_command;
extern const Command export_command;
extern const Command bake_command;
extern const Command simplify_command;

}  // namespace cli
