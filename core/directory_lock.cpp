// The directory lock with flock(2); the holder's process id written into the file for the
// message of the run that finds it held.
#include "core/directory_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "core/error.hpp"

namespace glaswave {

DirectoryLock::DirectoryLock(const std::filesystem::path& directory)
    : file_(directory / kFileName) {
  // A holder that releases removes the file: a lock taken on a file already removed is taken
  // again on the one now there.
  for (int attempt = 0; attempt < 100; ++attempt) {
    fd_ = ::open(file_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd_ < 0)
      throw config_error(directory.string(), "cannot create the output directory's lock " +
                                                 std::string(kFileName) + ": " +
                                                 std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int error_number = errno;
      char holder[32] = {};
      const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
      ::close(fd_);
      fd_ = -1;
      const std::string pid = n > 0 ? std::string(holder, static_cast<std::size_t>(n)) : "";
      if (error_number == EWOULDBLOCK)
        throw config_error(directory.string(),
                           "another glaswave run is writing into this output directory" +
                               (pid.empty() ? std::string() : " (process " + pid + ")") +
                               ": wait for it to end, or choose another --out");
      throw config_error(directory.string(), "cannot lock the output directory: " +
                                                 std::string(std::strerror(error_number)));
    }
    struct stat held {
    }, named{};
    if (::fstat(fd_, &held) == 0 && ::stat(file_.c_str(), &named) == 0 &&
        held.st_ino == named.st_ino && held.st_dev == named.st_dev) {
      const std::string pid = std::to_string(::getpid());
      if (::ftruncate(fd_, 0) == 0 && ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
        // The holder's id is only for a message: a lock without it still holds.
      }
      return;
    }
    ::close(fd_);
    fd_ = -1;
  }
  throw config_error(directory.string(),
                     "cannot lock the output directory: its lock file keeps "
                     "being replaced");
}

DirectoryLock::~DirectoryLock() {
  if (fd_ < 0) return;
  ::unlink(file_.c_str());  // while held: the next run creates its own
  ::close(fd_);
}

}  // namespace glaswave
