// The regular-file rule, with stat(2) and statfs(2): nothing is opened before it holds.
#include "core/input_file.hpp"

#include <linux/magic.h>
#include <sys/stat.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace glaswave {

std::string printable_path(std::string_view path) {
  std::string text;
  for (const char c : path) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte == 0) {
      text += "\\0";
    } else if (byte == '\n') {
      text += "\\n";
    } else if (byte < 0x20 || byte == 0x7f) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", byte);
      text += hex;
    } else {
      text += c;
    }
  }
  return text;
}

void require_no_nul(std::string_view path, const std::string& place, ErrorKind kind) {
  const std::size_t nul = path.find('\0');
  if (nul == std::string_view::npos) return;
  throw Error(kind, place,
              "a path must not hold a NUL byte (at byte " + std::to_string(nul) + " of \"" +
                  printable_path(path.substr(0, 200)) + (path.size() > 200 ? "...\"" : "\"") +
                  "): the file before it would be read instead");
}

void require_input_file(std::string_view path, const std::string& what, ErrorKind kind) {
  const std::string place = printable_path(path);
  require_no_nul(path, place, kind);
  const std::string name(path);
  const auto refuse = [&](const std::string& why) {
    throw Error(kind, place, "cannot read " + what + ": " + why);
  };
  if (name.empty()) refuse("the path is empty");
  struct stat status {};
  if (::stat(name.c_str(), &status) != 0) {
    const int error_number = errno;
    refuse(error_number == ENOENT ? std::string("no such file") : std::strerror(error_number));
  }
  if (S_ISDIR(status.st_mode)) refuse("it is a directory");
  if (S_ISFIFO(status.st_mode)) refuse("it is a FIFO (a pipe), not a regular file");
  if (S_ISSOCK(status.st_mode)) refuse("it is a socket, not a regular file");
  if (S_ISCHR(status.st_mode) || S_ISBLK(status.st_mode))
    refuse("it is a device, not a regular file");
  if (!S_ISREG(status.st_mode)) refuse("not a regular file");
  // /proc and /sys hold "regular" files whose size is 0 and whose reads are the kernel's.
  struct statfs system {};
  if (::statfs(name.c_str(), &system) == 0 &&
      (system.f_type == PROC_SUPER_MAGIC || system.f_type == SYSFS_MAGIC))
    refuse("a pseudo-file of /proc or /sys, not a file of data");
  if (::access(name.c_str(), R_OK) != 0) refuse(std::strerror(errno));
}

}  // namespace glaswave
