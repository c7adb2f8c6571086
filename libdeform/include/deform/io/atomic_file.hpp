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

// Reads a whole file. Throws deform::Error (naming `path`) when it cannot be opened or is larger than `max_bytes`.
DEFORM_IO_API std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes = max_file_bytes);
DEFORM_IO_API std::string read_file_text(const std::string& path, std::uint64_t max_bytes = max_file_bytes);

// Writes `data` to `path` atomically: a failed write leaves no partial file and never truncates an existing one.
// Throws deform::Error on failure (the temporary file is removed).
DEFORM_IO_API void write_file_atomic(const std::string& path, std::span<const std::uint8_t> data);
DEFORM_IO_API void write_file_atomic(const std::string& path, std::string_view text);

}  // namespace deform
