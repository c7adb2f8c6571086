// Seeded mutation fuzzing of the OBJ and MTL readers: every mutated text either parses into a consistent mesh or
// throws deform::Error; any other exception, a crash or a sanitizer report fails the test.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace {

const std::string data_folder = DEFORM_TEST_DATA "/mesh";

constexpr std::string_view obj_seed =
    "# seed\r\nmtllib cube.mtl\no thing\nv 0 0 0\nv 1 0 0 1\nv 1 1 0\nv 0 1 0 0.5 0.5 0.5\nv 0 0 1\n"
    "vt 0 0\nvt 1 0\nvt 1 1 0\nvn 0 0 1\nvn 0 1 0\ng side\nusemtl red\ns 1\nf 1 2 3\nf 1/1 2/2 3/3 4/1\n"
    "f -1//-1 -2//-2 -3//1\nusemtl checker\nf 1/1/1 2/2/2 3/3/1 4/1/2 5/2/1\nl 1 2\nf 5 \\\n 4 3\n";

// Tokens that stress numbers and indices.
constexpr std::string_view nasty_tokens[] = {"0",
                                             "-0",
                                             "99999999999999999999",
                                             "-9223372036854775808",
                                             "4294967296",
                                             "4294967295",
                                             "2147483648",
                                             "-1",
                                             "1e39",
                                             "1e-50",
                                             "nan",
                                             "-inf",
                                             "1/",
                                             "//",
                                             "1//",
                                             "/1/1",
                                             "1/1/1/1",
                                             "+",
                                             "-",
                                             ".",
                                             "e5",
                                             "0x10",
                                             "\\",
                                             "#",
                                             "f",
                                             "v",
                                             "mtllib",
                                             "usemtl",
                                             "-s",
                                             "map_Kd"};

std::string mutate(std::string text, std::mt19937& random) {
  const int edits = 1 + int(random() % 4);
  for (int e = 0; e < edits; ++e) {
    const std::size_t at = text.empty() ? 0 : random() % (text.size() + 1);
    switch (random() % 7) {
      case 0:  // replace a byte with any byte
        if (at < text.size()) text[at] = char(random() % 256);
        break;
      case 1:  // insert a syntax character
        text.insert(at, 1, " \n/-.#\\e0123456789\r\t"[random() % 21]);
        break;
      case 2:  // delete a run of bytes
        text.erase(std::min(at, text.size()), random() % 8);
        break;
      case 3:  // truncate
        text.resize(at);
        break;
      case 4: {  // insert a nasty token between blanks
        const auto token = nasty_tokens[random() % std::size(nasty_tokens)];
        text.insert(at, " " + std::string(token) + " ");
        break;
      }
      case 5: {  // delete one token
        const std::size_t start = text.find(' ', at);
        if (start == std::string::npos) break;
        const std::size_t end = text.find_first_of(" \n", start + 1);
        text.erase(start, end == std::string::npos ? std::string::npos : end - start);
        break;
      }
      default: {  // duplicate a line
        const std::size_t start = text.rfind('\n', at);
        const std::size_t begin = start == std::string::npos ? 0 : start + 1;
        const std::size_t end = text.find('\n', begin);
        if (end != std::string::npos) text.insert(begin, text.substr(begin, end - begin + 1));
        break;
      }
    }
  }
  return text;
}

// The invariants every parsed mesh keeps, whatever the text was.
void check_consistent(const deform::Mesh& mesh) {
  REQUIRE(mesh.vertex_normals.size() == mesh.vertex_count());
  REQUIRE((mesh.vertex_uvs.empty() || mesh.vertex_uvs.size() == mesh.vertex_count()));
  for (const std::uint32_t point : mesh.vertex_point) REQUIRE(point < mesh.point_count());
  for (const std::uint32_t vertex : mesh.triangles) REQUIRE(vertex < mesh.vertex_count());
  std::size_t corners = 0, triangles = 0;
  for (const std::uint32_t size : mesh.face_sizes) {
    REQUIRE(size >= 3);
    corners += size;
    triangles += size - 2;
  }
  REQUIRE(corners == mesh.face_corners.size());
  REQUIRE(triangles == mesh.triangle_count());
  std::size_t next = 0;
  for (const deform::Submesh& submesh : mesh.submeshes) {
    REQUIRE(submesh.first_triangle == next);
    REQUIRE(submesh.triangle_count > 0);
    REQUIRE(submesh.material < std::int32_t(mesh.materials.size()));
    next += submesh.triangle_count;
  }
  REQUIRE(next == mesh.triangle_count());
  const auto finite = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  for (const glm::vec3& p : mesh.positions) REQUIRE(finite(p));
  for (const glm::vec3& n : mesh.vertex_normals) REQUIRE(finite(n));
}

}  // namespace

TEST_CASE("fuzz: mutated OBJ texts parse consistently or throw deform::Error") {
  std::mt19937 random(20261121);
  int parsed = 0, rejected = 0;
  for (int round = 0; round < 6000; ++round) {
    const std::string text = mutate(std::string(obj_seed), random);
    try {
      deform::Warnings warnings;
      check_consistent(deform::parse_obj(text, "fuzz.obj", data_folder, &warnings));
      ++parsed;
    } catch (const deform::Error& error) {
      REQUIRE(error.position() > 0);  // every OBJ error names its line
      ++rejected;
    } catch (const std::exception& other) {
      CAPTURE(text);
      FAIL("unexpected exception: " << other.what());
    }
  }
  MESSAGE(parsed << " parsed, " << rejected << " rejected");
  CHECK(parsed > 500);  // the mutations keep exercising both paths
  CHECK(rejected > 500);
}

TEST_CASE("fuzz: mutated MTL texts parse or throw deform::Error") {
  const std::string seed =
      deform::read_file_text(data_folder + "/cube.mtl") + "d -halo 0.5\nmap_Kd -o 1 2 -mm 0 1 x.png\n";
  std::mt19937 random(77);
  int parsed = 0, rejected = 0;
  for (int round = 0; round < 6000; ++round) {
    const std::string text = mutate(seed, random);
    try {
      deform::Warnings warnings;
      const auto materials = deform::parse_mtl(text, "fuzz.mtl", data_folder, &warnings);
      for (const auto& material : materials) REQUIRE_FALSE(material.name.empty());
      ++parsed;
    } catch (const deform::Error& error) {
      REQUIRE(error.position() > 0);
      ++rejected;
    } catch (const std::exception& other) {
      CAPTURE(text);
      FAIL("unexpected exception: " << other.what());
    }
  }
  MESSAGE(parsed << " parsed, " << rejected << " rejected");
  CHECK(parsed > 500);
  CHECK(rejected > 500);
}

TEST_CASE("fuzz: random bytes and long lines") {
  std::mt19937 random(1);
  for (int round = 0; round < 2000; ++round) {
    std::string text(random() % 200, '\0');
    for (char& c : text) c = char(random() % 256);
    if (round % 2) text.insert(0, round % 4 == 1 ? "f " : "v ");
    try {
      check_consistent(deform::parse_obj(text, "bytes.obj", data_folder));
    } catch (const deform::Error&) {
    }
  }
  // A face of 100000 corners and a 1 MB comment: linear, no recursion.
  std::string big = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf";
  for (int i = 0; i < 100000; ++i) big += " " + std::to_string(1 + i % 3);
  big += "\n#" + std::string(1 << 20, 'x') + "\n";
  const deform::Mesh mesh = deform::parse_obj(big);
  CHECK(mesh.triangle_count() == 99998);
  CHECK(mesh.vertex_count() == 3);
}
