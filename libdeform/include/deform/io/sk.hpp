#pragma once
// The .sk skeleton (binary) and .skw skin weight (text) files; docs/formats.md gives both to the byte.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "deform/io/export.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// --- .sk files (binary, docs/formats.md) ---

// Reads a .sk file; throws deform::Error with file, byte offset and bone id on any malformed input (names must be
// UTF-8, NUL-terminated within their 80 bytes and NUL-padded). Allocates at most O(file size).
DEFORM_IO_API Skeleton read_sk(const std::string& path);
DEFORM_IO_API Skeleton parse_sk(std::span<const std::uint8_t> bytes, const std::string& name = "<memory>");
// The .sk bytes of a skeleton: parse_sk(format_sk(s)) == s, format_sk(parse_sk(b)) == b. Throws deform::Error for a
// name longer than 79 bytes or holding a NUL.
DEFORM_IO_API std::vector<std::uint8_t> format_sk(const Skeleton& skeleton);
DEFORM_IO_API void write_sk(const std::string& path, const Skeleton& skeleton);  // atomic
// Reads a .skw file for a mesh with `point_count` points and a skeleton with `bone_count` bones; keeps the strongest
// `influences` influences per vertex (4 by default, at most max_requested_influences; past the fourth in
// SkinWeights' extras) and renormalises them. Throws deform::Error with file, line and vertex on malformed input
// (wrong header or count, a vertex missing, repeated or out of order, a bone out of range or listed twice on a line,
// a weight negative or non-finite, no positive weight), of kind argument for `influences` out of range.
// Allocates O(point_count) only once `vertices N` matches.
DEFORM_IO_API SkinWeights read_skw(const std::string& path, std::size_t point_count, std::size_t bone_count,
                                   int influences = max_influences);
DEFORM_IO_API SkinWeights parse_skw(std::string_view text, std::size_t point_count, std::size_t bone_count,
                                    const std::string& name = "<memory>", int influences = max_influences);
// .skw text: one line per vertex with its positive-weight pairs, the extras after the four slots; weights written
// shortest-exact, so parse_skw with enough `influences` reads them back to within one rounding of the
// renormalisation. Throws deform::Error for a vertex with no positive weight or malformed extras.
DEFORM_IO_API std::string format_skw(const SkinWeights& weights);
DEFORM_IO_API void write_skw(const std::string& path, const SkinWeights& weights);  // atomic

}  // namespace deform
