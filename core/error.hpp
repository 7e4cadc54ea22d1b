// The one exception type of glaswave, in core/ so that every library can throw it; the faces
// (command line, Python) turn its kind into an exit status or an exception class.
#pragma once

#include <stdexcept>
#include <string>

namespace glaswave {

enum class ErrorKind {
  config = 2,  // bad command line or configuration
  input = 3,   // unusable input data: DEM, track, stands file
  run = 4,     // failure while running
};

// An error that names its place: a JSON path ("/canopy/pai"), a file path, or a shot.
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string place, const std::string& message)
      : std::runtime_error(place.empty() ? message : place + ": " + message),
        kind_(kind),
        place_(std::move(place)),
        message_(message) {}

  ErrorKind kind() const { return kind_; }
  const std::string& place() const { return place_; }
  const std::string& message() const { return message_; }  // what() without the place
  int exit_status() const { return static_cast<int>(kind_); }

 private:
  ErrorKind kind_;
  std::string place_;
  std::string message_;
};

inline Error config_error(std::string place, const std::string& message) {
  return Error(ErrorKind::config, std::move(place), message);
}
inline Error input_error(std::string place, const std::string& message) {
  return Error(ErrorKind::input, std::move(place), message);
}
inline Error run_error(std::string place, const std::string& message) {
  return Error(ErrorKind::run, std::move(place), message);
}

}  // namespace glaswave
