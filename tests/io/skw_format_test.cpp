// .skw files: parsing, strongest-4 renormalisation, round trips, every malformed case with its line and vertex.
#include <doctest/doctest.h>

#include <filesystem>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace {

struct Failure {
  std::int64_t line = -1;
  std::string element;
  std::string message;
};

Failure failure_of(std::string_view text, std::size_t points = 3, std::size_t bones = 5) {
  try {
    deform::parse_skw(text, points, bones, "case.skw");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "case.skw");
    CHECK(e.where() == deform::Error::Where::line);
    return {e.position(), e.element(), e.message()};
  }
  FAIL("accepted malformed text: " << text);
  return {};
}

}  // namespace

TEST_CASE("parse_skw: comments, blank lines, CRLF, sorting and renormalising") {
  const std::string text =
      "# weights for a 3-vertex mesh\n"
      "\n"
      "skw 1   # header\r\n"
      "vertices 3\n"
      "0  3 0.75  4 0.25\n"
      "  # a comment between vertices\n"
      "1\t2 1.0\n"
      "2 0 1 1 2 2 3 3 4 4 0.5  # six pairs, the strongest four kept\n";
  const deform::SkinWeights w = deform::parse_skw(text, 3, 5);
  REQUIRE(w.size() == 3);
  CHECK(w.bones[0] == glm::u16vec4(3, 4, 0, 0));
  CHECK(w.weights[0] == glm::vec4(0.75f, 0.25f, 0.0f, 0.0f));
  CHECK(w.bones[1] == glm::u16vec4(2, 0, 0, 0));
  CHECK(w.weights[1] == glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  // Pairs (0,1) (1,2) (2,3) (3,4) (4,0.5): the four strongest are bones 3, 2, 1, 0, sum 10.
  CHECK(w.bones[2] == glm::u16vec4(3, 2, 1, 0));
  CHECK(w.weights[2].x == doctest::Approx(0.4f));
  CHECK(w.weights[2].y == doctest::Approx(0.3f));
  CHECK(w.weights[2].z == doctest::Approx(0.2f));
  CHECK(w.weights[2].w == doctest::Approx(0.1f));
}

TEST_CASE("parse_skw: unnormalised weights, zero weights, ties") {
  const deform::SkinWeights w = deform::parse_skw("skw 1\nvertices 3\n0 1 2 2 6\n1 4 0 3 5\n2 2 1 1 1\n", 3, 5);
  CHECK(w.bones[0] == glm::u16vec4(2, 1, 0, 0));
  CHECK(w.weights[0] == glm::vec4(0.75f, 0.25f, 0, 0));
  CHECK(w.bones[1] == glm::u16vec4(3, 0, 0, 0));  // a zero weight is no influence
  CHECK(w.weights[1] == glm::vec4(1, 0, 0, 0));
  CHECK(w.bones[2] == glm::u16vec4(1, 2, 0, 0));  // equal weights: lower bone first
  CHECK(deform::parse_skw("skw 1\nvertices 0\n", 0, 1).size() == 0);
}

TEST_CASE("format_skw / parse_skw round trip, and through files") {
  deform::SkinWeights w;
  w.bones = {glm::u16vec4(1, 0, 0, 0), glm::u16vec4(4, 2, 3, 1), glm::u16vec4(0, 3, 0, 0)};
  w.weights = {glm::vec4(1, 0, 0, 0), glm::vec4(0.4f, 0.3f, 0.2f, 0.1f), glm::vec4(2.0f / 3.0f, 1.0f / 3.0f, 0, 0)};
  const std::string text = deform::format_skw(w);
  CHECK(text.rfind("skw 1\nvertices 3\n0 1 1\n1 4 0.4 2 0.3 3 0.2 1 0.1\n", 0) == 0);
  const deform::SkinWeights back = deform::parse_skw(text, 3, 5);
  CHECK(back.bones == w.bones);
  for (std::size_t v = 0; v < 3; ++v)
    for (int k = 0; k < 4; ++k) CHECK(back.weights[v][k] == doctest::Approx(w.weights[v][k]).epsilon(1e-6));
  CHECK(deform::format_skw(back) == deform::format_skw(deform::parse_skw(deform::format_skw(back), 3, 5)));
  const std::string path = (std::filesystem::temp_directory_path() / "deform_skw_format_test.skw").string();
  deform::write_skw(path, w);
  CHECK(deform::read_skw(path, 3, 5).bones == w.bones);
  std::filesystem::remove(path);
  CHECK_THROWS_AS(deform::read_skw(path, 3, 5), deform::Error);
  deform::SkinWeights empty_vertex = w;
  empty_vertex.weights[1] = glm::vec4(0.0f);
  CHECK_THROWS_AS(deform::format_skw(empty_vertex), deform::Error);
}

TEST_CASE(".skw past four influences: kept on request as SkinWeights' extras, written on the same line") {
  // Vertex 1 lists six influences, vertex 2 five; a reader keeps 4 unless asked for more.
  const std::string text = "skw 1\nvertices 3\n0 1 1\n1 0 1 1 2 2 3 3 4 4 5 5 6\n2 6 1 5 1 4 1 3 1 2 1\n";
  const deform::SkinWeights four = deform::parse_skw(text, 3, 7);
  CHECK_FALSE(four.has_extra());
  CHECK(four.bones[1] == glm::u16vec4(5, 4, 3, 2));
  CHECK(four.weights[1].x == doctest::Approx(6.0f / 18.0f));
  const deform::SkinWeights six = deform::parse_skw(text, 3, 7, "case.skw", 6);
  REQUIRE(six.extra_points == std::vector<std::uint32_t>{1, 2});
  CHECK(six.extra_offsets == std::vector<std::uint32_t>{0, 2, 3});
  CHECK(six.extra_bones == std::vector<std::uint16_t>{1, 0, 6});  // strongest first; equal weights: lower bone first
  CHECK(six.bones[1] == glm::u16vec4(5, 4, 3, 2));
  CHECK(six.weights[1].x == doctest::Approx(6.0f / 21.0f));
  CHECK(six.extra_weights[0] == doctest::Approx(2.0f / 21.0f));
  CHECK(six.bones[2] == glm::u16vec4(2, 3, 4, 5));
  for (std::size_t p = 0; p < 3; ++p) {
    float sum = six.weights[p].x + six.weights[p].y + six.weights[p].z + six.weights[p].w;
    for (std::size_t j = 0; j < six.extra_points.size(); ++j)
      if (six.extra_points[j] == p)
        for (std::uint32_t e = six.extra_offsets[j]; e < six.extra_offsets[j + 1]; ++e) sum += six.extra_weights[e];
    CHECK(sum == doctest::Approx(1.0f));
  }
  CHECK(deform::parse_skw(text, 3, 7, "case.skw", 5).extra_bones == std::vector<std::uint16_t>{1, 6});
  // Written back with every influence, read back the same.
  const std::string written = deform::format_skw(six);
  CHECK(written.find("\n1 5 ") != std::string::npos);
  const deform::SkinWeights again = deform::parse_skw(written, 3, 7, "again.skw", deform::max_requested_influences);
  CHECK(again.bones == six.bones);
  CHECK(again.extra_points == six.extra_points);
  CHECK(again.extra_offsets == six.extra_offsets);
  CHECK(again.extra_bones == six.extra_bones);
  for (std::size_t e = 0; e < six.extra_weights.size(); ++e)
    CHECK(again.extra_weights[e] == doctest::Approx(six.extra_weights[e]).epsilon(1e-6));
  CHECK(deform::format_skw(again) == written);
  // Requests out of range, and extras that do not add up, are errors.
  CHECK_THROWS_AS(deform::parse_skw(text, 3, 7, "case.skw", 0), deform::Error);
  CHECK_THROWS_AS(deform::parse_skw(text, 3, 7, "case.skw", deform::max_requested_influences + 1), deform::Error);
  deform::SkinWeights broken = six;
  broken.extra_offsets.back() = 9;
  CHECK_THROWS_AS(deform::format_skw(broken), deform::Error);
}

TEST_CASE("malformed .skw: each an error with the line and the vertex") {
  const std::string head = "skw 1\nvertices 3\n";
  Failure f = failure_of("");
  CHECK(f.message.find("header") != std::string::npos);
  f = failure_of("# only a comment\n\nvertices 3\n");
  CHECK(f.line == 3);
  CHECK(failure_of("skw 2\nvertices 3\n").line == 1);
  CHECK(failure_of("skw\n").line == 1);
  CHECK(failure_of("skw 1 extra\n").line == 1);
  CHECK(failure_of("skw 1\n").message.find("vertices") != std::string::npos);
  CHECK(failure_of("skw 1\nvertex 3\n").line == 2);
  CHECK(failure_of("skw 1\nvertices -3\n").line == 2);
  CHECK(failure_of("skw 1\nvertices 3x\n").line == 2);
  // A huge count is refused before anything is allocated from it.
  f = failure_of("skw 1\nvertices 4000000000000\n0 1 1\n");
  CHECK(f.line == 2);
  CHECK(f.message.find("does not match") != std::string::npos);
  CHECK(failure_of("skw 1\nvertices 99999999999999999999999\n").line == 2);
  CHECK(failure_of("skw 1\nvertices 2\n").line == 2);

  // Vertices: missing at the end, missing in the middle, repeated, out of order, one too many.
  f = failure_of(head + "0 1 1\n1 1 1\n");
  CHECK(f.element == "vertex 2");
  f = failure_of(head + "0 1 1\n2 1 1\n");
  CHECK(f.line == 4);
  CHECK(f.element == "vertex 1");
  f = failure_of(head + "0 1 1\n0 1 1\n");
  CHECK(f.line == 4);
  CHECK(f.element == "vertex 0");
  f = failure_of(head + "0 1 1\n1 1 1\n2 1 1\n3 1 1\n");
  CHECK(f.line == 6);
  CHECK(f.element == "vertex 3");
  CHECK(failure_of(head + "x 1 1\n").line == 3);
  CHECK(failure_of(head + "-1 1 1\n").line == 3);

  // Pairs.
  const auto second = [&](const std::string& line) { return failure_of(head + "0 1 1\n" + line + "\n2 1 1\n"); };
  for (const char* bad :
       {"1", "1 2", "1 2 0.5 3", "1 5 1", "1 99999999999 1", "1 -1 1", "1 a 1", "1 2 x", "1 2 -0.5", "1 2 nan",
        "1 2 inf", "1 2 1e39", "1 2 0", "1 2 0 3 0", "1 2 0.5 2 0.5", "1 2 0.5,", "1 2.0 1"}) {
    f = second(bad);
    CHECK_MESSAGE(f.line == 4, bad);
    CHECK_MESSAGE(f.element == "vertex 1", bad);
  }
  CHECK(second("1 2 0.5 2 0.5").message.find("twice") != std::string::npos);
  CHECK(second("1 2 0 3 0").message.find("no positive weight") != std::string::npos);
  CHECK(second("1 5 1").message.find("out of range") != std::string::npos);
}

TEST_CASE("skw: a line of 65,535 pairs reads in linear time, and a repeat among them is still found") {
  std::string line = "0";
  for (int bone = 0; bone < 65535; ++bone) line += " " + std::to_string(bone) + " 1";
  const deform::SkinWeights weights = deform::parse_skw("skw 1\nvertices 1\n" + line + "\n", 1, 65535, "wide.skw");
  CHECK(weights.weights[0].x == doctest::Approx(0.25f));
  CHECK_THROWS_WITH_AS(deform::parse_skw("skw 1\nvertices 1\n" + line + " 40000 2\n", 1, 65535, "wide.skw"),
                       doctest::Contains("bone 40000 listed twice"), deform::Error);
}
