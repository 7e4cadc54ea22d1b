// A product under construction: written to FINAL.part and renamed to FINAL only when
// complete, so that no half-written product ever lies under its final name (PRODUCT.md,
// section 2). Shared by every product writer so the rule lives in one place.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "core/error.hpp"

namespace glaswave {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path final_path)
      : final_path_(std::move(final_path)), part_path_(final_path_) {
    part_path_ += ".part";
  }

  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // An abandoned product (an exception, a writer never finished) must not survive as a
  // .part that a later reader might mistake for output; a failure here has nowhere to go.
  ~AtomicFile() {
    if (!committed_) {
      std::error_code ignored;
      std::filesystem::remove(part_path_, ignored);
    }
  }

  const std::filesystem::path& final_path() const { return final_path_; }
  const std::filesystem::path& part_path() const { return part_path_; }
  bool committed() const { return committed_; }

  // Renames the completed .part to the final name (atomic within one file system). The
  // caller must have closed the file first.
  void commit() {
    std::error_code error;
    std::filesystem::rename(part_path_, final_path_, error);
    if (error) {
      throw run_error(final_path_.string(), "cannot rename " + part_path_.string() +
                                                " to the final name: " + error.message());
    }
    committed_ = true;
  }

 private:
  std::filesystem::path final_path_;
  std::filesystem::path part_path_;
  bool committed_ = false;
};

// A whole text product (a CSV, a ROMC file) written through an AtomicFile.
inline void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  AtomicFile file(path);
  std::FILE* out = std::fopen(file.part_path().c_str(), "w");
  if (!out) throw run_error(path.string(), "cannot write");
  const bool written = std::fwrite(text.data(), 1, text.size(), out) == text.size();
  if (std::fclose(out) != 0 || !written) throw run_error(path.string(), "cannot write");
  file.commit();
}

}  // namespace glaswave
