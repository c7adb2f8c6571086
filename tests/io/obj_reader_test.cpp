// OBJ reader: every face form, relative indices, polygons, submeshes, materials, warnings and every malformed case.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace {

using deform::Mesh;

Mesh parse(std::string_view text, deform::Warnings* warnings = nullptr, deform::ObjNames* names = nullptr) {
  return deform::parse_obj(text, "t.obj", DEFORM_TEST_DATA "/mesh", warnings, {}, names);
}

// The OBJ `v` index (0-based) of every face corner, in file order.
std::vector<std::uint32_t> corner_points(const Mesh& mesh) {
  std::vector<std::uint32_t> points;
  for (const std::uint32_t vertex : mesh.face_corners) points.push_back(mesh.vertex_point[vertex]);
  return points;
}

std::vector<std::uint32_t> triangle_points(const Mesh& mesh) {
  std::vector<std::uint32_t> points;
  for (const std::uint32_t vertex : mesh.triangles) points.push_back(mesh.vertex_point[vertex]);
  return points;
}

// Parsing `text` throws deform::Error at `line` whose message contains `fragment`.
void check_error(std::string_view text, std::int64_t line, std::string_view fragment) {
  CAPTURE(text);
  try {
    parse(text);
    FAIL("no error thrown");
  } catch (const deform::Error& error) {
    CAPTURE(error.what());
    CHECK(error.file() == "t.obj");
    CHECK(error.where() == deform::Error::Where::line);
    CHECK(error.position() == line);
    CHECK(std::string(error.what()).find(fragment) != std::string::npos);
  }
}

bool contains(const deform::Warnings& warnings, std::string_view fragment) {
  for (const auto& message : warnings.messages)
    if (message.find(fragment) != std::string::npos) return true;
  return false;
}

constexpr std::string_view square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

}  // namespace

TEST_CASE("obj: empty file and comment-only file give an empty mesh") {
  for (const std::string_view text : {"", "\n\n", "# nothing\n   \n\t# more\n"}) {
    const Mesh mesh = parse(text);
    CHECK(mesh.point_count() == 0);
    CHECK(mesh.vertex_count() == 0);
    CHECK(mesh.triangle_count() == 0);
    CHECK(mesh.submeshes.empty());
  }
}

TEST_CASE("obj: points only — vertices counted, no triangles") {
  const Mesh mesh = parse("v 1 2 3\nv 4 5 6 1.0\nv -7 8.5e1 +9 0.1 0.2 0.3\n");
  REQUIRE(mesh.point_count() == 3);
  CHECK(mesh.positions[0] == glm::vec3(1, 2, 3));
  CHECK(mesh.positions[1] == glm::vec3(4, 5, 6));
  CHECK(mesh.positions[2] == glm::vec3(-7, 85, 9));
  CHECK(mesh.vertex_count() == 0);
  CHECK(mesh.triangle_count() == 0);
  CHECK(mesh.face_sizes.empty());
}

TEST_CASE("obj: face form v — one render vertex per point, computed normals") {
  const Mesh mesh = parse(std::string(square) + "f 1 2 3 4\n");
  CHECK(mesh.vertex_count() == 4);
  CHECK(mesh.vertex_point == std::vector<std::uint32_t>{0, 1, 2, 3});
  CHECK(mesh.face_sizes == std::vector<std::uint32_t>{4});
  CHECK(triangle_points(mesh) == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3});  // fan from the first corner
  CHECK(mesh.vertex_uvs.empty());
  REQUIRE(mesh.vertex_normals.size() == 4);
  for (const glm::vec3& n : mesh.vertex_normals) CHECK(n == glm::vec3(0, 0, 1));
}

TEST_CASE("obj: face form v/vt — split where UVs differ") {
  // Two triangles sharing points 1 and 3 (0-based 0 and 2) with different UVs on the second.
  const Mesh mesh = parse(std::string(square) +
                          "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5 0.25\n"
                          "f 1/1 2/2 3/3\nf 1/5 3/3 4/4\n");
  CHECK(mesh.vertex_point == std::vector<std::uint32_t>{0, 1, 2, 0, 3});
  REQUIRE(mesh.vertex_uvs.size() == 5);
  CHECK(mesh.vertex_uvs[0] == glm::vec2(0, 0));
  CHECK(mesh.vertex_uvs[3] == glm::vec2(0.5f, 0.5f));
  CHECK(mesh.vertex_uvs[4] == glm::vec2(0, 1));
  CHECK(mesh.triangles == std::vector<std::uint32_t>{0, 1, 2, 3, 2, 4});
}

TEST_CASE("obj: face form v//vn — normals as written") {
  const Mesh mesh = parse(std::string(square) + "vn 0 0 2\nvn 1 0 0\nf 1//1 2//1 3//2\n");
  CHECK(mesh.vertex_count() == 3);
  CHECK(mesh.vertex_uvs.empty());
  CHECK(mesh.vertex_normals == std::vector<glm::vec3>{{0, 0, 2}, {0, 0, 2}, {1, 0, 0}});
}

TEST_CASE("obj: face form v/vt/vn — deduplicated by the whole triple") {
  const Mesh mesh = parse(std::string(square) +
                          "vt 0 0\nvt 1 1\nvn 0 0 1\nvn 0 1 0\n"
                          "f 1/1/1 2/1/1 3/1/1\nf 1/1/1 3/1/1 4/1/1\nf 1/2/1 2/1/2 3/1/1\n");
  // Triples: (1,1,1) (2,1,1) (3,1,1) (4,1,1) (1,2,1) (2,1,2): six render vertices.
  CHECK(mesh.vertex_point == std::vector<std::uint32_t>{0, 1, 2, 3, 0, 1});
  CHECK(mesh.triangles == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 4, 5, 2});
  CHECK(mesh.vertex_uvs[4] == glm::vec2(1, 1));
  CHECK(mesh.vertex_normals[5] == glm::vec3(0, 1, 0));
}

TEST_CASE("obj: negative indices are relative to the elements read so far") {
  const Mesh relative = parse(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
      "f -3/-3/-1 -2/-2/-1 -1/-1/-1\n"
      "v 5 5 5\nf -4 -3 -1\n");
  const Mesh absolute = parse(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
      "f 1/1/1 2/2/1 3/3/1\n"
      "v 5 5 5\nf 1 2 4\n");
  CHECK(corner_points(relative) == std::vector<std::uint32_t>{0, 1, 2, 0, 1, 3});
  CHECK(corner_points(relative) == corner_points(absolute));
  CHECK(relative.vertex_uvs == absolute.vertex_uvs);
}

TEST_CASE("obj: polygons are fan-triangulated and kept whole for writing") {
  const Mesh mesh = parse(
      "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 2 2 0\nv 0 2 0\nv -1 1 0\n"
      "f 1 2 3 4 5 6\nf 1 2 3\n");
  CHECK(mesh.face_sizes == std::vector<std::uint32_t>{6, 3});
  CHECK(mesh.face_corners.size() == 9);
  CHECK(mesh.triangle_count() == 5);
  CHECK(triangle_points(mesh) == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 1, 2});
}

TEST_CASE("obj: faces may mix forms across faces, not within one") {
  const Mesh mesh = parse(std::string(square) + "vt 0 0\nvn 0 0 1\nf 1 2 3\nf 1/1 3/1 4/1\nf 1//1 2//1 4//1\n");
  CHECK(mesh.triangle_count() == 3);
  CHECK(mesh.vertex_uvs.size() == mesh.vertex_count());  // (0, 0) where a corner has no vt
  check_error(std::string(square) + "vt 0 0\nf 1/1 2 3\n", 6, "mixed");
  check_error(std::string(square) + "vt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3//1\n", 7, "f corner 2");
}

TEST_CASE("obj: o, g and usemtl start submeshes; s is ignored") {
  deform::Warnings warnings;
  deform::ObjNames names;
  const std::string text = std::string(square) +
                           "o first\ns 1\nf 1 2 3\nf 1 3 4\n"
                           "g part\nf 1 2 3\n"
                           "usemtl nowhere\ns off\nf 1 2 3\nusemtl nowhere\nf 1 3 4\n"
                           "o second\ng\nusemtl a\nusemtl nowhere\nf 1 2 4\n";
  const Mesh mesh = parse(text, &warnings, &names);
  REQUIRE(mesh.submeshes.size() == 4);
  CHECK(mesh.submeshes[0].first_triangle == 0);
  CHECK(mesh.submeshes[0].triangle_count == 2);
  CHECK(mesh.submeshes[1].first_triangle == 2);
  CHECK(mesh.submeshes[2].first_triangle == 3);
  CHECK(mesh.submeshes[2].triangle_count == 2);  // the repeated usemtl does not split
  CHECK(mesh.submeshes[2].material == -1);
  CHECK(mesh.submeshes[3].triangle_count == 1);
  // The names in effect, one entry per submesh (ObjNames); the mesh alone splits the same way without them.
  const std::vector<deform::ObjSubmeshNames> expected = {
      {"first", ""}, {"first", "part"}, {"first", "part"}, {"second", ""}};
  CHECK(names.submeshes == expected);
  CHECK(parse(text).submeshes.size() == 4);
  // One warning per unknown material name, at its first usemtl.
  REQUIRE(warnings.messages.size() == 1);
  CHECK(warnings.messages[0] == "t.obj: line 11: material 'nowhere' is not defined: default material used");
}

TEST_CASE("obj: cube fixture with MTL, materials and a texture resolved relative to the MTL") {
  deform::Warnings warnings;
  deform::ObjNames names;
  const Mesh mesh = deform::read_obj(DEFORM_TEST_DATA "/mesh/cube.obj", &warnings, {}, &names);
  CHECK(warnings.messages.empty());
  CHECK(mesh.point_count() == 8);
  CHECK(mesh.triangle_count() == 12);
  CHECK(mesh.vertex_count() == 24);  // each corner's (v, vt, vn) is unique on a flat-shaded cube
  REQUIRE(mesh.materials.size() == 2);
  CHECK(mesh.materials[0].name == "red");
  CHECK(mesh.materials[0].diffuse == glm::vec3(1, 0, 0));
  CHECK(mesh.materials[1].name == "checker");
  CHECK(mesh.materials[1].opacity == doctest::Approx(0.75f));
  CHECK(mesh.materials[1].diffuse_map == DEFORM_TEST_DATA "/mesh/textures/checker.png");
  REQUIRE(mesh.submeshes.size() == 2);
  CHECK(mesh.submeshes[0].material == 0);
  CHECK(mesh.submeshes[0].triangle_count == 6);
  CHECK(mesh.submeshes[1].material == 1);
  CHECK(mesh.submeshes[1].first_triangle == 6);
  REQUIRE(names.submeshes.size() == 2);
  CHECK(names.submeshes[1].object == "cube");
}

TEST_CASE("obj: a missing MTL is a warning naming file and line; the mesh still loads") {
  deform::Warnings warnings;
  const Mesh mesh =
      parse("# header\nmtllib missing.mtl cube.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n", &warnings);
  REQUIRE(warnings.messages.size() == 1);
  CHECK(warnings.messages[0].starts_with("t.obj: line 2: MTL file 'missing.mtl' not found"));
  CHECK(mesh.materials.size() == 2);  // cube.mtl on the same line was still read
  CHECK(mesh.submeshes[0].material == 0);
}

TEST_CASE("obj: a material defined twice keeps the first definition, with a warning; an MTL named twice is read once") {
  deform::Warnings warnings;
  deform::ObjNames names;
  const Mesh once = parse("mtllib cube.mtl\nmtllib cube.mtl cube.mtl\n", &warnings, &names);
  CHECK(once.materials.size() == 2);
  CHECK(names.material_libraries.size() == 1);
  CHECK(warnings.messages.empty());

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "deform_obj_two_mtl";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "a.mtl") << "newmtl red\nKd 1 0 0\n";
  std::ofstream(dir / "b.mtl") << "newmtl red\nKd 0 1 0\nnewmtl blue\nKd 0 0 1\n";
  const Mesh twice = deform::parse_obj("mtllib a.mtl\nmtllib b.mtl\n", "t.obj", dir.string(), &warnings);
  CHECK(twice.materials.size() == 2);
  CHECK(twice.materials[0].diffuse == glm::vec3(1.0f, 0.0f, 0.0f));
  REQUIRE(warnings.messages.size() == 1);
  CHECK(contains(warnings, "t.obj: line 2: material 'red' defined again"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("obj: a byte order mark is skipped, and one point used with many texture coordinates reads in linear time") {
  const Mesh bom = parse("\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CHECK(bom.point_count() == 3);
  CHECK(bom.triangle_count() == 1);

  // 100,000 faces on the same three points, each corner with its own `vt`: 300,000 render vertices, each found or
  // made in O(1) (the chain search alone would take minutes).
  std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  constexpr int faces = 100000;
  for (int i = 0; i < 3 * faces; ++i) text += "vt 0.5 0.5\n";
  for (int i = 0; i < faces; ++i) {
    const int t = 3 * i + 1;
    text += "f 1/" + std::to_string(t) + " 2/" + std::to_string(t + 1) + " 3/" + std::to_string(t + 2) + "\n";
  }
  text += "f 1/1 2/2 3/3\n";  // the first vertices again: found, not made
  const Mesh many = parse(text);
  CHECK(many.vertex_count() == 3 * faces);
  CHECK(many.triangles[3 * faces] == many.triangles[0]);
  CHECK(many.triangles[3 * faces + 2] == many.triangles[2]);
}

TEST_CASE("obj: unsupported statements are skipped with one warning per keyword") {
  deform::Warnings warnings;
  const Mesh mesh = parse(std::string(square) + "l 1 2\nl 2 3\np 1\ncurv 0 1 1 2\nf 1 2 3\nl 3 4\n", &warnings);
  CHECK(mesh.triangle_count() == 1);
  REQUIRE(warnings.messages.size() == 3);
  CHECK(warnings.messages[0] == "t.obj: line 5: statement 'l' is not supported: 3 skipped");
  CHECK(warnings.messages[1] == "t.obj: line 7: statement 'p' is not supported: 1 skipped");
  CHECK(warnings.messages[2] == "t.obj: line 8: statement 'curv' is not supported: 1 skipped");
}

TEST_CASE("obj: CRLF, tabs, trailing comments and line continuations") {
  const Mesh crlf = parse("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0 # corner\r\n\r\nf\t1 2 3\r\n");
  const Mesh continued = parse("v 0 \\\n 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\r\n2 \\\n 3\n# after\nf 1 2 3 \\");
  CHECK(crlf.positions == std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  CHECK(continued.positions == crlf.positions);
  CHECK(crlf.triangle_count() == 1);
  CHECK(continued.triangle_count() == 2);
  // Errors after a continuation report the line where the statement starts... and later lines stay counted right.
  check_error("v 0 \\\n0 0\nv 1\n", 3, "expected at least 3");
  check_error("v 0 \\\n0 x\n", 1, "malformed number 'x'");
}

TEST_CASE("obj: numbers — exponents, leading '+', underflow to zero; w and colours ignored") {
  const Mesh mesh = parse("v 1e2 -2.5E-1 +.5\nv 1e-60 0 0 1\nv 1 2 3 0.5 0.25 0.125\n");
  CHECK(mesh.positions[0] == glm::vec3(100, -0.25f, 0.5f));
  CHECK(mesh.positions[1] == glm::vec3(0, 0, 0));
  CHECK(mesh.positions[2] == glm::vec3(1, 2, 3));
}

TEST_CASE("obj: malformed lines throw deform::Error with file, line and element") {
  check_error("v 1 2\n", 1, "v: expected at least 3 numbers, found 2");
  check_error("v 1 2 3 4 5 6 7 8\n", 1, "too many numbers");
  check_error("v 1 2 abc\n", 1, "malformed number 'abc'");
  check_error("v 1 2 3x\n", 1, "malformed number '3x'");
  check_error("v 1 2 --3\n", 1, "malformed number");
  check_error("v 1 2 nan\n", 1, "not finite");
  check_error("v 1 2 inf\n", 1, "not finite");
  check_error("v 1 2 1e39\n", 1, "out of range");
  check_error("v 1 2 1e999\n", 1, "out of range");
  check_error("\nvn 0 1\n", 2, "vn: expected 3 numbers, found 2");
  check_error("vn 0 1 0 0\n", 1, "too many numbers");
  check_error("vt\n", 1, "vt: expected at least 1 numbers, found 0");
  check_error("vt 0 0 0 0\n", 1, "vt: too many numbers");
  check_error(std::string(square) + "f 1 2\n", 5, "at least 3 corners, found 2");
  check_error(std::string(square) + "f\n", 5, "found 0");
  check_error(std::string(square) + "f 1 0 3\n", 5, "f corner 2: v index 0");
  check_error(std::string(square) + "f 1 2 5\n", 5, "f corner 3: v index 5 is out of range: 4");
  check_error(std::string(square) + "f 1 2 -5\n", 5, "v index -5 is out of range");
  check_error(std::string(square) + "f 1 2 99999999999999999999\n", 5, "out of range");
  check_error(std::string(square) + "f 1/1 2/1 3/1\n", 5, "vt index 1 is out of range: 0");
  check_error(std::string(square) + "f 1//1 2//1 3//1\n", 5, "vn index 1 is out of range");
  check_error(std::string(square) + "f 1/ 2/ 3/\n", 5, "malformed corner '1/'");
  check_error(std::string(square) + "f 1// 2// 3//\n", 5, "malformed corner");
  check_error(std::string(square) + "f /1 2 3\n", 5, "malformed corner");
  check_error(std::string(square) + "f 1/1/1/1 2 3\n", 5, "malformed corner");
  check_error(std::string(square) + "f 1.5 2 3\n", 5, "malformed integer '1.5'");
  check_error(std::string(square) + "f 1 2 3 # fine\nf a b c\n", 6, "malformed integer 'a'");
  check_error("usemtl\n", 1, "usemtl: missing material name");
  check_error("mtllib\n", 1, "mtllib: missing file name");
  // A face refers only to elements above it.
  check_error("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", 1, "v index 1 is out of range: 0");
}

TEST_CASE("obj: read_obj of a missing file throws naming the file") {
  CHECK_THROWS_WITH_AS(deform::read_obj("/nonexistent/x.obj"), doctest::Contains("/nonexistent/x.obj"), deform::Error);
}

TEST_CASE("obj: an unsupported statement of garbage is reported in one bounded, printable line") {
  deform::Warnings warnings;
  const std::string garbage = "\x01\x02" + std::string(100000, '\0');
  const Mesh mesh = parse("v 0 0 0\n" + garbage + " 1 2\n", &warnings);
  CHECK(mesh.point_count() == 1);
  REQUIRE(warnings.messages.size() == 1);
  CHECK(warnings.messages[0].size() < 300);
  CHECK(warnings.messages[0].find("'\\x01\\x02\\x00") != std::string::npos);
}

TEST_CASE("obj: a long name copied into many submeshes is refused before memory runs away") {
  // A 1 MB object name, then the material alternating under it: every submesh would copy the name.
  std::string text = "v 0 0 0\nv 1 0 0\nv 0 1 0\no " + std::string(1 << 20, 'n') + "\n";
  for (int i = 0; i < 200; ++i) text += (i % 2 ? "usemtl a\n" : "usemtl b\n") + std::string("f 1 2 3\n");
  CHECK_THROWS_WITH_AS(parse(text), doctest::Contains("more submeshes than the file's size allows"), deform::Error);
  // The same with a short name reads.
  std::string fine = "v 0 0 0\nv 1 0 0\nv 0 1 0\no body\n";
  for (int i = 0; i < 200; ++i) fine += (i % 2 ? "usemtl a\n" : "usemtl b\n") + std::string("f 1 2 3\n");
  CHECK(parse(fine).submeshes.size() == 200);
}
