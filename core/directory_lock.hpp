// The lock of an output directory: one run at a time writes into it. Two runs on one --out (two
// fresh runs, or two --resume of one killed run, started together) would otherwise remove and
// write each other's files half-way. An flock(2) on a file in the directory: the kernel releases
// it when its process ends, however it ends, so a killed run leaves nothing that blocks --resume.
#pragma once

#include <filesystem>

namespace glaswave {

class DirectoryLock {
 public:
  // The lock file's name in the directory; not a product (it goes when the lock is released).
  static constexpr const char* kFileName = ".glaswave.lock";

  // Takes the lock of `directory` (which must exist), or throws Error (config, exit status 2)
  // naming the directory and the process that holds it.
  explicit DirectoryLock(const std::filesystem::path& directory);
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

 private:
  std::filesystem::path file_;
  int fd_ = -1;
};

}  // namespace glaswave
