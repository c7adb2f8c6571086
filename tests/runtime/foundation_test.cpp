// Foundation: errors with context, atomic files, the thread pool.
#include <doctest/doctest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <vector>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/parallel.hpp"
namespace fs = std::filesystem;

TEST_CASE("Error formats file, position and element") {
  CHECK(std::string(deform::Error::at_line("a.obj", 12, "vertex 3", "bad index").what()) ==
        "a.obj: line 12: vertex 3: bad index");
  CHECK(std::string(deform::Error::at_byte("b.sk", 412, "bone 3", "overrun").what()) == "b.sk: byte 412: bone 3: overrun");
  CHECK(std::string(deform::Error::in_file("", "", "empty").what()) == "<memory>: empty");
  const auto e = deform::Error::at_byte("b.sk", 7, "", "x");
  CHECK(e.where() == deform::Error::Where::byte);
  CHECK(e.position() == 7);
}

TEST_CASE("write_file_atomic replaces whole files and never leaves a partial one") {
  const fs::path dir = fs::temp_directory_path() / "deform_atomic_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "out.txt").string();
  deform::write_file_atomic(path, std::string_view("first"));
  CHECK(deform::read_file_text(path) == "first");
  deform::write_file_atomic(path, std::string_view("second, longer"));
  CHECK(deform::read_file_text(path) == "second, longer");
  // A write into a folder that does not exist fails with the path named, and creates nothing.
  CHECK_THROWS_WITH_AS(deform::write_file_atomic((dir / "missing" / "x.txt").string(), std::string_view("x")),
                       doctest::Contains("missing"), deform::Error);
  // Only out.txt is there: no temporary left behind.
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);
  // Reading enforces the size cap and names the file.
  CHECK_THROWS_AS(deform::read_file_text(path, 3), deform::Error);
  CHECK_THROWS_WITH_AS(deform::read_file_text((dir / "nope").string()), doctest::Contains("nope"), deform::Error);
  fs::remove_all(dir);
}

TEST_CASE("ThreadPool covers every index exactly once") {
  for (unsigned threads : {1u, 2u, 3u, 8u}) {
    deform::ThreadPool pool(threads);
    CHECK(pool.size() == threads);
    for (std::size_t count : {0u, 1u, 7u, 1000u, 100003u}) {
      std::vector<std::atomic<int>> hits(count);
      for (int repeat = 0; repeat < 3; ++repeat)
        pool.parallel_for(count, 16, [&](std::size_t b, std::size_t e) {
          for (std::size_t i = b; i < e; ++i) hits[i].fetch_add(1);
        });
      for (std::size_t i = 0; i < count; ++i) REQUIRE(hits[i].load() == 3);
    }
  }
}
