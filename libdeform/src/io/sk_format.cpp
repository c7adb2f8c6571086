// .sk skeleton files: binary, little-endian (docs/formats.md).
//
// Every length is checked against the bytes left before anything is allocated from it, so the reader's memory is
// bounded by the file size; every malformed case names the file, the byte offset of the offending field and the bone.
#include <array>
#include <cmath>
#include <cstring>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "skeleton_rules.hpp"

namespace deform {
namespace {

// std::bit_cast for 32-bit values, through memcpy: emscripten 3.1.6's libc++ has no std::bit_cast.
template <typename To, typename From>
To bits_as(From from) {
  static_assert(sizeof(To) == sizeof(From));
  To to;
  std::memcpy(&to, &from, sizeof to);
  return to;
}

constexpr std::array<std::uint8_t, 4> magic = {'S', 'K', 'E', 'L'};
constexpr std::size_t name_bytes = 80;
constexpr std::size_t header_bytes = 8;
// name, translation, rotation, six limits, parent, child_count.
constexpr std::size_t fixed_record_bytes = name_bytes + 4 * (3 + 3 + 6) + 4 + 4;
constexpr std::size_t translation_offset = name_bytes;
constexpr std::size_t rotation_offset = translation_offset + 12;
constexpr std::size_t limits_offset = rotation_offset + 12;
constexpr std::size_t parent_offset = limits_offset + 24;

std::string bone_element(std::int64_t id) { return id >= 0 ? "bone " + std::to_string(id) : std::string(); }

// True when `text` is well-formed UTF-8 (no overlongs, no surrogates, at most U+10FFFF).
bool valid_utf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t length = c < 0x80             ? 1
                               : (c & 0xE0) == 0xC0 ? 2
                               : (c & 0xF0) == 0xE0 ? 3
                               : (c & 0xF8) == 0xF0 ? 4
                                                    : 0;
    if (length == 0) return false;
    std::uint32_t code = length == 1 ? c : c & (0x7Fu >> length);
    if (i + length > text.size()) return false;
    for (std::size_t k = 1; k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xC0) != 0x80) return false;
      code = (code << 6) | (next & 0x3Fu);
    }
    constexpr std::uint32_t smallest[] = {0, 0, 0x80, 0x800, 0x10000};
    if (code < smallest[length] || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return false;
    i += length;
  }
  return true;
}

class Reader {
 public:
  Reader(std::span<const std::uint8_t> bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  std::size_t offset() const { return offset_; }
  std::size_t left() const { return bytes_.size() - offset_; }

  [[noreturn]] void fail(std::size_t at, std::int64_t bone, const std::string& message) const {
    throw Error::at_byte(name_, static_cast<std::int64_t>(at), bone_element(bone), message);
  }
  void need(std::size_t count, std::int64_t bone, const char* what) const {
    if (left() < count)
      fail(offset_, bone,
           std::string("file ends inside ") + what + " (" + std::to_string(count) + " bytes needed, " +
               std::to_string(left()) + " left)");
  }
  std::uint32_t u32() {
    const std::uint8_t* p = bytes_.data() + offset_;
    offset_ += 4;
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
  }
  std::int32_t i32() { return bits_as<std::int32_t>(u32()); }
  float f32(std::int64_t bone) {
    const std::size_t at = offset_;
    const float value = bits_as<float>(u32());
    if (!std::isfinite(value)) fail(at, bone, "number is not finite");
    return value;
  }
  std::string name(std::int64_t bone) {
    const std::size_t at = offset_;
    const auto* p = reinterpret_cast<const char*>(bytes_.data() + offset_);
    offset_ += name_bytes;
    const std::string_view field(p, name_bytes);
    const std::size_t end = field.find('\0');
    if (end == std::string_view::npos) fail(at, bone, "name has no terminating NUL within its 80 bytes");
    if (field.find_first_not_of('\0', end) != std::string_view::npos)
      fail(at + field.find_first_not_of('\0', end), bone, "name padding is not NUL");
    if (!valid_utf8(field.substr(0, end))) fail(at, bone, "name is not valid UTF-8");
    return std::string(field.substr(0, end));
  }

 private:
  std::span<const std::uint8_t> bytes_;
  const std::string& name_;
  std::size_t offset_ = 0;
};

struct RecordOffsets {
  std::size_t record, children;
};

class Writer {
 public:
  void bytes(const void* data, std::size_t count) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    out.insert(out.end(), p, p + count);
  }
  void u32(std::uint32_t v) {
    const std::uint8_t b[4] = {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
                               static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 24)};
    bytes(b, 4);
  }
  void i32(std::int32_t v) { u32(bits_as<std::uint32_t>(v)); }
  void f32(float v) { u32(bits_as<std::uint32_t>(v)); }

  std::vector<std::uint8_t> out;
};

}  // namespace

Skeleton parse_sk(std::span<const std::uint8_t> bytes, const std::string& name) {
  Reader in(bytes, name);
  in.need(header_bytes, -1, "the header");
  if (!std::equal(magic.begin(), magic.end(), bytes.begin())) in.fail(0, -1, "bad magic (expected \"SKEL\")");
  in.u32();
  const std::int32_t bone_count = in.i32();
  if (bone_count < 1 || static_cast<std::size_t>(bone_count) > detail::max_bones)
    in.fail(4, -1, "bone count " + std::to_string(bone_count) + " is outside 1..65535");
  const auto count = static_cast<std::size_t>(bone_count);
  if (count > in.left() / fixed_record_bytes)
    in.fail(4, -1,
            "bone count " + std::to_string(count) + " needs at least " + std::to_string(count * fixed_record_bytes) +
                " bytes, the file has " + std::to_string(in.left()) + " after the header");

  std::vector<Bone> bones(count);
  std::vector<RecordOffsets> offsets(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto id = static_cast<std::int64_t>(i);
    Bone& b = bones[i];
    offsets[i].record = in.offset();
    in.need(fixed_record_bytes, id, "a bone record");
    b.name = in.name(id);
    for (int k = 0; k < 3; ++k) b.bind_translation[k] = in.f32(id);
    for (int k = 0; k < 3; ++k) b.bind_rotation[k] = in.f32(id);
    for (int k = 0; k < 3; ++k) {
      b.limits.max[k] = in.f32(id);
      b.limits.min[k] = in.f32(id);
    }
    b.parent = in.i32();
    const std::size_t child_count_at = in.offset();
    const std::int32_t child_count = in.i32();
    if (child_count < 0 || static_cast<std::size_t>(child_count) > in.left() / 4)
      in.fail(child_count_at, id,
              "child count " + std::to_string(child_count) + " overruns the file (" + std::to_string(in.left()) +
                  " bytes left)");
    offsets[i].children = in.offset();
    b.children.resize(static_cast<std::size_t>(child_count));
    for (std::int32_t& child : b.children) child = in.i32();
  }
  if (in.left() != 0) in.fail(in.offset(), -1, std::to_string(in.left()) + " trailing bytes after the last bone");

  if (auto problem = detail::find_bone_problem(bones)) {
    using Field = detail::BoneProblem::Field;
    std::size_t at = header_bytes;
    if (problem->bone >= 0) {
      const RecordOffsets& o = offsets[static_cast<std::size_t>(problem->bone)];
      at = o.record;
      if (problem->field == Field::translation) at += translation_offset;
      if (problem->field == Field::rotation) at += rotation_offset;
      if (problem->field == Field::limits) at += limits_offset;
      if (problem->field == Field::parent) at += parent_offset;
      if (problem->field == Field::children) at = o.children;
    }
    in.fail(at, problem->bone, problem->message);
  }
  return Skeleton(std::move(bones), name);
}

Skeleton read_sk(const std::string& path) { return parse_sk(read_file_bytes(path), path); }

std::vector<std::uint8_t> format_sk(const Skeleton& skeleton) {
  Writer w;
  w.bytes(magic.data(), magic.size());
  w.i32(static_cast<std::int32_t>(skeleton.bone_count()));
  for (std::size_t i = 0; i < skeleton.bone_count(); ++i) {
    const Bone& b = skeleton.bones()[i];
    if (b.name.size() >= name_bytes || b.name.find('\0') != std::string::npos || !valid_utf8(b.name))
      throw Error::invalid_argument(bone_element(static_cast<std::int64_t>(i)),
                                    "name of " + std::to_string(b.name.size()) +
                                        " bytes cannot be written (.sk names are UTF-8, at most 79 bytes, no NUL)");
    std::array<char, name_bytes> name{};
    std::memcpy(name.data(), b.name.data(), b.name.size());
    w.bytes(name.data(), name.size());
    for (int k = 0; k < 3; ++k) w.f32(b.bind_translation[k]);
    for (int k = 0; k < 3; ++k) w.f32(b.bind_rotation[k]);
    for (int k = 0; k < 3; ++k) {
      w.f32(b.limits.max[k]);
      w.f32(b.limits.min[k]);
    }
    w.i32(b.parent);
    w.i32(static_cast<std::int32_t>(b.children.size()));
    for (std::int32_t child : b.children) w.i32(child);
  }
  return std::move(w.out);
}

void write_sk(const std::string& path, const Skeleton& skeleton) { write_file_atomic(path, format_sk(skeleton)); }

}  // namespace deform
