#pragma once
// Whole-file reads with a size cap and atomic writes (temporary file in the same folder, then rename).
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "deform/io/export.hpp"
namespace deform {

// Largest file any libdeform reader accepts (1 GiB): a guard against unbounded allocation, not a format limit.
inline constexpr std::uint64_t max_file_bytes = 1ull << 30;

// Reads a whole file. Throws deform::Error (naming `path`) when it cannot be opened, is not a regular file (a FIFO,
// device or socket would block or never end) or is larger than `max_bytes`.
DEFORM_IO_API std::vector<std::uint8_t> read_file_bytes(const std::string& path,
                                                        std::uint64_t max_bytes = max_file_bytes);
DEFORM_IO_API std::string read_file_text(const std::string& path, std::uint64_t max_bytes = max_file_bytes);

// Writes `data` to what `path` names without changing its kind: a regular file is replaced atomically (a temporary
// file .NAME.deform-tmp-N beside it, then a rename), keeping an existing file's mode and, where permitted, owner; a
// symbolic link is followed, dangling or not (the file it points to is written or created, the link stays); a device
// is written directly, and so is a FIFO that has a reader (one without a reader is refused at once instead of
// blocking). A failed write leaves no partial file, never truncates an existing one and removes its temporary file.
// Throws deform::Error naming `path` on failure: kind input for a path that cannot name an output file (a folder, a
// missing folder, a link loop), kind environment for what the system refused (permissions, a full disk, a read-only
// file system, a FIFO without a reader). It is a FileTransaction of one file.
DEFORM_IO_API void write_file_atomic(const std::string& path, std::span<const std::uint8_t> data);
DEFORM_IO_API void write_file_atomic(const std::string& path, std::string_view text);

// A set of files replaced together or not at all (a .gltf and its .bin, an export's OBJ, MTL, .sk and .skw):
//   FileTransaction files;
//   files.stage("o.bin", bin);    // written now, as a temporary .o.bin.deform-tmp-N beside its target
//   files.stage("o.gltf", json);
//   files.commit();               // every file in place, or none changed
// stage() writes each file in full (and fsyncs it) before anything is replaced. commit() then puts them in place in
// the order staged: an existing target is first kept as a hard link .NAME.deform-bak-N (or, where the file system has
// no hard links, renamed to it), then the temporary file is renamed over it, so a target is never missing. If any step
// fails, the files already put in place are put back (each backup renamed over its target; a target that did not
// exist is removed), every temporary is removed and the error is thrown: the previous files are as they were, byte for
// byte. After success the backups are removed. Targets are what write_file_atomic writes (links followed, modes kept);
// a device or FIFO target is written directly after the renames (it cannot be put back). A transaction destroyed
// without commit() removes its temporaries and changes nothing. Errors: as write_file_atomic's, naming the file.
class DEFORM_IO_API FileTransaction {
 public:
  FileTransaction() = default;
  FileTransaction(const FileTransaction&) = delete;
  FileTransaction& operator=(const FileTransaction&) = delete;
  ~FileTransaction();

  void stage(const std::string& path, std::span<const std::uint8_t> data);
  void stage(const std::string& path, std::string_view text);
  // Stages a file already written in full at `written` (a regular file this process made, as a staging folder's):
  // it is moved beside `path`'s target as its temporary file, by a rename on the same file system (else copied and
  // removed). `written` is gone afterwards, whatever happens.
  void stage_written(const std::string& path, const std::string& written);
  // Puts every staged file in place, or none; a transaction commits once.
  void commit();

  struct Entry {
    std::string named;                 // the path as given, for messages
    std::string target;                // the file written: `named` with symbolic links followed
    std::string temp;                  // the staged temporary file; empty for a direct (device, FIFO) target
    std::string backup;                // the previous file's backup, while commit() runs
    std::vector<std::uint8_t> direct;  // what a device or FIFO target gets
    bool existed = false;              // a regular file was at `target` when staged
    bool placed = false;               // commit() renamed the temporary over `target`
  };

 private:
  void stage(const std::string& path, std::span<const std::uint8_t> data, const std::string* written);
  void roll_back() noexcept;
  std::vector<Entry> entries_;
  bool committed_ = false;
};

// Testing only (not part of the API's promise): every file-system step of the atomic writes and transactions above
// (staging a file, backing up a target, renaming a file into place, writing a device) is counted, and the step
// numbered `step` (0-based, counted from this call) fails as an I/O error (EIO) would; -1 injects nothing.
// file_steps_for_testing() is the number of steps taken since the last call to inject_file_failure_for_testing.
// One global setting: tests that use it run single-threaded.
DEFORM_IO_API void inject_file_failure_for_testing(long step);
DEFORM_IO_API long file_steps_for_testing();

}  // namespace deform
