// export_native into an existing folder lands as one FileTransaction: a failure at any step of the landing leaves
// every file of the previous export byte for byte, and no temporary, staging folder or backup behind.
#include <doctest/doctest.h>

#include <filesystem>
#include <iterator>
#include <map>
#include <string>

#include "deform/extras/builtin.hpp"
#include "deform/import/import.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"

namespace fs = std::filesystem;

namespace {

std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir))
    files[entry.path().filename().string()] = deform::read_file_text(entry.path().string());
  return files;
}

}  // namespace

TEST_CASE("an export into an existing folder failing at any step leaves the previous export as it was") {
  const fs::path root = fs::temp_directory_path() / "deform_export_landing";
  fs::remove_all(root);
  fs::create_directories(root);
  const fs::path out = root / "out";
  deform::Model model = deform::builtin_character();
  (void)deform::export_native(model, out.string());
  // A previous set that differs from the next export in every file.
  const auto first = snapshot(out);
  for (const auto& file : first) deform::write_file_atomic((out / file.first).string(), "previous " + file.first);
  const auto before = snapshot(out);
  REQUIRE(before.size() == 4);
  long failures = 0;
  for (long step = 0;; ++step) {
    CAPTURE(step);
    deform::inject_file_failure_for_testing(step);
    bool failed = false;
    try {
      (void)deform::export_native(model, out.string());
    } catch (const deform::Error&) {
      failed = true;
    }
    deform::inject_file_failure_for_testing(-1);
    CHECK(std::distance(fs::directory_iterator(root), fs::directory_iterator()) == 1);  // no staging folder left
    if (!failed) break;
    ++failures;
    CHECK(snapshot(out) == before);
    REQUIRE(step < 200);
  }
  // Steps: the staging folder's 4 files each written and renamed, then the landing's 4 staged, 4 backed up and 4
  // renamed in.
  CHECK(failures == 20);
  CHECK(snapshot(out) == first);
  fs::remove_all(root);
}
