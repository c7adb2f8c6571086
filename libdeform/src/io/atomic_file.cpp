// Bounded whole-file reads and atomic writes (POSIX).
#include "deform/io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "deform/runtime/error.hpp"

namespace deform {
namespace {

namespace fs = std::filesystem;

std::string errno_text() { return std::strerror(errno); }

// Closes a descriptor on every path out of a scope.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

bool write_all(int fd, const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    data += written;
    size -= static_cast<std::size_t>(written);
  }
  return true;
}

// The failure injection of inject_file_failure_for_testing: the step numbered `steps_until_failure` fails.
long steps_until_failure = -1;
long steps_taken = 0;

// Counts a step; true (with errno set to EIO) when this is the step to fail.
bool injected_failure() {
  const bool fail = steps_taken++ == steps_until_failure;
  if (fail) errno = EIO;
  return fail;
}

std::string random_suffix() {
  static thread_local std::mt19937_64 generator{std::random_device{}()};
  return std::to_string(generator() % 4294967296ull);
}

// An errno as a deform::Error: a path that cannot name an output (a missing folder, a name too long, a link loop) is
// the user's input; anything else (permissions, a full disk, a read-only file system, an I/O error) is the
// environment's.
Error system_error(const std::string& path, const std::string& what, int code) {
  const std::string message = what + ": " + std::strerror(code);
  if (code == ENOENT || code == ENOTDIR || code == EISDIR || code == ELOOP || code == ENAMETOOLONG)
    return Error::in_file(path, "", message);
  return Error::environment(path, message);
}

// The file an output path names. An existing regular file: the path with every symbolic link resolved (its temporary
// file goes beside the real file). Anything else that exists (a device, a FIFO, /dev/stdout's link to a pipe, a
// folder): the path as given, opened through its links. Nothing there: symbolic links followed, dangling or not (a
// link to a file that does not exist yet names the file to create), relative link targets taken from the link's
// folder; past 40 links it is a loop.
std::string output_target(const std::string& path) {
  struct stat info {};
  std::error_code ec;
  if (::stat(path.c_str(), &info) == 0) {
    struct stat itself {};
    if (!S_ISREG(info.st_mode) || ::lstat(path.c_str(), &itself) != 0 || !S_ISLNK(itself.st_mode)) return path;
    const fs::path real = fs::canonical(path, ec);
    if (ec) throw system_error(path, "cannot resolve the symbolic link", ec.value());
    return real.string();
  }
  fs::path target(path);
  for (int hops = 0;; ++hops) {
    if (::lstat(target.c_str(), &info) != 0 || !S_ISLNK(info.st_mode)) return target.string();
    if (hops == 40) throw system_error(path, "cannot follow its symbolic links", ELOOP);
    const fs::path points_to = fs::read_symlink(target, ec);
    if (ec) throw system_error(path, "cannot read the symbolic link", ec.value());
    target = points_to.is_absolute() ? points_to : target.parent_path() / points_to;
  }
}

template <class Container>
Container read_all(const std::string& path, std::uint64_t max_bytes) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; the type is checked before anything is read.
  Descriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK)};
  if (file.fd < 0) throw system_error(path, "cannot open for reading", errno);
  struct stat info {};
  if (::fstat(file.fd, &info) != 0) throw Error::in_file(path, "", "cannot read its attributes: " + errno_text());
  if (S_ISDIR(info.st_mode)) throw Error::in_file(path, "", "is a directory, not a file");
  if (!S_ISREG(info.st_mode)) throw Error::in_file(path, "", "is not a regular file (a device, FIFO or socket)");
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes)
    throw Error::in_file(path, "", "file is " + std::to_string(size) + " bytes, more than the limit of " +
                                       std::to_string(max_bytes));
  Container data(static_cast<std::size_t>(size), {});
  std::size_t done = 0;
  while (done < data.size()) {  // a file that shrinks while read ends early; one that grows is read to `size`
    const ssize_t got = ::read(file.fd, reinterpret_cast<char*>(data.data()) + done, data.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error::in_file(path, "", "read failed: " + errno_text());
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  data.resize(done);
  return data;
}

}  // namespace

std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  return read_all<std::vector<std::uint8_t>>(path, max_bytes);
}

std::string read_file_text(const std::string& path, std::uint64_t max_bytes) {
  return read_all<std::string>(path, max_bytes);
}

void write_file_atomic(const std::string& path, std::span<const std::uint8_t> data) {
  FileTransaction file;
  file.stage(path, data);
  file.commit();
}

void inject_file_failure_for_testing(long step) {
  steps_until_failure = step;
  steps_taken = 0;
}

long file_steps_for_testing() { return steps_taken; }

FileTransaction::~FileTransaction() {
  if (committed_) return;
  for (const Entry& entry : entries_)
    if (!entry.temp.empty()) ::unlink(entry.temp.c_str());
}

void FileTransaction::stage(const std::string& path, std::string_view text) {
  stage(path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

void FileTransaction::stage_written(const std::string& path, const std::string& written) {
  struct Remove {
    const std::string& file;
    ~Remove() { ::unlink(file.c_str()); }
  } consumed{written};
  const std::size_t before = entries_.size();
  stage(path, {}, &written);
  if (entries_.size() == before || !entries_.back().temp.empty()) return;
  entries_.back().direct = read_file_bytes(written);  // a device or FIFO target: written by commit()
}

void FileTransaction::stage(const std::string& path, std::span<const std::uint8_t> data) { stage(path, data, nullptr); }

void FileTransaction::stage(const std::string& path, std::span<const std::uint8_t> data, const std::string* written) {
  if (committed_) throw Error::invalid_argument("FileTransaction", "stage() after commit()");
  Entry entry;
  entry.named = path;
  entry.target = output_target(path);
  std::error_code ec;
  const fs::path same = fs::absolute(entry.target, ec).lexically_normal();
  for (const Entry& other : entries_)
    if (fs::absolute(other.target, ec).lexically_normal() == same)
      throw Error::in_file(path, "", "names the same file as " + other.named + ", another output of this run");
  struct stat existing {};
  entry.existed = ::stat(entry.target.c_str(), &existing) == 0;
  if (entry.existed && S_ISDIR(existing.st_mode)) throw Error::in_file(path, "", "is a directory, not a file");
  if (entry.existed && !S_ISREG(existing.st_mode)) {  // a device or FIFO: written directly by commit()
    entry.existed = false;
    entry.direct.assign(data.begin(), data.end());
    entries_.push_back(std::move(entry));
    return;
  }

  // A temporary file beside the target, named so that one left by a killed process is recognisable:
  // .NAME.deform-tmp-NUMBER (docs/reliability.md).
  const fs::path target(entry.target);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  Descriptor out;
  if (injected_failure()) throw system_error(path, "cannot create a temporary file beside it", errno);
  if (written != nullptr) {  // already written: moved beside the target under a temporary name, or copied there
    bool moved = false;
    for (int attempt = 0; attempt < 16 && !moved; ++attempt) {
      entry.temp = (folder / ("." + target.filename().string() + ".deform-tmp-" + random_suffix())).string();
      struct stat taken {};
      if (::lstat(entry.temp.c_str(), &taken) == 0) continue;
      if (::rename(written->c_str(), entry.temp.c_str()) == 0) {
        moved = true;
      } else if (errno == EXDEV) {
        stage(path, read_file_bytes(*written), nullptr);
        return;
      } else {
        throw system_error(path, "cannot move the written file beside it", errno);
      }
    }
    if (!moved) throw system_error(path, "cannot move the written file beside it", EEXIST);
    if (entry.existed) {
      if (::chmod(entry.temp.c_str(), existing.st_mode & 07777) != 0 ||
          (::chown(entry.temp.c_str(), existing.st_uid, existing.st_gid) != 0 && errno != EPERM)) {
        const int code = errno;
        ::unlink(entry.temp.c_str());
        throw system_error(path, "cannot keep the file's mode and owner", code);
      }
    }
    entries_.push_back(std::move(entry));
    return;
  }
  for (int attempt = 0; attempt < 16 && out.fd < 0; ++attempt) {
    entry.temp = (folder / ("." + target.filename().string() + ".deform-tmp-" + random_suffix())).string();
    out.fd = ::open(entry.temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (out.fd < 0 && errno != EEXIST) break;
  }
  if (out.fd < 0) throw system_error(path, "cannot create a temporary file beside it", errno);

  std::string failure;
  int code = 0;
  const auto failed = [&](const char* what) {
    code = errno;
    failure = what;
  };
  if (!write_all(out.fd, data.data(), data.size())) failed("write failed");
  if (failure.empty() && entry.existed) {
    // Keep the replaced file's permissions, and its owner where this process may set it (root, or the same owner).
    if (::fchmod(out.fd, existing.st_mode & 07777) != 0) failed("cannot keep the file's mode");
    if (failure.empty() && ::fchown(out.fd, existing.st_uid, existing.st_gid) != 0 && errno != EPERM)
      failed("cannot keep the file's owner");
  }
  if (failure.empty() && ::fsync(out.fd) != 0) failed("fsync failed");
  const int fd = out.fd;
  out.fd = -1;
  if (::close(fd) != 0 && failure.empty()) failed("close failed");
  if (!failure.empty()) {
    ::unlink(entry.temp.c_str());
    throw system_error(path, failure, code);
  }
  entries_.push_back(std::move(entry));
}

void FileTransaction::commit() {
  if (committed_) throw Error::invalid_argument("FileTransaction", "commit() called twice");
  // Only a set needs backups: a single file's rename replaces it atomically, and nothing after it can fail.
  const bool single = entries_.size() == 1;
  try {
    for (Entry& entry : entries_) {
      if (entry.temp.empty()) continue;
      if (entry.existed && !single) {
        const fs::path target(entry.target);
        const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
        if (injected_failure()) throw system_error(entry.named, "cannot keep a backup of it", errno);
        for (int attempt = 0; attempt < 16 && entry.backup.empty(); ++attempt) {
          std::string backup =
              (folder / ("." + target.filename().string() + ".deform-bak-" + random_suffix())).string();
          // A hard link leaves the target in place; a file system without them gets a rename (the target is then
          // missing until the staged file lands, never changed).
          if (::link(entry.target.c_str(), backup.c_str()) == 0 ||
              (errno != EEXIST && ::rename(entry.target.c_str(), backup.c_str()) == 0))
            entry.backup = std::move(backup);
          else if (errno != EEXIST)
            throw system_error(entry.named, "cannot keep a backup of it", errno);
        }
        if (entry.backup.empty()) throw system_error(entry.named, "cannot keep a backup of it", EEXIST);
      }
      if (injected_failure() || ::rename(entry.temp.c_str(), entry.target.c_str()) != 0)
        throw system_error(entry.named, "cannot move into place", errno);
      entry.placed = true;
    }
    for (Entry& entry : entries_) {
      if (!entry.temp.empty()) continue;
      if (injected_failure()) throw system_error(entry.named, "write failed", errno);
      // O_NONBLOCK: a FIFO without a reader is refused (ENXIO) instead of blocking this process for ever.
      Descriptor out{::open(entry.target.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK)};
      if (out.fd < 0 && errno == ENXIO)
        throw Error::environment(entry.named, "is a FIFO that no process reads: nothing written");
      if (out.fd < 0) throw system_error(entry.named, "cannot open for writing", errno);
      const int flags = ::fcntl(out.fd, F_GETFL);
      if (flags < 0 || ::fcntl(out.fd, F_SETFL, flags & ~O_NONBLOCK) != 0)
        throw system_error(entry.named, "cannot open for writing", errno);
      if (!write_all(out.fd, entry.direct.data(), entry.direct.size()))
        throw system_error(entry.named, "write failed", errno);
    }
  } catch (...) {
    roll_back();
    throw;
  }
  committed_ = true;
  for (const Entry& entry : entries_)
    if (!entry.backup.empty()) ::unlink(entry.backup.c_str());
}

void FileTransaction::roll_back() noexcept {
  for (auto entry = entries_.rbegin(); entry != entries_.rend(); ++entry) {
    if (entry->placed) {
      if (!entry->backup.empty())
        ::rename(entry->backup.c_str(), entry->target.c_str());
      else if (!entry->existed)
        ::unlink(entry->target.c_str());
    } else {
      if (!entry->backup.empty()) {
        // Backed up but not replaced: a hard link is removed; a rename is undone.
        struct stat target {};
        if (::stat(entry->target.c_str(), &target) == 0)
          ::unlink(entry->backup.c_str());
        else
          ::rename(entry->backup.c_str(), entry->target.c_str());
      }
      if (!entry->temp.empty()) ::unlink(entry->temp.c_str());
    }
    entry->placed = false;
    entry->backup.clear();
  }
  committed_ = true;  // nothing left to remove; a failed transaction is not committed again
}

void write_file_atomic(const std::string& path, std::string_view text) {
  write_file_atomic(path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace deform
