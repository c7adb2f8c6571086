// The CLI's lattice JSON: values, defaults, and errors that name the key.
#include <doctest/doctest.h>

#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
namespace {

std::string error_of(std::string_view json, std::size_t points = 10) {
  try {
    deform::parse_lattice_json(json, points, "L.json");
  } catch (const deform::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("lattice JSON: origin, size, degree, displacements and vertices") {
  const auto doc = deform::parse_lattice_json(
      R"({"origin": [1, 2, 3], "size": [2, 4, 8], "degree": [1, 2, 1],
          "displacements": [{"index": [1, 2, 0], "offset": [0.5, -1, 0]}, {"index": [0, 0, 1], "offset": [0, 0, 2]}],
          "vertices": [4, 0, 9]})",
      10);
  CHECK(doc.lattice.degree() == glm::ivec3(1, 2, 1));
  CHECK(doc.lattice.frame().origin == glm::vec3(1, 2, 3));
  CHECK(doc.lattice.control_points()[doc.lattice.index(1, 2, 0)] == glm::vec3(3.5f, 5.0f, 3.0f));
  CHECK(doc.lattice.control_points()[doc.lattice.index(0, 0, 1)] == glm::vec3(1.0f, 2.0f, 13.0f));
  CHECK(doc.lattice.control_points()[doc.lattice.index(0, 1, 0)] == glm::vec3(1.0f, 4.0f, 3.0f));
  CHECK(doc.displacement_count == 2);
  CHECK(doc.has_vertices);
  CHECK(doc.vertices == std::vector<std::uint32_t>{4, 0, 9});

  const auto plain = deform::parse_lattice_json(R"({"origin": [0, 0, 0], "size": [1, 1, 1]})", 0);
  CHECK(plain.lattice.degree() == glm::ivec3(3));
  CHECK_FALSE(plain.has_vertices);
  CHECK(plain.displacement_count == 0);
}

TEST_CASE("lattice JSON errors name the file and the key") {
  const std::string base = R"("origin": [0, 0, 0], "size": [1, 1, 1])";
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0,0], "offset": [0,0,0]}, {"index": [0,0,0],
        "offset": [1,0,0]}, {"index": [0, 4, 0], "offset": [0, 0, 0]}]})") ==
        "L.json: key 'displacements[1].index': control point listed twice");
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0,1], "offset": [0,0,0]}, {"index": [0,0,0],
        "offset": [1,0,0]}, {"index": [0, 4, 0], "offset": [0, 0, 0]}]})") ==
        "L.json: key 'displacements[2].index[1]': 4 is outside [0, 3]");
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0], "offset": [0,0,0]}]})") ==
        "L.json: key 'displacements[0].index': must have 3 elements, not 2");
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0,0]}]})") ==
        "L.json: key 'displacements[0].offset': is missing");
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0,0], "offset": [0,1e999,0]}]})") != "");
  CHECK(error_of("{" + base + R"(, "displacements": [{"index": [0,0,0], "offset": [0,1e39,0]}]})") ==
        "L.json: key 'displacements[0].offset[1]': is not a finite number");
  CHECK(error_of(R"({"origin": [0, 0, 0], "size": [1, 0, 1]})") == "L.json: key 'size[1]': must be positive");
  CHECK(error_of(R"({"origin": [0, 0, 0], "size": [1, -2, 1]})") == "L.json: key 'size[1]': must be positive");
  CHECK(error_of(R"({"origin": [0, 0], "size": [1, 1, 1]})") == "L.json: key 'origin': must have 3 elements, not 2");
  CHECK(error_of(R"({"size": [1, 1, 1]})") == "L.json: key 'origin': is missing");
  CHECK(error_of("{" + base + R"(, "degree": [3, 0, 3]})") == "L.json: key 'degree[1]': 0 is outside [1, 16]");
  CHECK(error_of("{" + base + R"(, "degree": [3, 1.5, 3]})") == "L.json: key 'degree[1]': must be an integer");
  CHECK(error_of("{" + base + R"(, "vertices": [1, 10]})") == "L.json: key 'vertices[1]': 10 is outside [0, 9]");
  CHECK(error_of("{" + base + R"(, "vertices": [1, -1]})") == "L.json: key 'vertices[1]': -1 is outside [0, 9]");
  CHECK(error_of("{" + base + R"(, "vertices": [3, 3]})") == "L.json: key 'vertices[1]': vertex 3 is listed twice");
  CHECK(error_of("{" + base + R"(, "verts": []})") ==
        "L.json: key 'verts': unknown key (expected origin, size, degree, displacements, vertices)");
  CHECK(error_of("[1, 2]") == "L.json: the lattice must be a JSON object");
  const std::string malformed = error_of(R"({"origin": [0, 0, 0], "size": [1, 1,)");
  CHECK(malformed.rfind("L.json: byte ", 0) == 0);
}
