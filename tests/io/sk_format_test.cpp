// .sk files: byte layout, byte-exact round trips, and every malformed case of the spec with its offset and bone.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "runtime/skeleton_test_util.hpp"

namespace {

// std::bit_cast for 32-bit values, through memcpy: emscripten 3.1.6's libc++ has no std::bit_cast.
template <typename To, typename From>
To bits_as(From from) {
  static_assert(sizeof(To) == sizeof(From));
  To to;
  std::memcpy(&to, &from, sizeof to);
  return to;
}

// A bone record written field by field, so that tests can build files the Skeleton class would never produce.
struct RawBone {
  std::string name;
  std::int32_t parent = -1;
  std::vector<std::int32_t> children;
  float numbers[12] = {0, 0, 0, 0, 0, 0, 180, -180, 180, -180, 180, -180};  // t, r, max/min x, y, z
};

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}

std::vector<std::uint8_t> raw_sk(const std::vector<RawBone>& bones, std::int64_t count = -1) {
  std::vector<std::uint8_t> out = {'S', 'K', 'E', 'L'};
  put32(out, static_cast<std::uint32_t>(count >= 0 ? count : static_cast<std::int64_t>(bones.size())));
  for (const RawBone& b : bones) {
    std::uint8_t name[80] = {};
    std::memcpy(name, b.name.data(), std::min<std::size_t>(b.name.size(), 80));
    out.insert(out.end(), name, name + 80);
    for (float f : b.numbers) put32(out, bits_as<std::uint32_t>(f));
    put32(out, static_cast<std::uint32_t>(b.parent));
    put32(out, static_cast<std::uint32_t>(b.children.size()));
    for (std::int32_t c : b.children) put32(out, static_cast<std::uint32_t>(c));
  }
  return out;
}

// root(0) -> 2 -> 1: a parent later in the file.
std::vector<RawBone> valid_raw() {
  std::vector<RawBone> bones(3);
  bones[0].name = "root";
  bones[0].children = {2};
  bones[1].name = "tip";
  bones[1].parent = 2;
  bones[1].numbers[1] = 1.0f;
  bones[2].name = "mid";
  bones[2].parent = 0;
  bones[2].children = {1};
  bones[2].numbers[0] = 1.0f;
  return bones;
}

// Byte offset of bone `id`'s record in raw_sk(bones).
std::int64_t record_offset(const std::vector<RawBone>& bones, std::size_t id) {
  std::int64_t at = 8;
  for (std::size_t i = 0; i < id; ++i) at += 136 + 4 * static_cast<std::int64_t>(bones[i].children.size());
  return at;
}

struct Failure {
  std::int64_t offset = -2;
  std::string element;
  std::string message;
};

Failure failure_of(const std::vector<std::uint8_t>& bytes) {
  try {
    deform::parse_sk(bytes, "case.sk");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "case.sk");
    CHECK(e.where() == deform::Error::Where::byte);
    return {e.position(), e.element(), e.message()};
  }
  FAIL("accepted a malformed file");
  return {};
}

std::string data_path(const char* file) { return std::string(DEFORM_TEST_DATA) + "/skeleton/" + file; }

}  // namespace

TEST_CASE("format_sk writes the spec's layout") {
  const deform::Skeleton s(skeleton_test::arm_bones());
  const std::vector<std::uint8_t> bytes = deform::format_sk(s);
  // 5 records of 136 bytes + 4 child ids (2 + 1 + 1 + 0 + 0) after an 8-byte header.
  REQUIRE(bytes.size() == 8 + 5 * 136 + 4 * 4);
  CHECK(std::memcmp(bytes.data(), "SKEL\x05\0\0\0", 8) == 0);
  CHECK(std::memcmp(bytes.data() + 8, "root\0\0", 6) == 0);
  auto f32 = [&](std::size_t at) {
    return bits_as<float>(bytes[at] | bytes[at + 1] << 8 | bytes[at + 2] << 16 | bytes[at + 3] << 24);
  };
  auto i32 = [&](std::size_t at) {
    return static_cast<std::int32_t>(bytes[at] | bytes[at + 1] << 8 | bytes[at + 2] << 16 | bytes[at + 3] << 24);
  };
  const std::size_t elbow = 8 + (136 + 8) + (136 + 4);
  CHECK(std::memcmp(bytes.data() + elbow, "elbow", 6) == 0);
  CHECK(f32(elbow + 80 + 4) == 1.0f);  // ty
  CHECK(f32(elbow + 92) == 10.0f);     // rx
  CHECK(f32(elbow + 100) == 20.0f);    // rz
  CHECK(f32(elbow + 104) == 10.0f);    // max_rx
  CHECK(f32(elbow + 108) == -10.0f);   // min_rx
  CHECK(f32(elbow + 120) == 150.0f);   // max_rz
  CHECK(f32(elbow + 124) == 0.0f);     // min_rz
  CHECK(i32(elbow + 128) == 1);        // parent
  CHECK(i32(elbow + 132) == 1);        // child count
  CHECK(i32(elbow + 136) == 3);        // the wrist
}

TEST_CASE("round trips: read(write(s)) == s and write(read(bytes)) == bytes") {
  const deform::Skeleton s(skeleton_test::arm_bones());
  const deform::Skeleton back = deform::parse_sk(deform::format_sk(s));
  CHECK(std::equal(s.bones().begin(), s.bones().end(), back.bones().begin(), back.bones().end()));
  const std::vector<std::uint8_t> raw = raw_sk(valid_raw());
  const deform::Skeleton later = deform::parse_sk(raw);
  CHECK(deform::format_sk(later) == raw);
  CHECK(later.bone(1).parent == 2);
  CHECK(skeleton_test::head(later.bind_world()[1]) == glm::vec3(1, 1, 0));
  // Negative zero and odd floats survive to the bit.
  std::vector<RawBone> odd = valid_raw();
  odd[1].numbers[0] = -0.0f;
  odd[1].numbers[2] = std::numeric_limits<float>::denorm_min();
  odd[1].numbers[6] = odd[1].numbers[7] = 12.5f;  // locked axis
  CHECK(deform::format_sk(deform::parse_sk(raw_sk(odd))) == raw_sk(odd));
  // Names: empty, shared, 79 bytes, UTF-8.
  std::vector<deform::Bone> bones = skeleton_test::arm_bones();
  bones[1].name = "";
  bones[3].name = "head";
  bones[2].name = std::string(79, 'x');
  bones[0].name =
      "h\xC3\xBC"
      "fte";
  const deform::Skeleton named(bones);
  CHECK(std::equal(bones.begin(), bones.end(), deform::parse_sk(deform::format_sk(named)).bones().begin()));
}

TEST_CASE("write_sk / read_sk through a file, and the checked-in arm.sk") {
  const deform::Skeleton s(skeleton_test::arm_bones());
  const std::string path = (std::filesystem::temp_directory_path() / "deform_sk_format_test.sk").string();
  deform::write_sk(path, s);
  CHECK(deform::read_sk(path).bones().size() == 5);
  CHECK(deform::read_file_bytes(path) == deform::format_sk(s));
  std::filesystem::remove(path);
  CHECK_THROWS_AS(deform::read_sk(path), deform::Error);
  // tests/data/skeleton/arm.sk is format_sk(arm_bones()); DEFORM_WRITE_TEST_DATA=1 regenerates it.
  if (std::getenv("DEFORM_WRITE_TEST_DATA")) deform::write_sk(data_path("arm.sk"), s);
  CHECK(deform::read_file_bytes(data_path("arm.sk")) == deform::format_sk(s));
}

TEST_CASE("a name longer than 79 bytes (or with a NUL, or not UTF-8) cannot be written") {
  for (const std::string& name : {std::string(80, 'x'), std::string("a\0b", 3), std::string("\xFF")}) {
    std::vector<deform::Bone> bones = skeleton_test::arm_bones();
    bones[3].name = name;
    const deform::Skeleton s(bones);
    try {
      deform::format_sk(s);
      FAIL("wrote an unwritable name");
    } catch (const deform::Error& e) {
      CHECK(e.element() == "bone 3");
    }
  }
}

TEST_CASE("malformed files: each an error with the byte offset and the bone") {
  const std::vector<RawBone> good = valid_raw();
  const std::vector<std::uint8_t> bytes = raw_sk(good);
  const auto at = [&](std::size_t id, std::int64_t field) { return record_offset(good, id) + field; };

  SUBCASE("header") {
    std::vector<std::uint8_t> b = bytes;
    b[2] = 'X';
    CHECK(failure_of(b).offset == 0);
    CHECK(failure_of({'S', 'K', 'E'}).offset == 0);
    CHECK(failure_of({}).offset == 0);
    CHECK(failure_of(raw_sk({}, 0)).offset == 4);
    CHECK(failure_of(raw_sk(good, 65536)).offset == 4);
    CHECK(failure_of(raw_sk(good, 0xFFFFFFFF)).offset == 4);  // -1
    CHECK(failure_of(raw_sk(good, 0x7FFFFFFF)).offset == 4);
    const Failure many = failure_of(raw_sk(good, 4));  // more bones than bytes
    CHECK(many.offset == 4);
    CHECK(many.message.find("bone count 4") != std::string::npos);
  }
  SUBCASE("truncation anywhere") {
    for (std::size_t size = 0; size < bytes.size(); ++size) {
      const Failure f =
          failure_of(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size)));
      CHECK(f.offset >= 0);
      CHECK(f.offset <= static_cast<std::int64_t>(size));
    }
    // Cut inside bone 2's record (the child ids before it keep the bone count plausible): reported at its start.
    Failure f = failure_of(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + at(2, 133)));
    CHECK(f.offset == at(2, 0));
    CHECK(f.element == "bone 2");
    // Cut inside its child ids: the child count overruns.
    f = failure_of(std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 1));
    CHECK(f.offset == at(2, 132));
    CHECK(f.element == "bone 2");
    // Cut inside the first record: the bone count no longer fits.
    CHECK(failure_of(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + at(0, 100))).offset == 4);
  }
  SUBCASE("trailing bytes") {
    std::vector<std::uint8_t> b = bytes;
    b.push_back(0);
    const Failure f = failure_of(b);
    CHECK(f.offset == static_cast<std::int64_t>(bytes.size()));
  }
  SUBCASE("child counts that overrun, negative child counts") {
    std::vector<RawBone> bad = good;
    std::vector<std::uint8_t> b = raw_sk(bad);
    b[static_cast<std::size_t>(at(2, 132))] = 0xFF;  // child count 255 + ...
    b[static_cast<std::size_t>(at(2, 135))] = 0x7F;
    Failure f = failure_of(b);
    CHECK(f.offset == at(2, 132));
    CHECK(f.element == "bone 2");
    b[static_cast<std::size_t>(at(2, 135))] = 0xFF;  // negative
    f = failure_of(b);
    CHECK(f.offset == at(2, 132));
  }
  SUBCASE("NaN and infinity") {
    for (int field = 0; field < 12; ++field) {
      std::vector<RawBone> bad = good;
      bad[1].numbers[field] = field % 2 ? std::numeric_limits<float>::infinity() : std::nanf("");
      const Failure f = failure_of(raw_sk(bad));
      CHECK(f.offset == at(1, 80 + 4 * field));
      CHECK(f.element == "bone 1");
    }
  }
  SUBCASE("min > max") {
    std::vector<RawBone> bad = good;
    bad[2].numbers[8] = -5.0f;  // max_ry
    bad[2].numbers[9] = 5.0f;   // min_ry
    const Failure f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(2, 104));
    CHECK(f.element == "bone 2");
    CHECK(f.message.find("min > max") != std::string::npos);
  }
  SUBCASE("out-of-range ids") {
    std::vector<RawBone> bad = good;
    bad[1].parent = 3;
    Failure f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(1, 128));
    CHECK(f.element == "bone 1");
    bad = good;
    bad[2].children = {7};
    f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(2, 136));
    CHECK(f.element == "bone 2");
    bad = good;
    bad[2].children = {-1};
    CHECK(failure_of(raw_sk(bad)).element == "bone 2");
  }
  SUBCASE("several roots, root not first") {
    std::vector<RawBone> bad = good;
    bad[1].parent = -1;
    bad[2].children = {};
    Failure f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(1, 128));
    CHECK(f.element == "bone 1");
    CHECK(f.message.find("second root") != std::string::npos);
    bad = good;
    bad[0].parent = 2;
    f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(0, 128));
    CHECK(f.element == "bone 0");
  }
  SUBCASE("cycles") {
    std::vector<RawBone> bad = good;
    bad[0].children = {};
    bad[2].parent = 1;  // 1 -> 2 -> 1
    bad[1].children = {2};
    const Failure f = failure_of(raw_sk(bad));
    CHECK(f.message.find("cycle") != std::string::npos);
    CHECK(f.element == "bone 1");
    CHECK(f.offset == record_offset(bad, 1) + 128);
  }
  SUBCASE("child lists that disagree with the parents") {
    std::vector<RawBone> bad = good;
    bad[2].children = {};  // tip's parent does not list it
    Failure f = failure_of(raw_sk(bad));
    CHECK(f.element == "bone 1");
    CHECK(f.message.find("does not list") != std::string::npos);
    bad = good;
    bad[0].children = {2, 1};  // root lists tip, whose parent is mid
    f = failure_of(raw_sk(bad));
    CHECK(f.element == "bone 0");
    CHECK(f.offset == at(0, 136));
    bad = good;
    bad[2].children = {1, 1};  // listed twice
    f = failure_of(raw_sk(bad));
    CHECK(f.element == "bone 2");
    CHECK(f.message.find("twice") != std::string::npos);
  }
  SUBCASE("names") {
    std::vector<RawBone> bad = good;
    bad[1].name = std::string(80, 'n');  // no NUL in 80 bytes
    Failure f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(1, 0));
    CHECK(f.element == "bone 1");
    bad[1].name = std::string("ab\0c", 4);  // junk after the terminator
    f = failure_of(raw_sk(bad));
    CHECK(f.offset == at(1, 3));
    bad[1].name = "\xC0\xAF";  // overlong UTF-8
    CHECK(failure_of(raw_sk(bad)).offset == at(1, 0));
    bad[1].name = "\xED\xA0\x80";  // a surrogate
    CHECK(failure_of(raw_sk(bad)).element == "bone 1");
  }
}
