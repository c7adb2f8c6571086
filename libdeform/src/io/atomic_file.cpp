// Bounded whole-file reads and atomic writes: POSIX, and Windows through its own API (wide paths, MoveFileExW).
#include "deform/io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

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
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"

namespace deform {
namespace {

namespace fs = std::filesystem;

// Every path in the API is UTF-8: on Windows the wide path the system calls take, elsewhere the bytes unchanged.
using utf8_path::from_utf8;
using utf8_path::to_utf8;

// ---- The file-system primitives, one copy per system. Each returns false on failure with errno set to the reason
// (on Windows the system's error translated, see errno_from_windows), so the steps above them are shared. ----

enum class FileKind { missing, regular, directory, other };

struct FileStatus {
  FileKind kind = FileKind::missing;
#ifndef _WIN32
  struct stat info {};  // a regular file's mode and owner, kept by its replacement
#endif
};

#ifdef _WIN32

// The errno closest to a Windows error, for the messages and the input/environment split of system_error.
int errno_from_windows(DWORD code) {
  switch (code) {
    case ERROR_FILE_NOT_FOUND:
    case ERROR_PATH_NOT_FOUND:
    case ERROR_INVALID_DRIVE:
    case ERROR_BAD_NETPATH:
    case ERROR_BAD_NET_NAME:
    case ERROR_INVALID_NAME: return ENOENT;
    case ERROR_DIRECTORY: return ENOTDIR;
    case ERROR_FILENAME_EXCED_RANGE: return ENAMETOOLONG;
    case ERROR_CANT_RESOLVE_FILENAME: return ELOOP;
    case ERROR_FILE_EXISTS:
    case ERROR_ALREADY_EXISTS: return EEXIST;
    case ERROR_ACCESS_DENIED:
    case ERROR_SHARING_VIOLATION:
    case ERROR_LOCK_VIOLATION:
    case ERROR_WRITE_PROTECT: return EACCES;
    case ERROR_DISK_FULL:
    case ERROR_HANDLE_DISK_FULL: return ENOSPC;
    case ERROR_NOT_SAME_DEVICE: return EXDEV;
    case ERROR_NOT_ENOUGH_MEMORY:
    case ERROR_OUTOFMEMORY: return ENOMEM;
    case ERROR_NOT_SUPPORTED:
    case ERROR_INVALID_FUNCTION: return ENOSYS;
    default: return EIO;
  }
}

bool failed_windows() {
  errno = errno_from_windows(GetLastError());
  return false;
}

// Closes a handle on every path out of a scope.
struct Handle {
  HANDLE h = INVALID_HANDLE_VALUE;
  ~Handle() {
    if (h != INVALID_HANDLE_VALUE) CloseHandle(h);
  }
};

// FILE_SHARE_DELETE: a file this process reads can still be replaced by another's MoveFileExW.
constexpr DWORD share_all = FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE;

FileStatus file_status(const std::string& path) {
  FileStatus status;
  const DWORD attributes = GetFileAttributesW(from_utf8(path).c_str());
  if (attributes == INVALID_FILE_ATTRIBUTES) return status;
  if (attributes & FILE_ATTRIBUTE_DIRECTORY) {
    status.kind = FileKind::directory;
    return status;
  }
  // A name the console or a device answers to (NUL, CON) has attributes but is no disk file.
  Handle file{CreateFileW(from_utf8(path).c_str(), 0, share_all, nullptr, OPEN_EXISTING, 0, nullptr)};
  status.kind =
      file.h == INVALID_HANDLE_VALUE || GetFileType(file.h) == FILE_TYPE_DISK ? FileKind::regular : FileKind::other;
  return status;
}

bool exists_no_follow(const std::string& path) {
  return GetFileAttributesW(from_utf8(path).c_str()) != INVALID_FILE_ATTRIBUTES;
}

// Replaces `to` by `from` in one step; MOVEFILE_WRITE_THROUGH returns once the move is on the disk.
bool rename_over(const std::string& from, const std::string& to) {
  return MoveFileExW(from_utf8(from).c_str(), from_utf8(to).c_str(),
                     MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH) != 0 ||
         failed_windows();
}

// Moves `from` to `to`, which must not exist (a temporary or backup name; never replaces a file).
bool rename_new(const std::string& from, const std::string& to) {
  return MoveFileExW(from_utf8(from).c_str(), from_utf8(to).c_str(), MOVEFILE_WRITE_THROUGH) != 0 || failed_windows();
}

bool hard_link(const std::string& existing, const std::string& link) {
  return CreateHardLinkW(from_utf8(link).c_str(), from_utf8(existing).c_str(), nullptr) != 0 || failed_windows();
}

bool remove_file(const std::string& path) { return DeleteFileW(from_utf8(path).c_str()) != 0 || failed_windows(); }

// Windows files carry no POSIX mode or owner: a replacement gets the folder's inherited permissions, as any new file.
bool keep_mode_and_owner(const std::string&, const FileStatus&) { return true; }

// A new file opened for writing, created only if nothing has the name.
struct NewFile {
  Handle file;
  bool create(const std::string& path) {
    file.h =
        CreateFileW(from_utf8(path).c_str(), GENERIC_WRITE, 0, nullptr, CREATE_NEW, FILE_ATTRIBUTE_NORMAL, nullptr);
    return file.h != INVALID_HANDLE_VALUE || failed_windows();
  }
  bool write(const std::uint8_t* data, std::size_t size) {
    while (size > 0) {
      const DWORD chunk = static_cast<DWORD>(std::min<std::size_t>(size, 1u << 30));
      DWORD written = 0;
      if (!WriteFile(file.h, data, chunk, &written, nullptr)) return failed_windows();
      if (written == 0) {
        errno = EIO;
        return false;
      }
      data += written;
      size -= written;
    }
    return true;
  }
  bool keep(const FileStatus&) { return true; }
  bool sync() { return FlushFileBuffers(file.h) != 0 || failed_windows(); }
  bool close() {
    const HANDLE h = file.h;
    file.h = INVALID_HANDLE_VALUE;
    return CloseHandle(h) != 0 || failed_windows();
  }
};

#else  // POSIX

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

FileStatus file_status(const std::string& path) {
  FileStatus status;
  if (::stat(path.c_str(), &status.info) != 0) return status;
  status.kind = S_ISREG(status.info.st_mode)   ? FileKind::regular
                : S_ISDIR(status.info.st_mode) ? FileKind::directory
                                               : FileKind::other;
  return status;
}

bool exists_no_follow(const std::string& path) {
  struct stat info {};
  return ::lstat(path.c_str(), &info) == 0;
}

bool rename_over(const std::string& from, const std::string& to) { return ::rename(from.c_str(), to.c_str()) == 0; }

bool rename_new(const std::string& from, const std::string& to) { return ::rename(from.c_str(), to.c_str()) == 0; }

bool hard_link(const std::string& existing, const std::string& link) {
  return ::link(existing.c_str(), link.c_str()) == 0;
}

bool remove_file(const std::string& path) { return ::unlink(path.c_str()) == 0; }

// Keeps the replaced file's permissions, and its owner where this process may set it (root, or the same owner).
bool keep_mode_and_owner(const std::string& file, const FileStatus& existing) {
  return ::chmod(file.c_str(), existing.info.st_mode & 07777) == 0 &&
         (::chown(file.c_str(), existing.info.st_uid, existing.info.st_gid) == 0 || errno == EPERM);
}

// A new file opened for writing, created only if nothing has the name.
struct NewFile {
  Descriptor out;
  bool create(const std::string& path) {
    out.fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    return out.fd >= 0;
  }
  bool write(const std::uint8_t* data, std::size_t size) { return write_all(out.fd, data, size); }
  // As keep_mode_and_owner, through the open descriptor.
  bool keep(const FileStatus& existing) {
    return ::fchmod(out.fd, existing.info.st_mode & 07777) == 0 &&
           (::fchown(out.fd, existing.info.st_uid, existing.info.st_gid) == 0 || errno == EPERM);
  }
  bool sync() { return ::fsync(out.fd) == 0; }
  bool close() {
    const int fd = out.fd;
    out.fd = -1;
    return ::close(fd) == 0;
  }
};

#endif

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

#ifdef _WIN32

// Writes a target that is no disk file (a device such as NUL or CON, a named pipe) in place.
void write_direct(const std::string& target, const std::string& named, const std::vector<std::uint8_t>& data) {
  NewFile out;
  out.file.h = CreateFileW(from_utf8(target).c_str(), GENERIC_WRITE, share_all, nullptr, OPEN_EXISTING,
                           FILE_ATTRIBUTE_NORMAL, nullptr);
  if (out.file.h == INVALID_HANDLE_VALUE) {
    failed_windows();
    throw system_error(named, "cannot open for writing", errno);
  }
  if (!out.write(data.data(), data.size())) throw system_error(named, "write failed", errno);
}

// The file an output path names. Windows resolves symbolic links and junctions itself when a file is opened; a
// rename replaces the name given (a link is replaced, not its target).
std::string output_target(const std::string& path) { return path; }

template <class Container>
Container read_all(const std::string& path, std::uint64_t max_bytes) {
  // FILE_FLAG_BACKUP_SEMANTICS opens a folder too, so that it is reported as one.
  Handle file{CreateFileW(from_utf8(path).c_str(), GENERIC_READ, share_all, nullptr, OPEN_EXISTING,
                          FILE_FLAG_BACKUP_SEMANTICS, nullptr)};
  if (file.h == INVALID_HANDLE_VALUE) {
    failed_windows();
    throw system_error(path, "cannot open for reading", errno);
  }
  BY_HANDLE_FILE_INFORMATION info{};
  if (GetFileType(file.h) == FILE_TYPE_DISK && GetFileInformationByHandle(file.h, &info) &&
      (info.dwFileAttributes & FILE_ATTRIBUTE_DIRECTORY))
    throw Error::in_file(path, "", "is a directory, not a file");
  if (GetFileType(file.h) != FILE_TYPE_DISK)
    throw Error::in_file(path, "", "is not a regular file (a device, pipe or console)");
  LARGE_INTEGER bytes{};
  if (!GetFileSizeEx(file.h, &bytes)) {
    failed_windows();
    throw Error::in_file(path, "", std::string("cannot read its attributes: ") + std::strerror(errno));
  }
  const auto size = static_cast<std::uint64_t>(bytes.QuadPart);
  if (size > max_bytes)
    throw Error::in_file(
        path, "", "file is " + std::to_string(size) + " bytes, more than the limit of " + std::to_string(max_bytes));
  Container data(static_cast<std::size_t>(size), {});
  std::size_t done = 0;
  while (done < data.size()) {  // a file that shrinks while read ends early; one that grows is read to `size`
    const DWORD chunk = static_cast<DWORD>(std::min<std::size_t>(data.size() - done, 1u << 30));
    DWORD got = 0;
    if (!ReadFile(file.h, reinterpret_cast<char*>(data.data()) + done, chunk, &got, nullptr)) {
      failed_windows();
      throw Error::in_file(path, "", std::string("read failed: ") + std::strerror(errno));
    }
    if (got == 0) break;
    done += got;
  }
  data.resize(done);
  return data;
}

#else  // POSIX

// Writes a device or FIFO in place.
void write_direct(const std::string& target, const std::string& named, const std::vector<std::uint8_t>& data) {
  // O_NONBLOCK: a FIFO without a reader is refused (ENXIO) instead of blocking this process for ever.
  Descriptor out{::open(target.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK)};
  if (out.fd < 0 && errno == ENXIO) throw Error::environment(named, "is a FIFO that no process reads: nothing written");
  if (out.fd < 0) throw system_error(named, "cannot open for writing", errno);
  const int flags = ::fcntl(out.fd, F_GETFL);
  if (flags < 0 || ::fcntl(out.fd, F_SETFL, flags & ~O_NONBLOCK) != 0)
    throw system_error(named, "cannot open for writing", errno);
  if (!write_all(out.fd, data.data(), data.size())) throw system_error(named, "write failed", errno);
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
    throw Error::in_file(
        path, "", "file is " + std::to_string(size) + " bytes, more than the limit of " + std::to_string(max_bytes));
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

#endif

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
    if (!entry.temp.empty()) remove_file(entry.temp);
}

void FileTransaction::stage(const std::string& path, std::string_view text) {
  stage(path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

void FileTransaction::stage_written(const std::string& path, const std::string& written) {
  struct Remove {
    const std::string& file;
    ~Remove() { remove_file(file); }
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
  const fs::path same = fs::absolute(from_utf8(entry.target), ec).lexically_normal();
  for (const Entry& other : entries_)
    if (fs::absolute(from_utf8(other.target), ec).lexically_normal() == same)
      throw Error::in_file(path, "", "names the same file as " + other.named + ", another output of this run");
  const FileStatus existing = file_status(entry.target);
  entry.existed = existing.kind != FileKind::missing;
  if (existing.kind == FileKind::directory) throw Error::in_file(path, "", "is a directory, not a file");
  if (existing.kind == FileKind::other) {  // a device or FIFO: written directly by commit()
    entry.existed = false;
    entry.direct.assign(data.begin(), data.end());
    entries_.push_back(std::move(entry));
    return;
  }

  // A temporary file beside the target, named so that one left by a killed process is recognisable:
  // .NAME.deform-tmp-NUMBER (docs/reliability.md).
  const fs::path target = from_utf8(entry.target);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string temp_prefix = "." + to_utf8(target.filename()) + ".deform-tmp-";
  if (injected_failure()) throw system_error(path, "cannot create a temporary file beside it", errno);
  if (written != nullptr) {  // already written: moved beside the target under a temporary name, or copied there
    bool moved = false;
    for (int attempt = 0; attempt < 16 && !moved; ++attempt) {
      entry.temp = to_utf8(folder / from_utf8(temp_prefix + random_suffix()));
      if (exists_no_follow(entry.temp)) continue;
      if (rename_new(*written, entry.temp)) {
        moved = true;
      } else if (errno == EXDEV) {
        stage(path, read_file_bytes(*written), nullptr);
        return;
      } else {
        throw system_error(path, "cannot move the written file beside it", errno);
      }
    }
    if (!moved) throw system_error(path, "cannot move the written file beside it", EEXIST);
    if (entry.existed && !keep_mode_and_owner(entry.temp, existing)) {
      const int code = errno;
      remove_file(entry.temp);
      throw system_error(path, "cannot keep the file's mode and owner", code);
    }
    entries_.push_back(std::move(entry));
    return;
  }
  NewFile out;
  bool created = false;
  for (int attempt = 0; attempt < 16 && !created; ++attempt) {
    entry.temp = to_utf8(folder / from_utf8(temp_prefix + random_suffix()));
    created = out.create(entry.temp);
    if (!created && errno != EEXIST) break;
  }
  if (!created) throw system_error(path, "cannot create a temporary file beside it", errno);

  std::string failure;
  int code = 0;
  const auto failed = [&](const char* what) {
    code = errno;
    failure = what;
  };
  if (!out.write(data.data(), data.size())) failed("write failed");
  // Keep the replaced file's permissions, and its owner where this process may set it (root, or the same owner).
  if (failure.empty() && entry.existed && !out.keep(existing)) failed("cannot keep the file's mode and owner");
  if (failure.empty() && !out.sync()) failed("fsync failed");
  if (!out.close() && failure.empty()) failed("close failed");
  if (!failure.empty()) {
    remove_file(entry.temp);
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
        const fs::path target = from_utf8(entry.target);
        const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
        if (injected_failure()) throw system_error(entry.named, "cannot keep a backup of it", errno);
        for (int attempt = 0; attempt < 16 && entry.backup.empty(); ++attempt) {
          std::string backup =
              to_utf8(folder / from_utf8("." + to_utf8(target.filename()) + ".deform-bak-" + random_suffix()));
          // A hard link leaves the target in place; a file system without them gets a rename (the target is then
          // missing until the staged file lands, never changed).
          if (hard_link(entry.target, backup) || (errno != EEXIST && rename_new(entry.target, backup)))
            entry.backup = std::move(backup);
          else if (errno != EEXIST) throw system_error(entry.named, "cannot keep a backup of it", errno);
        }
        if (entry.backup.empty()) throw system_error(entry.named, "cannot keep a backup of it", EEXIST);
      }
      if (injected_failure() || !rename_over(entry.temp, entry.target))
        throw system_error(entry.named, "cannot move into place", errno);
      entry.placed = true;
    }
    for (Entry& entry : entries_) {
      if (!entry.temp.empty()) continue;
      if (injected_failure()) throw system_error(entry.named, "write failed", errno);
      write_direct(entry.target, entry.named, entry.direct);
    }
  } catch (...) {
    roll_back();
    throw;
  }
  committed_ = true;
  for (const Entry& entry : entries_)
    if (!entry.backup.empty()) remove_file(entry.backup);
}

void FileTransaction::roll_back() noexcept {
  for (auto entry = entries_.rbegin(); entry != entries_.rend(); ++entry) {
    if (entry->placed) {
      if (!entry->backup.empty()) rename_over(entry->backup, entry->target);
      else if (!entry->existed) remove_file(entry->target);
    } else {
      if (!entry->backup.empty()) {
        // Backed up but not replaced: a hard link is removed; a rename is undone.
        if (file_status(entry->target).kind != FileKind::missing) remove_file(entry->backup);
        else rename_new(entry->backup, entry->target);
      }
      if (!entry->temp.empty()) remove_file(entry->temp);
    }
    entry->placed = false;
    entry->backup.clear();
  }
  committed_ = true;  // nothing left to remove; a failed transaction is not committed again
}

void write_file_atomic(const std::string& path, std::string_view text) {
  write_file_atomic(path,
                    std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace deform
