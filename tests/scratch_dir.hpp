// A test's own scratch folder: fresh under the system's temporary directory, removed at its end.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>

namespace glaswave::test_support {

// A fresh folder <temp>/<label>_<process id>_<test suite>_<test>, made on construction (any
// leftover of that name removed first) and removed with everything in it on destruction. The
// process id keeps runs of the suite from other checkouts on this machine apart; the test's
// name keeps the tests of one run apart. The label may hold a space, to check that no shell
// ever sees the path. A folder that cannot be removed is a failure of the test.
class ScratchDir {
 public:
  explicit ScratchDir(std::string_view label = "glaswave") {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(label) + "_" + std::to_string(::getpid());
    if (info != nullptr) name += std::string("_") + info->test_suite_name() + "_" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');  // parameterised tests: "Suite/0"
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    if (keep_) return;
    std::error_code error;
    std::filesystem::remove_all(path_, error);
    if (error) ADD_FAILURE() << "cannot remove " << path_ << ": " << error.message();
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }

  // Writes `text` to the file `name` in the folder, making its parent folders; its path.
  std::filesystem::path write(const std::filesystem::path& name, const std::string& text) const {
    const std::filesystem::path file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file) << text;
    return file;
  }

  // Leaves the folder in place at the end, for inspection (of a failed test, say).
  void keep() { keep_ = true; }

 private:
  std::filesystem::path path_;
  bool keep_ = false;
};

}  // namespace glaswave::test_support
