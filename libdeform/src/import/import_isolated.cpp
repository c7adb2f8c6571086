// import_model_isolated: Assimp in a child process (deform-import-worker) under memory, stack and time limits (POSIX).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "deform/import/import.hpp"
#include "deform/runtime/error.hpp"
#include "wire.hpp"

extern char** environ;

namespace deform {
namespace {

namespace fs = std::filesystem;

std::string find_worker(const std::string& given) {
  std::vector<std::string> candidates;
  if (!given.empty()) candidates.push_back(given);
  if (const char* env = std::getenv("DEFORM_IMPORT_WORKER"); env != nullptr && *env != '\0') candidates.push_back(env);
#if defined(DEFORM_IMPORT_WORKER_BUILT)
  candidates.push_back(DEFORM_IMPORT_WORKER_BUILT);
#endif
#if defined(DEFORM_IMPORT_WORKER_INSTALLED)
  candidates.push_back(DEFORM_IMPORT_WORKER_INSTALLED);
#endif
  for (const std::string& candidate : candidates) {
    std::error_code error;
    if (fs::is_regular_file(candidate, error) && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (!given.empty() && candidate == given) break;  // a worker the caller named must be the one used
  }
  throw Error::invalid_argument("IsolationLimits::worker",
                                "the importer process deform-import-worker was not found (set DEFORM_IMPORT_WORKER)");
}

struct Pipe {
  int read = -1, write = -1;
  Pipe() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw Error::invalid_argument("import", std::string("pipe: ") + std::strerror(errno));
    read = fds[0], write = fds[1];
  }
  ~Pipe() {
    close_read();
    close_write();
  }
  void close_read() {
    if (read >= 0) ::close(read), read = -1;
  }
  void close_write() {
    if (write >= 0) ::close(write), write = -1;
  }
};

// The worker's environment: this process's, with the memory limit also told to AddressSanitizer. A sanitized worker
// cannot limit its address space (the shadow memory needs terabytes of it), so there the limit is ASan's instead:
// past it allocations fail (std::bad_alloc, the worker's exit 3) as they would under RLIMIT_AS. An unsanitized
// worker ignores the variable.
std::vector<std::string> worker_environment(std::uint64_t max_memory_bytes) {
  std::vector<std::string> env;
  std::string asan_options;
  for (char** e = environ; e != nullptr && *e != nullptr; ++e) {
    const std::string_view entry = *e;
    if (entry.rfind("ASAN_OPTIONS=", 0) == 0)
      asan_options = std::string(entry.substr(13)) + ":";
    else
      env.emplace_back(entry);
  }
  if (max_memory_bytes > 0) {
    const std::uint64_t megabytes = std::max<std::uint64_t>(1, max_memory_bytes >> 20);
    asan_options += "allocator_may_return_null=1:soft_rss_limit_mb=" + std::to_string(megabytes) +
                    ":max_allocation_size_mb=" + std::to_string(megabytes);
  }
  if (!asan_options.empty()) env.push_back("ASAN_OPTIONS=" + asan_options);
  return env;
}

std::string signal_name(int signal) {
  const char* name = ::strsignal(signal);
  return std::to_string(signal) + (name != nullptr ? std::string(", ") + name : std::string());
}

// The worker's own CPU limit: the wall-clock limit in whole seconds, rounded up (0, no limit, for none or a limit too
// large to matter). A worker uses at most one CPU, so it reaches this no sooner than the parent's deadline.
std::string cpu_seconds(double max_seconds) {
  if (!(max_seconds > 0.0) || max_seconds > 1e9) return "0";
  return std::to_string(static_cast<unsigned long long>(std::ceil(max_seconds)));
}

}  // namespace

ImportedModel import_model_isolated(const std::string& path, const ImportOptions& options,
                                    const IsolationLimits& limits) {
  const std::string worker = find_worker(limits.worker);
  std::vector<std::string> args = {worker,
                                   "--max-memory", std::to_string(limits.max_memory_bytes),
                                   "--max-stack", std::to_string(limits.max_stack_bytes),
                                   "--max-cpu-seconds", cpu_seconds(limits.max_seconds),
                                   "--parent", std::to_string(::getpid()),
                                   "--ticks-per-second", std::to_string(options.default_ticks_per_second),
                                   "--loop", options.loop_clips ? "1" : "0",
                                   "--", path};
  // The reference policy travels as one --allow-outside per folder, before "--" (the worker confines as we would).
  for (const std::string& folder : options.references.allow_outside)
    args.insert(args.end() - 2, {"--allow-outside", folder});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env = worker_environment(limits.max_memory_bytes);
  std::vector<char*> envp;
  for (std::string& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);

  Pipe out, err;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out.write, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err.write, STDERR_FILENO);
  pid_t pid = -1;
  const int spawned = ::posix_spawn(&pid, worker.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw Error::in_file(path, "", "cannot start the importer process: " + std::string(std::strerror(spawned)));
  out.close_write();
  err.close_write();

  // Read both pipes until they close, the deadline passes or the answer outgrows its limit.
  std::vector<std::uint8_t> answer;
  std::string messages;
  constexpr std::size_t max_message_bytes = 64 * 1024;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(limits.max_seconds);
  std::string stopped;
  std::uint8_t buffer[1 << 16];
  while (out.read >= 0 || err.read >= 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", limits.max_seconds);
      stopped = std::string("took more than ") + seconds + " s";
      break;
    }
    pollfd fds[2] = {{out.read, POLLIN, 0}, {err.read, POLLIN, 0}};
    const int ready = ::poll(fds, 2, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno != EINTR) {
      stopped = std::string("poll failed: ") + std::strerror(errno);
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t got = ::read(fds[i].fd, buffer, sizeof buffer);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        (i == 0 ? out : err).close_read();
        continue;
      }
      if (i == 0) {
        if (answer.size() + std::size_t(got) > limits.max_output_bytes) {
          stopped = "sent back more than " + std::to_string(limits.max_output_bytes) + " bytes";
          break;
        }
        answer.insert(answer.end(), buffer, buffer + got);
      } else if (messages.size() < max_message_bytes) {
        messages.append(reinterpret_cast<const char*>(buffer),
                        std::min<std::size_t>(std::size_t(got), max_message_bytes - messages.size()));
      }
    }
    if (!stopped.empty()) break;
  }
  if (!stopped.empty()) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!stopped.empty()) throw Error::in_file(path, "", "the importer " + stopped + " and was stopped");

  while (!messages.empty() && (messages.back() == '\n' || messages.back() == '\r')) messages.pop_back();
  // A sanitized worker past its memory limit (worker_environment) reports it and exits or aborts (abort_on_error):
  // the same error as an unsanitized worker's RLIMIT_AS gives.
  const bool out_of_memory = messages.find("AddressSanitizer: soft rss limit exhausted") != std::string::npos ||
                             messages.find("AddressSanitizer: allocator is out of memory") != std::string::npos ||
                             messages.find("AddressSanitizer: requested allocation size") != std::string::npos;
  if (out_of_memory && !(WIFEXITED(status) && WEXITSTATUS(status) == 0))
    throw Error::in_file(path, "", "the import needed more than " + std::to_string(limits.max_memory_bytes) +
                                       " bytes of memory");
  if (WIFSIGNALED(status)) {
    throw Error::in_file(path, "", "the importer crashed (signal " + signal_name(WTERMSIG(status)) +
                                       ") reading it" + (messages.empty() ? "" : ": " + messages));
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  if (code != 0) {
    // The worker prints deform::Error's what(), which already names the file; anything else is passed on as is.
    const std::string prefix = path + ": ";
    if (messages.rfind(prefix, 0) == 0) messages.erase(0, prefix.size());
    throw Error::in_file(path, "", messages.empty() ? "the importer failed (exit " + std::to_string(code) + ")"
                                                    : messages);
  }
  return wire::decode(answer, path);
}

}  // namespace deform
