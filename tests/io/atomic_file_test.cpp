// Whole-file reads and atomic writes: what the user named keeps its kind, mode and links; nothing partial is left.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#ifndef _WIN32
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

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

// Paths are UTF-8 on every system: on Windows they become wide paths (a name outside the ANSI code page survives).
TEST_CASE("names in UTF-8 are written, replaced, staged together and read back under the same names") {
  const fs::path dir = fresh_folder("deform_atomic_utf8");
  const std::string name = "Ωmega ünïcode 日本.obj";
  const std::string other = "ñame ✓.mtl";
  const std::u8string folder_u8 = dir.u8string();
  const std::string folder(folder_u8.begin(), folder_u8.end());
  deform::write_file_atomic(folder + "/" + name, std::string_view("first"));
  deform::write_file_atomic(folder + "/" + name, std::string_view("second"));
  {
    deform::FileTransaction files;
    files.stage(folder + "/" + name, std::string_view("third"));
    files.stage(folder + "/" + other, std::string_view("mtl"));
    files.commit();
  }
  CHECK(deform::read_file_text(folder + "/" + name) == "third");
  CHECK(deform::read_file_text(folder + "/" + other) == "mtl");
  CHECK(fs::exists(dir / fs::path(std::u8string(name.begin(), name.end()))));
  CHECK(fs::exists(dir / fs::path(std::u8string(other.begin(), other.end()))));
  CHECK(entries(dir) == 2);  // no temporary or backup left, and no file under a mangled name
  fs::remove_all(dir);
}

TEST_CASE("reading or replacing a folder is refused, naming it") {
  const fs::path dir = fresh_folder("deform_atomic_folder");
  CHECK_THROWS_WITH_AS(deform::read_file_text(dir.string()), doctest::Contains("directory"), deform::Error);
  CHECK_THROWS_WITH_AS(deform::write_file_atomic(dir.string(), std::string_view("x")), doctest::Contains("directory"),
                       deform::Error);
  CHECK(entries(dir) == 0);
  fs::remove_all(dir);
}

#ifndef _WIN32  // POSIX modes, symbolic links and FIFOs
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
  // A reader first (a non-blocking open for reading needs no writer), then the write, which fits the pipe's buffer.
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  REQUIRE(reader >= 0);
  deform::write_file_atomic(fifo.string(), std::string_view("streamed"));
  char received[32] = {};
  CHECK(::read(reader, received, sizeof received) == 8);
  ::close(reader);
  CHECK(std::string(received) == "streamed");
  CHECK(fs::is_fifo(fs::status(fifo)));
  // Without a reader, writing would block this process until one came: refused at once, as the environment's.
  try {
    deform::write_file_atomic(fifo.string(), std::string_view("lost"));
    FAIL("a FIFO without a reader was accepted");
  } catch (const deform::Error& e) {
    CHECK(e.kind() == deform::Error::Kind::environment);
    CHECK(std::string(e.what()).find("no process reads") != std::string::npos);
  }
  CHECK(fs::is_fifo(fs::status(fifo)));
  // Reading a FIFO would wait forever for a writer: it is refused at once, naming the file.
  CHECK_THROWS_WITH_AS(deform::read_file_text(fifo.string()), doctest::Contains("not a regular file"), deform::Error);
  fs::remove_all(dir);
}

TEST_CASE("a dangling symbolic link is followed: the file it names is created, the link stays") {
  const fs::path dir = fresh_folder("deform_atomic_dangling");
  fs::create_directories(dir / "real");
  fs::create_symlink("real/made.txt", dir / "link.txt");
  fs::create_symlink("link.txt", dir / "link2.txt");  // a chain of two, relative targets
  deform::write_file_atomic((dir / "link2.txt").string(), std::string_view("made"));
  CHECK(fs::is_symlink(fs::symlink_status(dir / "link.txt")));
  CHECK(fs::is_symlink(fs::symlink_status(dir / "link2.txt")));
  CHECK(deform::read_file_text((dir / "real" / "made.txt").string()) == "made");
  fs::create_symlink("loop_b", dir / "loop_a");
  fs::create_symlink("loop_a", dir / "loop_b");
  CHECK_THROWS_WITH_AS(deform::write_file_atomic((dir / "loop_a").string(), std::string_view("x")),
                       doctest::Contains("symbolic links"), deform::Error);
  CHECK(entries(dir) == 5);
  CHECK(entries(dir / "real") == 1);
  fs::remove_all(dir);
}
#endif

TEST_CASE("write errors say whose they are: a path that names no output is input, a full disk the environment's") {
  const fs::path dir = fresh_folder("deform_atomic_kinds_of_error");
  const auto kind_of = [](const std::string& path) {
    try {
      deform::write_file_atomic(path, std::string_view("x"));
    } catch (const deform::Error& e) {
      return e.kind();
    }
    return deform::Error::Kind::argument;  // no error: no kind this test expects
  };
  CHECK(kind_of((dir / "missing" / "x.txt").string()) == deform::Error::Kind::input);
  CHECK(kind_of(dir.string()) == deform::Error::Kind::input);
#ifndef _WIN32
  if (fs::exists("/dev/full")) CHECK(kind_of("/dev/full") == deform::Error::Kind::environment);  // ENOSPC
#endif
  deform::inject_file_failure_for_testing(0);
  CHECK(kind_of((dir / "y.txt").string()) == deform::Error::Kind::environment);  // EIO
  deform::inject_file_failure_for_testing(-1);
  CHECK(entries(dir) == 0);
  fs::remove_all(dir);
}

namespace {

// The bytes of every entry of `dir` by name: the folder's whole state, temporaries and backups included.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir))
    files[entry.path().filename().string()] = deform::read_file_text(entry.path().string());
  return files;
}

// A transaction over `count` files in a fresh folder: the even-numbered ones exist before (0600, "old N"), the others
// do not; the last two are staged as files already written elsewhere (as an export's staging folder has them). A
// failure is injected at each step in turn: each failing run must leave the folder exactly as it was (the same names,
// the same bytes, the same modes), and the run past the last step must put every new file in place.
void fail_at_every_step(std::size_t count) {
  const fs::path dir = fresh_folder("deform_atomic_transaction");
  const fs::path elsewhere = fresh_folder("deform_atomic_transaction_staged");
  for (std::size_t i = 0; i < count; i += 2) {
    const fs::path file = dir / ("f" + std::to_string(i));
    deform::write_file_atomic(file.string(), "old " + std::to_string(i));
    fs::permissions(file, fs::perms::owner_read | fs::perms::owner_write);
  }
  const auto before = snapshot(dir);
  long failures = 0;
  for (long step = 0;; ++step) {
    CAPTURE(step);
    deform::inject_file_failure_for_testing(step);
    bool failed = false;
    try {
      deform::FileTransaction files;
      for (std::size_t i = 0; i < count; ++i) {
        const std::string target = (dir / ("f" + std::to_string(i))).string();
        const std::string text = "new " + std::to_string(i) + std::string(i * 1000, 'x');
        if (i + 2 >= count) {
          const std::string written = (elsewhere / ("w" + std::to_string(i))).string();
          std::ofstream(written) << text;
          files.stage_written(target, written);
        } else {
          files.stage(target, text);
        }
      }
      files.commit();
    } catch (const deform::Error& e) {
      failed = true;
      CHECK(e.kind() == deform::Error::Kind::environment);
    }
    const long steps = deform::file_steps_for_testing();
    deform::inject_file_failure_for_testing(-1);
    if (!failed) {
      CHECK(steps <= step);  // the transaction ran out of steps before the one to fail
      break;
    }
    ++failures;
    CHECK(snapshot(dir) == before);
#ifndef _WIN32  // Windows files have no POSIX mode to keep
    const fs::perms private_mode = fs::perms::owner_read | fs::perms::owner_write;
    for (std::size_t i = 0; i < count; i += 2)
      CHECK(fs::status(dir / ("f" + std::to_string(i))).permissions() == private_mode);
#endif
    CHECK(entries(elsewhere) == 0);  // files staged from elsewhere are consumed, never left behind
    REQUIRE(step < 100);
  }
  // Each file is staged and renamed in; each existing one is also backed up.
  CHECK(failures == long(count + count + (count + 1) / 2));
  const auto after = snapshot(dir);
  REQUIRE(after.size() == count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::string name = "f" + std::to_string(i);
    CHECK(after.at(name) == "new " + std::to_string(i) + std::string(i * 1000, 'x'));
#ifndef _WIN32
    if (i % 2 == 0) CHECK(fs::status(dir / name).permissions() == (fs::perms::owner_read | fs::perms::owner_write));
#endif
  }
  fs::remove_all(dir);
  fs::remove_all(elsewhere);
}

}  // namespace

TEST_CASE("a FileTransaction failing at any step leaves the previous files byte for byte, and no temporary") {
  SUBCASE("two files") { fail_at_every_step(2); }
  SUBCASE("five files") { fail_at_every_step(5); }
}

TEST_CASE("a FileTransaction not committed changes nothing; a file named twice is refused") {
  const fs::path dir = fresh_folder("deform_atomic_uncommitted");
  deform::write_file_atomic((dir / "a").string(), std::string_view("old"));
  {
    deform::FileTransaction files;
    files.stage((dir / "a").string(), std::string_view("new"));
    files.stage((dir / "b").string(), std::string_view("new"));
    CHECK(entries(dir) == 3);  // the two temporaries beside a
    CHECK_THROWS_WITH_AS(files.stage((dir / "." / "a").string(), std::string_view("again")),
                         doctest::Contains("names the same file"), deform::Error);
  }
  CHECK(snapshot(dir) == std::map<std::string, std::string>{{"a", "old"}});
  fs::remove_all(dir);
}
