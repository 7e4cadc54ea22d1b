// A write that failed, in words: a full disk (or a quota, or a file size limit) is said as such,
// since it is the one a user can fix without changing anything else.
#pragma once

#include <cerrno>
#include <cstring>
#include <string>

#include "core/error.hpp"

namespace glaswave {

// Whether errno `error_number` means there is no room left to write.
inline bool no_space(int error_number) {
  return error_number == ENOSPC || error_number == EDQUOT || error_number == EFBIG;
}

// The message of a write to a file that failed with errno `error_number`.
inline std::string write_failure(int error_number) {
  if (error_number == ENOSPC || error_number == EDQUOT)
    return std::string("cannot write: the disk is full (") + std::strerror(error_number) + ")";
  if (error_number == EFBIG)
    return std::string("cannot write: the disk is full or the file size limit is reached (") +
           std::strerror(error_number) + ")";
  return std::string("cannot write: ") + std::strerror(error_number);
}

// Error (run) for a write to `file` that failed with errno `error_number`.
inline Error write_error(const std::string& file, int error_number) {
  return run_error(file, write_failure(error_number));
}

}  // namespace glaswave
