// import_model_isolated: Assimp in a child process (deform-import-worker) under memory, stack and time limits: on POSIX
// posix_spawn and the worker's own rlimits, on Windows CreateProcessW inside a job object that holds the limits.
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

#ifdef _WIN32
#ifndef NOMINMAX
#define NOMINMAX
#endif
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#include <windows.h>
#else
#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

#include "deform/import/import.hpp"
#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"
#include "wire.hpp"

#ifndef _WIN32
extern char** environ;
#endif

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
#ifdef _WIN32
    if (fs::is_regular_file(utf8_path::from_utf8(candidate), error)) return candidate;
#else
    if (fs::is_regular_file(candidate, error) && ::access(candidate.c_str(), X_OK) == 0) return candidate;
#endif
    if (!given.empty() && candidate == given) break;  // a worker the caller named must be the one used
  }
  throw Error::invalid_argument("IsolationLimits::worker",
                                "the importer process deform-import-worker was not found (set DEFORM_IMPORT_WORKER)");
}

#ifndef _WIN32
struct Pipe {
  int read = -1, write = -1;
  Pipe() {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
      throw Error::invalid_argument("import", std::string("pipe: ") + std::strerror(errno));
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
    if (entry.rfind("ASAN_OPTIONS=", 0) == 0) asan_options = std::string(entry.substr(13)) + ":";
    else env.emplace_back(entry);
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

#endif

// The worker's own CPU limit: the wall-clock limit in whole seconds, rounded up (0, no limit, for none or a limit too
// large to matter). A worker uses at most one CPU, so it reaches this no sooner than the parent's deadline.
std::string cpu_seconds(double max_seconds) {
  if (!(max_seconds > 0.0) || max_seconds > 1e9) return "0";
  return std::to_string(static_cast<unsigned long long>(std::ceil(max_seconds)));
}

// The worker's arguments (the first is the worker itself).
std::vector<std::string> worker_arguments(const std::string& worker, const std::string& path,
                                          const ImportOptions& options, const IsolationLimits& limits,
                                          long long parent) {
  std::vector<std::string> args = {worker,
                                   "--max-memory",
                                   std::to_string(limits.max_memory_bytes),
                                   "--max-stack",
                                   std::to_string(limits.max_stack_bytes),
                                   "--max-cpu-seconds",
                                   cpu_seconds(limits.max_seconds),
                                   "--parent",
                                   std::to_string(parent),
                                   "--ticks-per-second",
                                   std::to_string(options.default_ticks_per_second),
                                   "--loop",
                                   options.loop_clips ? "1" : "0",
                                   "--",
                                   path};
  // The reference policy travels as one --allow-outside per folder, before "--" (the worker confines as we would).
  for (const std::string& folder : options.references.allow_outside)
    args.insert(args.end() - 2, {"--allow-outside", folder});
  return args;
}

std::string seconds_text(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", seconds);
  return text;
}

// A worker that exited with `code` (not 0) and printed `messages`: the error to throw.
Error worker_failed(const std::string& path, int code, std::string messages) {
  // The worker prints deform::Error's what(), which already names the file; anything else is passed on as is.
  const std::string prefix = path + ": ";
  if (messages.rfind(prefix, 0) == 0) messages.erase(0, prefix.size());
  return Error::in_file(path, "",
                        messages.empty() ? "the importer failed (exit " + std::to_string(code) + ")" : messages);
}

#ifdef _WIN32

std::wstring wide(const std::string& utf8) { return utf8_path::from_utf8(utf8).wstring(); }

// Appends one argument as the C runtime's parser of the command line reads it back: quoted when it holds a space, tab
// or quote; backslashes doubled before a quote and before the closing quote.
void append_argument(std::wstring& line, const std::wstring& argument) {
  if (!line.empty()) line += L' ';
  if (!argument.empty() && argument.find_first_of(L" \t\n\v\"") == std::wstring::npos) {
    line += argument;
    return;
  }
  line += L'"';
  std::size_t backslashes = 0;
  for (const wchar_t c : argument) {
    if (c == L'\\') {
      ++backslashes;
      continue;
    }
    line.append(c == L'"' ? backslashes * 2 + 1 : backslashes, L'\\');
    backslashes = 0;
    line += c;
  }
  line.append(backslashes * 2, L'\\');
  line += L'"';
}

struct OwnedHandle {
  HANDLE h = nullptr;
  OwnedHandle() = default;
  explicit OwnedHandle(HANDLE handle) : h(handle) {}
  OwnedHandle(const OwnedHandle&) = delete;
  OwnedHandle& operator=(const OwnedHandle&) = delete;
  ~OwnedHandle() { reset(); }
  void reset() {
    if (h != nullptr && h != INVALID_HANDLE_VALUE) CloseHandle(h);
    h = nullptr;
  }
};

std::string windows_error(const char* what) {
  return std::string(what) + " (Windows error " + std::to_string(GetLastError()) + ")";
}

#endif

}  // namespace

#ifdef _WIN32

// The worker runs in a job object: JOB_OBJECT_LIMIT_PROCESS_MEMORY is the memory limit (an allocation past it fails:
// std::bad_alloc, the worker's exit 3, as under RLIMIT_AS), JOB_OBJECT_LIMIT_PROCESS_TIME the CPU limit (the
// wall-clock limit rounded up, as RLIMIT_CPU), JOB_OBJECT_LIMIT_KILL_ON_JOB_CLOSE ends it with this process (the
// handle closes when this process dies however it dies: PR_SET_PDEATHSIG's part), one active process (the worker
// starts nothing). The stack limit has no Windows equivalent (a thread's stack is sized when it is made): the worker
// keeps the stack its executable was linked with. Only the two pipes are inherited (PROC_THREAD_ATTRIBUTE_HANDLE_LIST),
// never another handle this process has open.
ImportedModel import_model_isolated(const std::string& path, const ImportOptions& options,
                                    const IsolationLimits& limits) {
  const std::string worker = find_worker(limits.worker);
  std::wstring command_line;
  for (const std::string& argument :
       worker_arguments(worker, path, options, limits, static_cast<long long>(GetCurrentProcessId())))
    append_argument(command_line, wide(argument));
  const auto cannot_start = [&](const char* what) {
    return Error::in_file(path, "", "cannot start the importer process: " + windows_error(what));
  };

  OwnedHandle job{CreateJobObjectW(nullptr, nullptr)};
  if (job.h == nullptr) throw cannot_start("CreateJobObjectW");
  JOBOBJECT_EXTENDED_LIMIT_INFORMATION job_limits{};
  DWORD flags = JOB_OBJECT_LIMIT_KILL_ON_JOB_CLOSE | JOB_OBJECT_LIMIT_DIE_ON_UNHANDLED_EXCEPTION |
                JOB_OBJECT_LIMIT_ACTIVE_PROCESS;
  job_limits.BasicLimitInformation.ActiveProcessLimit = 1;
  if (limits.max_memory_bytes > 0) {
    flags |= JOB_OBJECT_LIMIT_PROCESS_MEMORY;
    job_limits.ProcessMemoryLimit = static_cast<SIZE_T>(limits.max_memory_bytes);
  }
  const unsigned long long cpu_limit = std::strtoull(cpu_seconds(limits.max_seconds).c_str(), nullptr, 10);
  if (cpu_limit > 0) {
    flags |= JOB_OBJECT_LIMIT_PROCESS_TIME;  // user time, in 100 ns units
    job_limits.BasicLimitInformation.PerProcessUserTimeLimit.QuadPart = static_cast<LONGLONG>(cpu_limit) * 10000000;
  }
  job_limits.BasicLimitInformation.LimitFlags = flags;
  if (!SetInformationJobObject(job.h, JobObjectExtendedLimitInformation, &job_limits, sizeof job_limits))
    throw cannot_start("SetInformationJobObject");

  // The pipes: the worker's ends inheritable, this process's not.
  SECURITY_ATTRIBUTES inheritable{sizeof(SECURITY_ATTRIBUTES), nullptr, TRUE};
  OwnedHandle out_read, out_write, err_read, err_write;
  if (!CreatePipe(&out_read.h, &out_write.h, &inheritable, 1 << 16) ||
      !CreatePipe(&err_read.h, &err_write.h, &inheritable, 1 << 16) ||
      !SetHandleInformation(out_read.h, HANDLE_FLAG_INHERIT, 0) ||
      !SetHandleInformation(err_read.h, HANDLE_FLAG_INHERIT, 0))
    throw cannot_start("CreatePipe");
  HANDLE inherited[2] = {out_write.h, err_write.h};
  SIZE_T attribute_bytes = 0;
  InitializeProcThreadAttributeList(nullptr, 1, 0, &attribute_bytes);
  std::vector<unsigned char> attribute_storage(attribute_bytes);
  const auto attributes = reinterpret_cast<LPPROC_THREAD_ATTRIBUTE_LIST>(attribute_storage.data());
  if (!InitializeProcThreadAttributeList(attributes, 1, 0, &attribute_bytes))
    throw cannot_start("InitializeProcThreadAttributeList");
  struct DeleteList {
    LPPROC_THREAD_ATTRIBUTE_LIST list;
    ~DeleteList() { DeleteProcThreadAttributeList(list); }
  } delete_list{attributes};
  if (!UpdateProcThreadAttribute(attributes, 0, PROC_THREAD_ATTRIBUTE_HANDLE_LIST, inherited, sizeof inherited, nullptr,
                                 nullptr))
    throw cannot_start("UpdateProcThreadAttribute");
  STARTUPINFOEXW startup{};
  startup.StartupInfo.cb = sizeof startup;
  startup.StartupInfo.dwFlags = STARTF_USESTDHANDLES;
  startup.StartupInfo.hStdInput = nullptr;
  startup.StartupInfo.hStdOutput = out_write.h;
  startup.StartupInfo.hStdError = err_write.h;
  startup.lpAttributeList = attributes;

  // Started suspended, put in the job, then let run: it never runs a step outside its limits.
  PROCESS_INFORMATION started{};
  const std::wstring program = wide(worker);
  if (!CreateProcessW(program.c_str(), command_line.data(), nullptr, nullptr, TRUE,
                      CREATE_SUSPENDED | CREATE_NO_WINDOW | EXTENDED_STARTUPINFO_PRESENT, nullptr, nullptr,
                      &startup.StartupInfo, &started))
    throw cannot_start("CreateProcessW");
  OwnedHandle process{started.hProcess}, thread{started.hThread};
  if (!AssignProcessToJobObject(job.h, process.h)) {
    TerminateProcess(process.h, 1);
    throw cannot_start("AssignProcessToJobObject");
  }
  ResumeThread(thread.h);
  out_write.reset();
  err_write.reset();

  // Read both pipes until they close, the deadline passes or the answer outgrows its limit. Anonymous pipes cannot be
  // waited on: each is asked what it holds (PeekNamedPipe), and between rounds with nothing to read this waits on the
  // process for a few milliseconds.
  std::vector<std::uint8_t> answer;
  std::string messages;
  constexpr std::size_t max_message_bytes = 64 * 1024;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(limits.max_seconds);
  std::string stopped;
  std::vector<std::uint8_t> buffer(1 << 16);
  OwnedHandle* pipes[2] = {&out_read, &err_read};
  while (out_read.h != nullptr || err_read.h != nullptr) {
    if (std::chrono::steady_clock::now() >= deadline) {
      stopped = "took more than " + seconds_text(limits.max_seconds) + " s";
      break;
    }
    bool read_any = false;
    for (int i = 0; i < 2 && stopped.empty(); ++i) {
      if (pipes[i]->h == nullptr) continue;
      DWORD available = 0;
      if (!PeekNamedPipe(pipes[i]->h, nullptr, 0, nullptr, &available, nullptr)) {  // the worker's end is closed
        pipes[i]->reset();
        continue;
      }
      if (available == 0) continue;
      DWORD got = 0;
      if (!ReadFile(pipes[i]->h, buffer.data(), std::min<DWORD>(available, DWORD(buffer.size())), &got, nullptr) ||
          got == 0) {
        pipes[i]->reset();
        continue;
      }
      read_any = true;
      if (i == 0) {
        if (answer.size() + got > limits.max_output_bytes) {
          stopped = "sent back more than " + std::to_string(limits.max_output_bytes) + " bytes";
          break;
        }
        answer.insert(answer.end(), buffer.begin(), buffer.begin() + got);
      } else if (messages.size() < max_message_bytes) {
        messages.append(reinterpret_cast<const char*>(buffer.data()),
                        std::min<std::size_t>(got, max_message_bytes - messages.size()));
      }
    }
    if (!stopped.empty()) break;
    if (!read_any) WaitForSingleObject(process.h, 5);
  }
  if (!stopped.empty()) TerminateJobObject(job.h, 1);
  WaitForSingleObject(process.h, INFINITE);
  DWORD exit_code = 1;
  GetExitCodeProcess(process.h, &exit_code);
  if (!stopped.empty()) throw Error::in_file(path, "", "the importer " + stopped + " and was stopped");

  while (!messages.empty() && (messages.back() == '\n' || messages.back() == '\r')) messages.pop_back();
  // An exception the worker did not handle ends it with its NTSTATUS code (0xC0000005, an access violation, ...).
  if (exit_code >= 0xC0000000u) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%08lX", static_cast<unsigned long>(exit_code));
    throw Error::in_file(path, "",
                         std::string("the importer crashed (exception ") + code + ") reading it" +
                             (messages.empty() ? "" : ": " + messages));
  }
  if (exit_code != 0) throw worker_failed(path, static_cast<int>(exit_code), messages);
  return wire::decode(answer, path);
}

#else  // POSIX

ImportedModel import_model_isolated(const std::string& path, const ImportOptions& options,
                                    const IsolationLimits& limits) {
  const std::string worker = find_worker(limits.worker);
  std::vector<std::string> args = worker_arguments(worker, path, options, limits, static_cast<long long>(::getpid()));
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
  if (spawned != 0)
    throw Error::in_file(path, "", "cannot start the importer process: " + std::string(std::strerror(spawned)));
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
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      stopped = "took more than " + seconds_text(limits.max_seconds) + " s";
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
    throw Error::in_file(path, "",
                         "the import needed more than " + std::to_string(limits.max_memory_bytes) + " bytes of memory");
  if (WIFSIGNALED(status)) {
    throw Error::in_file(path, "",
                         "the importer crashed (signal " + signal_name(WTERMSIG(status)) + ") reading it" +
                             (messages.empty() ? "" : ": " + messages));
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  if (code != 0) throw worker_failed(path, code, messages);
  return wire::decode(answer, path);
}

#endif

}  // namespace deform
