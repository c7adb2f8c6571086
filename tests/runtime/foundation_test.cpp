// Foundation: errors with context, the thread pool.
#include <doctest/doctest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/parallel.hpp"
namespace fs = std::filesystem;

TEST_CASE("Error formats file, position and element") {
  CHECK(std::string(deform::Error::at_line("a.obj", 12, "vertex 3", "bad index").what()) ==
        "a.obj: line 12: vertex 3: bad index");
  CHECK(std::string(deform::Error::at_byte("b.sk", 412, "bone 3", "overrun").what()) ==
        "b.sk: byte 412: bone 3: overrun");
  CHECK(std::string(deform::Error::in_file("", "", "empty").what()) == "<memory>: empty");
  const auto e = deform::Error::at_byte("b.sk", 7, "", "x");
  CHECK(e.where() == deform::Error::Where::byte);
  CHECK(e.position() == 7);
}

TEST_CASE("Error keeps what() one short line whatever the input quotes") {
  const std::string huge(10 * 1024 * 1024, 'k');
  const deform::Error e = deform::Error::at_line("rig.json", 3, "key '" + huge + "'", "unknown key");
  CHECK(std::string(e.what()).size() < 300);
  CHECK(std::string(e.what()).find("(10485766 bytes)") != std::string::npos);
  const deform::Error injected = deform::Error::in_file("a.obj", "object 'x\nv 1 2 3'", "bad");
  CHECK(std::string(injected.what()) == "a.obj: object 'x\\x0av 1 2 3': bad");
  // A cut never splits a UTF-8 character.
  std::string accents;
  for (int i = 0; i < 150; ++i) accents += "\xc3\xa9";
  const std::string cut = deform::Error::in_file("f", accents, "m").element();
  CHECK(cut.find("...") == 200);
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
