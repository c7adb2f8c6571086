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
DEFORM_IO_API std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes = max_file_bytes);
DEFORM_IO_API std::string read_file_text(const std::string& path, std::uint64_t max_bytes = max_file_bytes);

// Writes `data` to what `path` names without changing its kind: a regular file is replaced atomically (a temporary
// file .NAME.deform-tmp-N beside it, then a rename), keeping an existing file's mode and, where permitted, owner; a
// symbolic link is followed (its target is replaced, the link stays); a device or FIFO is written directly. A failed
// write leaves no partial file, never truncates an existing one and removes its temporary file. Throws
// deform::Error naming `path` on failure.
DEFORM_IO_API void write_file_atomic(const std::string& path, std::span<const std::uint8_t> data);
DEFORM_IO_API void write_file_atomic(const std::string& path, std::string_view text);

}  // namespace deform
