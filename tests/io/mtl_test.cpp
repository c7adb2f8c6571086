// MTL reader: every supported statement, defaults, texture options and paths, warnings and malformed lines.
#include <doctest/doctest.h>

#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace {

const std::string data_folder = DEFORM_TEST_DATA "/mesh";

std::vector<deform::Material> parse(std::string_view text, deform::Warnings* warnings = nullptr) {
  return deform::parse_mtl(text, "t.mtl", data_folder, warnings);
}

void check_error(std::string_view text, std::int64_t line, std::string_view fragment) {
  CAPTURE(text);
  try {
    parse(text);
    FAIL("no error thrown");
  } catch (const deform::Error& error) {
    CAPTURE(error.what());
    CHECK(error.file() == "t.mtl");
    CHECK(error.position() == line);
    CHECK(std::string(error.what()).find(fragment) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("mtl: every supported statement") {
  deform::Warnings warnings;
  const auto materials = parse(
      "# comment\r\nnewmtl skin tone\r\nKa 0.1 0.2 0.3\nKd 0.5\nKs 1 0.5 0.25\nNs 96.5\nd -halo 0.5\nillum 3\n"
      "map_Kd -blendu on -o 0.5 0.5 -s 2 -mm 0 1 -clamp off textures/checker.png\n"
      "newmtl plain\nTr 0.2\n",
      &warnings);
  CHECK(warnings.messages.empty());
  REQUIRE(materials.size() == 2);
  const deform::Material& skin = materials[0];
  CHECK(skin.name == "skin tone");
  CHECK(skin.ambient == glm::vec3(0.1f, 0.2f, 0.3f));
  CHECK(skin.diffuse == glm::vec3(0.5f));
  CHECK(skin.specular == glm::vec3(1, 0.5f, 0.25f));
  CHECK(skin.shininess == 96.5f);
  CHECK(skin.opacity == 0.5f);
  CHECK(skin.illum == 3);
  CHECK(skin.diffuse_map == data_folder + "/textures/checker.png");
  const deform::Material& plain = materials[1];  // MTL defaults where the file says nothing
  CHECK(plain.ambient == glm::vec3(0.2f));
  CHECK(plain.diffuse == glm::vec3(0.8f));
  CHECK(plain.specular == glm::vec3(0.0f));
  CHECK(plain.opacity == doctest::Approx(0.8f));
  CHECK(plain.illum == 2);
  CHECK(plain.diffuse_map.empty());
}

TEST_CASE("mtl: texture paths — relative to the MTL folder, absolute kept, blanks allowed, missing warned") {
  deform::Warnings warnings;
  // An absolute path outside the MTL's folder is refused unless its folder is allowed (referenced_file.hpp).
  const std::string text =
      "newmtl a\nmap_Kd textures/../textures/checker.png\n"
      "newmtl b\nmap_Kd /abs/path/t.png\n"
      "newmtl c\nmap_Kd my texture.png\n";
  CHECK_THROWS_WITH_AS(parse(text), doctest::Contains("t.mtl: line 4: map_Kd: refused"), deform::Error);
  deform::ReferencePolicy policy;
  policy.allow_outside = {"/abs"};
  const auto materials = deform::parse_mtl(text, "t.mtl", data_folder, &warnings, policy);
  CHECK(materials[0].diffuse_map == data_folder + "/textures/checker.png");
#ifdef _WIN32  // a path with a root but no drive is on the drive of the MTL's folder
  CHECK(materials[1].diffuse_map == data_folder.substr(0, 2) + "/abs/path/t.png");
#else
  CHECK(materials[1].diffuse_map == "/abs/path/t.png");
#endif
  CHECK(materials[2].diffuse_map == data_folder + "/my texture.png");
  REQUIRE(warnings.messages.size() == 2);
  CHECK(warnings.messages[0].starts_with("t.mtl: line 4: texture '/abs/path/t.png' not found"));
  CHECK(warnings.messages[1].starts_with("t.mtl: line 6: texture 'my texture.png' not found"));
}

TEST_CASE("mtl: statements it does not use — known ones silent, unknown ones warned once") {
  deform::Warnings warnings;
  const auto materials = parse("newmtl a\nNi 1.45\nKe 0 0 0\nmap_Bump n.png\nfoo 1\nfoo 2\n", &warnings);
  CHECK(materials.size() == 1);
  REQUIRE(warnings.messages.size() == 1);
  CHECK(warnings.messages[0] == "t.mtl: line 5: statement 'foo' is not supported: 2 skipped");
}

TEST_CASE("mtl: malformed lines") {
  check_error("Kd 1 1 1\n", 1, "Kd: statement before the first newmtl");
  check_error("newmtl\n", 1, "newmtl: missing material name");
  check_error("newmtl a\nKd 1 1\n", 2, "Kd: expected 1 or 3 numbers, found 2");
  check_error("newmtl a\nKd 1 1 1 1\n", 2, "too many numbers");
  check_error("newmtl a\nKa x\n", 2, "malformed number 'x'");
  check_error("newmtl a\nKs nan 0 0\n", 2, "not finite");
  check_error("newmtl a\nd\n", 2, "d: expected 1 numbers, found 0");
  check_error("newmtl a\nTr 0.5 0.5\n", 2, "too many numbers");
  check_error("newmtl a\nNs 1e40\n", 2, "out of range");
  check_error("newmtl a\nillum 11\n", 2, "illumination model 11 is not 0 to 10");
  check_error("newmtl a\nillum 2.5\n", 2, "malformed integer '2.5'");
  check_error("newmtl a\nillum 2 3\n", 2, "unexpected '3'");
  check_error("newmtl a\nmap_Kd\n", 2, "missing texture file name");
  check_error("newmtl a\nmap_Kd -s 1 1 1\n", 2, "missing texture file name");
  check_error("newmtl a\nmap_Kd -zoom 2 t.png\n", 2, "unknown texture option '-zoom'");
  check_error("newmtl a\nmap_Kd -s t.png\n", 2, "missing its numbers");
  check_error("newmtl a\nmap_Kd -clamp\n", 2, "missing its argument");
}
