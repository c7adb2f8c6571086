// deform-import-worker: the process import_model_isolated starts. Limits itself (memory, stack), imports one file with
// Assimp (import_model) and writes the model to stdout in the private wire layout (wire.hpp).
//   deform-import-worker --max-memory BYTES --max-stack BYTES --max-cpu-seconds S --parent PID --ticks-per-second T
//                        --loop 0|1 [--allow-outside DIR]... -- PATH
// Exit status: 0 with the model on stdout; 2 with deform::Error's message on stderr; 3 out of memory; 1 otherwise.
// A crash or a hang is what the parent is there for; on Linux the worker also ends by itself when the parent dies
// (PR_SET_PDEATHSIG, SIGKILL: a parent killed by kill -9 or the OOM killer leaves no importer running) and when it
// has used S seconds of CPU (RLIMIT_CPU: the parent's deadline, kept even by a worker the parent can no longer stop).
// On Windows the parent's job object holds the memory and CPU limits and ends the worker with the parent
// (import_isolated.cpp); the worker sets nothing itself.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>
#include <string_view>

#ifdef _WIN32
#include <fcntl.h>
#include <io.h>
#else
#include <csignal>
#include <sys/resource.h>
#include <unistd.h>
#endif
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "deform/import/import.hpp"
#include "deform/runtime/error.hpp"
#include "wire.hpp"

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool sanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool sanitized = true;
#else
constexpr bool sanitized = false;
#endif
#else
constexpr bool sanitized = false;
#endif

#ifndef _WIN32
void limit(int resource, unsigned long long bytes) {
  rlimit value{static_cast<rlim_t>(bytes), static_cast<rlim_t>(bytes)};
  rlimit current{};
  if (::getrlimit(resource, &current) == 0 && current.rlim_max != RLIM_INFINITY && value.rlim_max > current.rlim_max)
    value.rlim_max = value.rlim_cur = current.rlim_max;
  ::setrlimit(resource, &value);
}

// Ties the worker's life to the parent's (Linux; on Windows the parent's job object does). The parent-death
// signal is checked against a race: a parent that died before prctl() took effect has already re-parented this
// process, and getppid() no longer names it. The CPU limit is the wall-clock limit rounded up: SIGXCPU at it, SIGKILL a
// second later if SIGXCPU is caught (Assimp does not catch it).
void tie_to_parent(long long parent, unsigned long long cpu_seconds) {
#ifdef __linux__
  if (parent > 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (static_cast<long long>(::getppid()) != parent) ::_exit(1);
  }
  if (cpu_seconds > 0) {
    rlimit value{static_cast<rlim_t>(cpu_seconds), static_cast<rlim_t>(cpu_seconds + 1)};
    rlimit current{};
    if (::getrlimit(RLIMIT_CPU, &current) == 0 && current.rlim_max != RLIM_INFINITY &&
        value.rlim_max > current.rlim_max)
      value.rlim_max = value.rlim_cur = current.rlim_max;
    ::setrlimit(RLIMIT_CPU, &value);
  }
#else
  (void)parent;
  (void)cpu_seconds;
#endif
}

#endif

volatile unsigned long long test_spins = 0;  // DEFORM_IMPORT_WORKER_TEST_SPIN's counter

bool write_all(const std::vector<std::uint8_t>& bytes) {
#ifdef _WIN32
  // Bytes as they are: no CR inserted before each LF.
  if (_setmode(_fileno(stdout), _O_BINARY) == -1) return false;
  return std::fwrite(bytes.data(), 1, bytes.size(), stdout) == bytes.size() && std::fflush(stdout) == 0;
#else
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(STDOUT_FILENO, bytes.data() + done, bytes.size() - done);
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  unsigned long long memory = 0, stack = 0, cpu_seconds = 0;
  long long parent = 0;
  deform::ImportOptions options;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--" && i + 1 < argc) {
      path = argv[++i];
    } else if (i + 1 < argc && a == "--max-memory") {
      memory = std::strtoull(argv[++i], nullptr, 10);
    } else if (i + 1 < argc && a == "--max-stack") {
      stack = std::strtoull(argv[++i], nullptr, 10);
    } else if (i + 1 < argc && a == "--max-cpu-seconds") {
      cpu_seconds = std::strtoull(argv[++i], nullptr, 10);
    } else if (i + 1 < argc && a == "--parent") {
      parent = std::strtoll(argv[++i], nullptr, 10);
    } else if (i + 1 < argc && a == "--ticks-per-second") {
      options.default_ticks_per_second = std::strtod(argv[++i], nullptr);
    } else if (i + 1 < argc && a == "--loop") {
      options.loop_clips = std::string_view(argv[++i]) == "1";
    } else if (i + 1 < argc && a == "--allow-outside") {  // ImportOptions::references, one folder each
      options.references.allow_outside.emplace_back(argv[++i]);
    } else {
      std::fprintf(stderr, "deform-import-worker: unexpected argument '%s' (it is started by libdeform)\n", argv[i]);
      return 1;
    }
  }
  if (path.empty()) {
    std::fprintf(stderr, "deform-import-worker: no file\n");
    return 1;
  }
#ifdef _WIN32
  (void)stack;
  (void)cpu_seconds;
  (void)parent;
  (void)sanitized;
#else
  tie_to_parent(parent, cpu_seconds);
  if (memory > 0 && !sanitized) limit(RLIMIT_AS, memory);
  if (stack > 0) limit(RLIMIT_STACK, stack);
#endif
  // Testing only (tests/cli/outputs_test.py): spin on the CPU, as Assimp looping on a hostile file does, until a
  // limit or the parent's death ends the process.
  const char* spin = std::getenv("DEFORM_IMPORT_WORKER_TEST_SPIN");
  if (spin != nullptr && std::string_view(spin) == "1")
    for (;;) test_spins = test_spins + 1;  // volatile stores: a loop the compiler keeps
  try {
    const std::vector<std::uint8_t> bytes = deform::wire::encode(deform::import_model(path, options));
    return write_all(bytes) ? 0 : 1;
  } catch (const deform::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "the import needed more than %llu bytes of memory\n", memory);
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
