// Seeded mutation fuzzing of the .sk and .skw readers: thousands of mutants of valid inputs (bit flips, truncation,
// insertion, deletion, duplicated spans, huge counts). Each must parse or throw deform::Error, never anything else;
// what parses must be a valid skeleton (resp. weights) and, for .sk, write back to the very same bytes.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "runtime/skeleton_test_util.hpp"

namespace {

using Rng = std::mt19937;

std::size_t pick(Rng& rng, std::size_t size) {
  return size == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, size - 1)(rng);
}

// One random edit of `data` (bytes or text), biased towards the shapes that break readers.
template <typename Container, typename Value>
void mutate(Container& data, Rng& rng, const std::vector<Value>& alphabet) {
  switch (pick(rng, 7)) {
    case 0:  // flip one bit
      if (!data.empty()) data[pick(rng, data.size())] ^= static_cast<Value>(1u << pick(rng, 8));
      break;
    case 1:  // truncate
      data.resize(pick(rng, data.size() + 1));
      break;
    case 2: {  // insert a few values
      const std::size_t at = pick(rng, data.size() + 1);
      const std::size_t count = 1 + pick(rng, 8);
      for (std::size_t k = 0; k < count; ++k)
        data.insert(data.begin() + static_cast<std::ptrdiff_t>(at), alphabet[pick(rng, alphabet.size())]);
      break;
    }
    case 3: {  // delete a span
      const std::size_t at = pick(rng, data.size() + 1);
      const std::size_t count = std::min(data.size() - at, 1 + pick(rng, 16));
      data.erase(data.begin() + static_cast<std::ptrdiff_t>(at),
                 data.begin() + static_cast<std::ptrdiff_t>(at + count));
      break;
    }
    case 4: {  // duplicate a span
      const std::size_t at = pick(rng, data.size() + 1);
      const std::size_t count = std::min(data.size() - at, 1 + pick(rng, 64));
      const Container span(data.begin() + static_cast<std::ptrdiff_t>(at),
                           data.begin() + static_cast<std::ptrdiff_t>(at + count));
      data.insert(data.begin() + static_cast<std::ptrdiff_t>(pick(rng, data.size() + 1)), span.begin(), span.end());
      break;
    }
    default:  // overwrite one value
      if (!data.empty()) data[pick(rng, data.size())] = alphabet[pick(rng, alphabet.size())];
      break;
  }
}

// Writes a little-endian int32 at a random 4-aligned offset: counts, parents and child ids land on such offsets.
void plant_int(std::vector<std::uint8_t>& bytes, Rng& rng) {
  static const std::uint32_t values[] = {
      0,         1,          2,          3,          4,          5,       65535,
      65536,     0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 0xFFFFFFFE, 1000000, 0x7F800000 /* inf */,
      0x7FC00000 /* NaN */};
  if (bytes.size() < 4) return;
  const std::size_t at = pick(rng, bytes.size() / 4) * 4;
  const std::uint32_t v = values[pick(rng, std::size(values))];
  for (int k = 0; k < 4; ++k) bytes[at + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(v >> (8 * k));
}

}  // namespace

TEST_CASE("fuzz .sk: 30000 mutants parse or throw deform::Error; what parses writes back byte-exact") {
  std::vector<deform::Bone> bones = skeleton_test::arm_bones();
  bones[4].name = "";
  bones.push_back(skeleton_test::make_bone("tip", 6, {}, {0, 0.1f, 0}));  // its parent comes later in the file
  bones.push_back(skeleton_test::make_bone("late parent", 0, {5}, {0.2f, 0, 0}, {0, 30, 0}));
  bones[0].children.push_back(6);
  const std::vector<std::uint8_t> valid = deform::format_sk(deform::Skeleton(bones));
  std::vector<std::uint8_t> alphabet;
  for (int v = 0; v < 256; ++v) alphabet.push_back(static_cast<std::uint8_t>(v));

  Rng rng(20261121);
  int parsed = 0, rejected = 0;
  for (int i = 0; i < 30000; ++i) {
    std::vector<std::uint8_t> bytes = valid;
    const std::size_t edits = 1 + pick(rng, 3);
    for (std::size_t e = 0; e < edits; ++e) {
      if (pick(rng, 3) == 0) plant_int(bytes, rng);
      else mutate(bytes, rng, alphabet);
    }
    try {
      const deform::Skeleton s = deform::parse_sk(bytes, "fuzz.sk");
      ++parsed;
      REQUIRE(deform::format_sk(s) == bytes);
      REQUIRE(s.order().size() == s.bone_count());
    } catch (const deform::Error&) {
      ++rejected;
    } catch (...) {
      FAIL("mutant " << i << " threw something other than deform::Error");
    }
  }
  MESSAGE(parsed << " mutants parsed, " << rejected << " rejected");
  CHECK(parsed > 1000);    // the mutations reach past the header...
  CHECK(rejected > 1000);  // ...and break things
}

TEST_CASE("fuzz .skw: 30000 mutants parse or throw deform::Error; what parses is normalised and in range") {
  const std::string valid =
      "# test weights\nskw 1\nvertices 6\n0 0 1\n1 1 0.5 2 0.5  # two\n2 2 0.25 3 0.25 4 0.25 5 0.25 6 0.1\n"
      "\n3 6 1.0\n4 0 0.3 6 0.7\n5 5 2 4 1e-3\n";
  const std::string chars = "0123456789 .-+e#\n\t\rxvsk";
  std::vector<char> alphabet(chars.begin(), chars.end());
  const std::size_t bone_count = 7;

  Rng rng(4711);
  int parsed = 0, rejected = 0;
  for (int i = 0; i < 30000; ++i) {
    std::string text = valid;
    const std::size_t edits = 1 + pick(rng, 3);
    for (std::size_t e = 0; e < edits; ++e) {
      if (pick(rng, 8) == 0) {
        text.insert(pick(rng, text.size() + 1), pick(rng, 2) ? "99999999999999999999" : "4294967296");
      } else {
        mutate(text, rng, alphabet);
      }
    }
    try {
      const deform::SkinWeights w = deform::parse_skw(text, 6, bone_count, "fuzz.skw");
      ++parsed;
      REQUIRE(w.size() == 6);
      for (std::size_t v = 0; v < w.size(); ++v) {
        const glm::vec4 weights = w.weights[v];
        CHECK(weights.x + weights.y + weights.z + weights.w == doctest::Approx(1.0f).epsilon(1e-5));
        for (int k = 0; k < 4; ++k) {
          CHECK(w.bones[v][k] < bone_count);
          CHECK(weights[k] >= 0.0f);
          if (k > 0) CHECK(weights[k] <= weights[k - 1]);
        }
      }
      REQUIRE(deform::parse_skw(deform::format_skw(w), 6, bone_count).bones == w.bones);
    } catch (const deform::Error&) {
      ++rejected;
    } catch (...) {
      FAIL("mutant " << i << " threw something other than deform::Error");
    }
  }
  MESSAGE(parsed << " mutants parsed, " << rejected << " rejected");
  CHECK(parsed > 1000);
  CHECK(rejected > 1000);
}
