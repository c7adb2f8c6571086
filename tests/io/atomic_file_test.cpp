// Whole-file reads and atomic writes: what the user named keeps its kind, mode and links; nothing partial is left.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include <sys/stat.h>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"

namespace fs = std::filesystem;

namespace {

fs::path fresh_folder(const char* name) {
  const fs::path dir = fs::temp_directory_path() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

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

TEST_CASE("write_file_atomic keeps an existing file's mode and writes through a symbolic link") {
  const fs::path dir = fresh_folder("deform_atomic_kinds");
  const std::string secret = (dir / "secret.txt").string();
  deform::write_file_atomic(secret, std::string_view("old"));
  fs::permissions(secret, fs::perms::owner_read | fs::perms::owner_write);
  deform::write_file_atomic(secret, std::string_view("new"));
  CHECK(deform::read_file_text(secret) == "new");
  CHECK(fs::status(secret).permissions() == (fs::perms::owner_read | fs::perms::owner_write));

  const fs::path link = dir / "link.txt";
  fs::create_symlink("secret.txt", link);
  deform::write_file_atomic(link.string(), std::string_view("through the link"));
  CHECK(fs::is_symlink(fs::symlink_status(link)));
  CHECK(deform::read_file_text(secret) == "through the link");
  CHECK(entries(dir) == 2);  // no temporary file left
  fs::remove_all(dir);
}

TEST_CASE("a FIFO is written directly, never replaced, and refused as an input") {
  const fs::path dir = fresh_folder("deform_atomic_fifo");
  const fs::path fifo = dir / "pipe";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo);
    received.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  });
  deform::write_file_atomic(fifo.string(), std::string_view("streamed"));
  reader.join();
  CHECK(received == "streamed");
  CHECK(fs::is_fifo(fs::status(fifo)));
  // Reading a FIFO would wait forever for a writer: it is refused at once, naming the file.
  CHECK_THROWS_WITH_AS(deform::read_file_text(fifo.string()), doctest::Contains("not a regular file"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::read_file_text(dir.string()), doctest::Contains("directory"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::write_file_atomic(dir.string(), std::string_view("x")), doctest::Contains("directory"),
                       deform::Error);
  fs::remove_all(dir);
}
