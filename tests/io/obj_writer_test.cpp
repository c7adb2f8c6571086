// OBJ/MTL writer: exact text for a small mesh, and read(write(mesh)) == mesh on fixtures and random meshes.
#include <doctest/doctest.h>

#include <filesystem>
#include <random>
#include <stdexcept>

#include <unistd.h>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace {

using deform::Mesh;

// What a round trip must keep: points, faces (as OBJ `v` indices per corner), render vertices, UVs, normals, submeshes
// (their `o`/`g` names are the ObjNames' and compared by the callers).
void check_same(const Mesh& a, const Mesh& b) {
  CHECK(a.positions == b.positions);
  CHECK(a.vertex_point == b.vertex_point);
  CHECK(a.face_sizes == b.face_sizes);
  CHECK(a.face_corners == b.face_corners);
  CHECK(a.triangles == b.triangles);
  CHECK(a.vertex_uvs == b.vertex_uvs);
  CHECK(a.vertex_normals == b.vertex_normals);
  REQUIRE(a.submeshes.size() == b.submeshes.size());
  for (std::size_t s = 0; s < a.submeshes.size(); ++s) {
    CHECK(a.submeshes[s].first_triangle == b.submeshes[s].first_triangle);
    CHECK(a.submeshes[s].triangle_count == b.submeshes[s].triangle_count);
    CHECK(a.submeshes[s].material == b.submeshes[s].material);
  }
}

}  // namespace

TEST_CASE("obj writer: exact text of a quad and a triangle") {
  deform::ObjNames names;
  const Mesh mesh = deform::parse_obj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.1 0.2 0.3\nvt 0 0\nvt 1 0.5\n"
      "g top\nf 1/1 2/2 3/1 4/2\nf 1/1 3/1 5/2\n",
      "t.obj", ".", nullptr, {}, &names);
  // Positions replaced by the caller's (a deformation): point 4 moved; points without faces are written too.
  std::vector<glm::vec3> moved = mesh.positions;
  moved[1] = {2.5f, -1.0f, 1e-7f};
  const std::string text =
      deform::format_obj(mesh, moved, {}, {.mtllib = "", .submesh_names = names.submeshes, .write_normals = false});
  CHECK(text ==
        "v 0 0 0\nv 2.5 -1 1e-07\nv 1 1 0\nv 0 1 0\nv 0.1 0.2 0.3\n"
        "vt 0 0\nvt 1 0.5\nvt 0 0\nvt 1 0.5\nvt 1 0.5\n"
        "g top\nf 1/1 2/2 3/3 4/4\nf 1/1 3/3 5/5\n");
  const std::string plain = deform::format_obj(
      mesh, moved, {}, {.mtllib = "", .submesh_names = names.submeshes, .write_normals = false, .write_uvs = false});
  CHECK(plain.ends_with("\ng top\nf 1 2 3 4\nf 1 3 5\n"));
  // Without the names the mesh alone is written: its geometry holds no `o` or `g`.
  CHECK(deform::format_obj(mesh, moved, {}, {.write_normals = false, .write_uvs = false})
            .ends_with("v 0.1 0.2 0.3\nf 1 2 3 4\nf 1 3 5\n"));
  const std::string normals = deform::format_obj(mesh, moved, {}, {.mtllib = "", .write_uvs = false});
  CHECK(normals.find("vn 0 0 1\n") != std::string::npos);
  CHECK(normals.ends_with("f 1//1 2//2 3//3 4//4\nf 1//1 3//3 5//5\n"));
}

TEST_CASE("obj writer: round trip of the cube fixture with materials and an MTL") {
  deform::ObjNames names;
  const Mesh cube = deform::read_obj(DEFORM_TEST_DATA "/mesh/cube.obj", nullptr, {}, &names);
  REQUIRE(names.submeshes.size() == cube.submeshes.size());
  const auto folder = std::filesystem::temp_directory_path() / ("deform_mesh_writer_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  deform::write_file_atomic((folder / "out.mtl").string(), deform::format_mtl(cube.materials));
  deform::write_obj((folder / "out.obj").string(), cube, cube.positions, {},
                    {.mtllib = "out.mtl", .submesh_names = names.submeshes});
  deform::Warnings warnings;
  // The MTL names the fixture's texture where it lies, outside the new folder: read because that folder is allowed.
  deform::ReferencePolicy policy;
  policy.allow_outside = {DEFORM_TEST_DATA "/mesh"};
  deform::ObjNames back_names;
  const Mesh back = deform::read_obj((folder / "out.obj").string(), &warnings, policy, &back_names);
  CHECK(warnings.messages.empty());
  check_same(cube, back);
  CHECK(back_names.submeshes == names.submeshes);
  REQUIRE(back.materials.size() == cube.materials.size());
  for (std::size_t m = 0; m < cube.materials.size(); ++m) {
    CHECK(back.materials[m].name == cube.materials[m].name);
    CHECK(back.materials[m].ambient == cube.materials[m].ambient);
    CHECK(back.materials[m].diffuse == cube.materials[m].diffuse);
    CHECK(back.materials[m].specular == cube.materials[m].specular);
    CHECK(back.materials[m].opacity == cube.materials[m].opacity);
    CHECK(back.materials[m].shininess == cube.materials[m].shininess);
    CHECK(back.materials[m].illum == cube.materials[m].illum);
    CHECK(back.materials[m].diffuse_map == cube.materials[m].diffuse_map);  // absolute after the first read
  }
  std::filesystem::remove_all(folder);
}

TEST_CASE("obj writer: an OBJ written elsewhere names the input's MTL files relative to itself") {
  const Mesh cube = deform::read_obj(DEFORM_TEST_DATA "/mesh/cube.obj");
  deform::ObjNames cube_names;
  deform::read_obj(DEFORM_TEST_DATA "/mesh/cube.obj", nullptr, {}, &cube_names);
  REQUIRE(cube_names.material_libraries.size() == 1);
  CHECK(std::filesystem::equivalent(cube_names.material_libraries[0], DEFORM_TEST_DATA "/mesh/cube.mtl"));
  deform::ObjNames none{{{"stale", "names"}}, {"stale.mtl"}};  // replaced, not appended to
  deform::parse_obj("v 0 0 0\n", "t.obj", ".", nullptr, {}, &none);
  CHECK(none.material_libraries.empty());
  CHECK(none.submeshes.empty());

  // Next to the input, two folders below it, and in another tree: each reads back with the same materials (the
  // other tree's OBJ names an MTL outside its own folder: read only where the caller allows that folder).
  const auto root = std::filesystem::temp_directory_path() / ("deform_mesh_mtllib_" + std::to_string(::getpid()));
  const auto data = root / "data", deep = root / "out" / "deeper";
  std::filesystem::create_directories(data);
  std::filesystem::create_directories(deep);
  std::filesystem::copy_file(DEFORM_TEST_DATA "/mesh/cube.mtl", data / "cube.mtl");
  std::filesystem::copy(DEFORM_TEST_DATA "/mesh/textures", data / "textures");  // cube.mtl's map_Kd
  deform::write_file_atomic((data / "cube.obj").string(),
                            deform::format_obj(cube, cube.positions, {}, {.mtllib = "cube.mtl"}));
  deform::ObjNames input_names;
  const Mesh input = deform::read_obj((data / "cube.obj").string(), nullptr, {}, &input_names);
  CHECK(deform::material_libraries_for(input_names, (data / "same.obj").string()) == "cube.mtl");
  CHECK(deform::material_libraries_for(input_names, (deep / "o.obj").string()) == "../../data/cube.mtl");
  CHECK(deform::material_libraries_for(deform::ObjNames{}, (deep / "o.obj").string()).empty());
  for (const auto& out : {data / "same.obj", deep / "o.obj"}) {
    deform::write_obj(out.string(), input, input.positions, {},
                      {.mtllib = deform::material_libraries_for(input_names, out.string())});
    deform::Warnings warnings;
    if (out == deep / "o.obj") CHECK_THROWS_AS(deform::read_obj(out.string(), &warnings), deform::Error);
    deform::ReferencePolicy policy;
    policy.allow_outside = {data.string()};
    const Mesh back = deform::read_obj(out.string(), &warnings, policy);
    CHECK(warnings.messages.empty());
    REQUIRE(back.materials.size() == cube.materials.size());
    for (std::size_t m = 0; m < cube.materials.size(); ++m) CHECK(back.materials[m].name == cube.materials[m].name);
    CHECK(back.submeshes[0].material == cube.submeshes[0].material);
  }
  std::filesystem::remove_all(root);
}

TEST_CASE("obj writer: seeded random meshes survive read(format(mesh)) exactly") {
  std::mt19937 random(12345);
  std::uniform_real_distribution<float> coordinate(-1e3f, 1e3f);
  for (int round = 0; round < 200; ++round) {
    const int points = 3 + int(random() % 30), uvs = int(random() % 5), normals = int(random() % 5);
    std::string text;
    for (int i = 0; i < points; ++i)
      text += "v " + std::to_string(coordinate(random)) + " " + std::to_string(coordinate(random)) + " " +
              std::to_string(coordinate(random) * 1e-6f) + "\n";
    for (int i = 0; i < uvs; ++i) text += "vt 0." + std::to_string(random() % 1000) + " " + std::to_string(i) + "\n";
    for (int i = 0; i < normals; ++i) text += "vn 0 " + std::to_string(i) + " 1\n";
    const int faces = 1 + int(random() % 20);
    for (int f = 0; f < faces; ++f) {
      if (random() % 4 == 0) text += "o part" + std::to_string(random() % 3) + "\n";
      text += "f";
      const int corners = 3 + int(random() % 4);
      const bool with_uv = uvs > 0 && random() % 2, with_normal = normals > 0 && random() % 2;
      for (int c = 0; c < corners; ++c) {
        text += " " + std::to_string(1 + random() % unsigned(points));
        if (with_uv) text += "/" + std::to_string(1 + random() % unsigned(uvs));
        if (with_normal) text += std::string(with_uv ? "/" : "//") + std::to_string(1 + random() % unsigned(normals));
      }
      text += "\n";
    }
    CAPTURE(text);
    deform::ObjNames names, back_names;
    const Mesh mesh = deform::parse_obj(text, "t.obj", ".", nullptr, {}, &names);
    REQUIRE(names.submeshes.size() == mesh.submeshes.size());
    const Mesh back =
        deform::parse_obj(deform::format_obj(mesh, mesh.positions, {}, {.submesh_names = names.submeshes}), "back.obj",
                          ".", nullptr, {}, &back_names);
    check_same(mesh, back);
    CHECK(back_names.submeshes == names.submeshes);
  }
}

TEST_CASE("obj writer: wrong span sizes are rejected") {
  const Mesh mesh = deform::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::vector<glm::vec3> two(2), four(4);
  CHECK_THROWS_AS(deform::format_obj(mesh, two), deform::Error);
  CHECK_THROWS_AS(deform::format_obj(mesh, mesh.positions, four), deform::Error);
  CHECK_THROWS_AS(deform::write_obj("/nonexistent-folder/x.obj", mesh, mesh.positions), deform::Error);
  // Names for a mesh of another submesh count: refused, never read past the end.
  const std::vector<deform::ObjSubmeshNames> two_names(2);
  CHECK_THROWS_WITH_AS(deform::format_obj(mesh, mesh.positions, {}, {.submesh_names = two_names}),
                       doctest::Contains("2 names for 1 submeshes"), deform::Error);
}

TEST_CASE("obj writer: a non-finite position or normal is refused, naming it, and nothing is written") {
  const Mesh mesh = deform::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  std::vector<glm::vec3> positions = mesh.positions;
  positions[1].y = std::nanf("");
  CHECK_THROWS_WITH_AS(deform::format_obj(mesh, positions), doctest::Contains("vertex 1"), deform::Error);
  positions[1].y = INFINITY;
  const std::string path = (std::filesystem::temp_directory_path() / "deform_nan_test.obj").string();
  std::filesystem::remove(path);
  CHECK_THROWS_AS(deform::write_obj(path, mesh, positions), deform::Error);
  CHECK_FALSE(std::filesystem::exists(path));
  std::vector<glm::vec3> normals(mesh.vertex_count(), glm::vec3(0.0f, 0.0f, 1.0f));
  normals[2].x = std::nanf("");
  CHECK_THROWS_WITH_AS(deform::format_obj(mesh, mesh.positions, normals), doctest::Contains("render vertex 2"),
                       deform::Error);
}

TEST_CASE("names written into OBJ and MTL lines cannot inject statements") {
  deform::Mesh mesh = deform::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj");
  const deform::ObjSubmeshNames names[] = {{"x\nv 9 9 9\nf 1 2 3", "tail\\"}};
  mesh.materials.push_back(deform::Material{});
  mesh.materials[0].name = "red # not a comment\r";
  mesh.materials[0].diffuse_map = "skin.png\nmap_Kd /etc/passwd";
  mesh.submeshes[0].material = 0;
  deform::ObjWriteOptions options;
  options.mtllib = "a.mtl\nmtllib b.mtl";
  options.submesh_names = names;
  deform::ObjNames again_names;
  const deform::Mesh again = deform::parse_obj(deform::format_obj(mesh, mesh.positions, {}, options), "again.obj", ".",
                                               nullptr, {}, &again_names);
  CHECK(again.point_count() == 3);
  CHECK(again.triangle_count() == 1);
  REQUIRE(again_names.submeshes.size() == 1);
  CHECK(again_names.submeshes[0].object == "x_v 9 9 9_f 1 2 3");
  CHECK(again_names.submeshes[0].group == "tail_");
  const std::vector<deform::Material> materials = deform::parse_mtl(deform::format_mtl(mesh.materials), "m.mtl", "/");
  REQUIRE(materials.size() == 1);
  CHECK(materials[0].name == "red _ not a comment_");
}
