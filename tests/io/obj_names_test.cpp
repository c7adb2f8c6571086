// OBJ names, property-tested: whatever bytes an object, group or material is named (from an import, a glTF mesh named
// "a\\ "), the OBJ and MTL the writers make read back to the same faces, with each face in the group and object
// obj_safe_name gives and the same material. Names may change (made safe), but alike on both sides and distinctly.
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "deform/io/obj.hpp"
#include "deform/runtime/mesh.hpp"

namespace fs = std::filesystem;

namespace {

// Bytes that break lines, comments, continuations and trimming, mixed with plain ones and any byte at all.
std::string random_name(std::mt19937& random) {
  static const char tricky[] = {' ',  '\\',   '#', '\n', '\r', '\t', '\v',   '\f',
                                '\0', '\x7f', 'a', 'b',  '_',  '%',  '\xff', '\xc3'};
  std::string name(random() % 9, ' ');
  for (char& c : name) c = random() % 4 == 0 ? static_cast<char>(random() % 256) : tricky[random() % sizeof tricky];
  return name;
}

// Six triangles, each its own submesh (g s0 ... g s5), over four points.
deform::Mesh six_submeshes() {
  std::string text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  const char* faces[] = {"1 2 3", "1 3 4", "2 3 4", "1 2 4", "3 2 1", "4 3 1"};
  for (int s = 0; s < 6; ++s) text += "g s" + std::to_string(s) + "\nf " + faces[s] + "\n";
  return deform::parse_obj(text);
}

}  // namespace

TEST_CASE("any byte string as an object, group or material name reads back to the same faces, groups and materials") {
  const fs::path dir = fs::temp_directory_path() / "deform_obj_names";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const deform::Mesh base = six_submeshes();
  REQUIRE(base.submeshes.size() == 6);
  int renamed = 0;
  for (std::uint32_t seed = 0; seed < 2000; ++seed) {
    CAPTURE(seed);
    std::mt19937 random(seed);
    deform::Mesh mesh = base;
    mesh.materials.resize(1 + random() % 4);
    for (deform::Material& material : mesh.materials) material.name = random_name(random);
    std::vector<deform::ObjSubmeshNames> submesh_names(mesh.submeshes.size());
    for (std::size_t s = 0; s < mesh.submeshes.size(); ++s) {
      // Names repeat now and then, as real files' do: a repeated name must read back the same.
      submesh_names[s].object = random() % 3 == 0 ? std::string("same") : random_name(random);
      submesh_names[s].group = random_name(random);
      mesh.submeshes[s].material = static_cast<std::int32_t>(random() % (mesh.materials.size() + 1)) - 1;  // none
    }
    deform::ObjWriteOptions options;
    options.mtllib = "m.mtl";
    options.submesh_names = submesh_names;
    const std::string obj = deform::format_obj(mesh, mesh.positions, {}, options);
    std::ofstream(dir / "m.mtl", std::ios::binary) << deform::format_mtl(mesh.materials);
    deform::Warnings warnings;  // "material 'default' is not defined" for faces without one
    deform::ObjNames read_names;
    const deform::Mesh read = deform::parse_obj(obj, "names.obj", dir.string(), &warnings, {}, &read_names);
    REQUIRE(read_names.submeshes.size() == read.submeshes.size());

    // The faces, point for point.
    REQUIRE(read.triangle_count() == mesh.triangle_count());
    for (std::size_t c = 0; c < mesh.triangles.size(); ++c)
      REQUIRE(read.vertex_point[read.triangles[c]] == mesh.vertex_point[mesh.triangles[c]]);
    // The materials: their safe names, distinct, in order.
    const std::vector<std::string> names = deform::obj_material_names(mesh.materials);
    REQUIRE(read.materials.size() == mesh.materials.size());
    REQUIRE(std::set<std::string>(names.begin(), names.end()).size() == names.size());
    for (std::size_t m = 0; m < names.size(); ++m) {
      CHECK(read.materials[m].name == names[m]);
      renamed += names[m] != mesh.materials[m].name;
    }
    // Each triangle: the same material, its object and group as obj_safe_name writes them.
    const auto submesh_of = [](const deform::Mesh& m, std::size_t triangle) -> std::size_t {
      for (std::size_t s = 0; s < m.submeshes.size(); ++s)
        if (triangle >= m.submeshes[s].first_triangle &&
            triangle < m.submeshes[s].first_triangle + m.submeshes[s].triangle_count)
          return s;
      FAIL("triangle " << triangle << " is in no submesh");
      return 0;
    };
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      CAPTURE(t);
      const std::size_t written = submesh_of(mesh, t), back = submesh_of(read, t);
      CHECK(read.submeshes[back].material == mesh.submeshes[written].material);
      CHECK(read_names.submeshes[back].object == deform::obj_safe_name(submesh_names[written].object));
      CHECK(read_names.submeshes[back].group == deform::obj_safe_name(submesh_names[written].group));
    }
  }
  CHECK(renamed > 700);  // the names were hostile enough to need it
  // A name the reader can read is written unchanged, and the safe names are what the reader reads.
  CHECK(deform::obj_safe_name("Body mesh.001 (ß)") == "Body mesh.001 (ß)");
  CHECK(deform::obj_safe_name("a\\ ") == "a\\_");
  CHECK(deform::obj_safe_name(" a\\") == "_a_");
  CHECK(deform::obj_safe_name("x\ny#z") == "x_y_z");
  fs::remove_all(dir);
}

TEST_CASE("a line whose backslash is followed by blanks continues, without the backslash") {
  // Other writers leave blanks after a continuation's backslash; the joined statement must not keep the backslash.
  deform::ObjNames names;
  const deform::Mesh mesh =
      deform::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\ng left \\  \n right\nf 1 2 3\n", "t.obj", ".", nullptr, {}, &names);
  REQUIRE(mesh.submeshes.size() == 1);
  REQUIRE(names.submeshes.size() == 1);
  CHECK(names.submeshes[0].group == "left   right");
}
