// The one exception type of glaswave, in core/ so that every library can throw it; the faces
// (command line, Python) turn its kind into an exit status or an exception class.
#pragma once

#include <stdexcept>
#include <string>

#include "core/excerpt.hpp"

namespace glaswave {

enum class ErrorKind {
  config = 2,  // bad command line or configuration
  input = 3,   // unusable input data: DEM, track, stands file
  run = 4,     // failure while running
};

// The longest place kept whole: a path the system can open is shorter (PATH_MAX); a longer
// one (a 1 MB string given as a file) is named by its excerpt (core/excerpt.hpp).
inline constexpr std::size_t max_place_chars = 4096;

// An error that names its place: a JSON path ("/canopy/pai"), a file path, or a shot.
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, std::string place, const std::string& message)
      : Error(kind, bounded_place(std::move(place)), message, 0) {}

  ErrorKind kind() const { return kind_; }
  // Whether the place is a member of the settings the thrower was given ("vertical_datum"; empty
  // for the settings as a whole) rather than a JSON path or a file: the floors below the
  // configuration know their settings, not the JSON they came from.
  bool names_setting() const { return names_setting_; }
  // The same error placed at `section` (a JSON pointer such as "/terrain") when it names a
  // setting: "/terrain/vertical_datum". Other errors come back as they are.
  Error in_section(const std::string& section) const {
    if (!names_setting_) return *this;
    return Error(kind_, place_.empty() ? section : section + "/" + place_, message_);
  }
  const std::string& place() const { return place_; }
  const std::string& message() const { return message_; }  // what() without the place
  int exit_status() const { return static_cast<int>(kind_); }

 private:
  Error(ErrorKind kind, std::string place, const std::string& message, int /*bounded*/)
      : std::runtime_error(place.empty() ? message : place + ": " + message),
        kind_(kind),
        place_(std::move(place)),
        message_(message) {}
  static std::string bounded_place(std::string place) {
    return place.size() > max_place_chars ? excerpt(place) : place;
  }

  ErrorKind kind_;
  std::string place_;
  std::string message_;
  bool names_setting_ = false;

  friend Error setting_error(ErrorKind kind, std::string setting, const std::string& message);
};

// An error about one of the settings a floor below the configuration was given, named as its
// member ("vertical_datum"), or empty for the settings as a whole.
inline Error setting_error(ErrorKind kind, std::string setting, const std::string& message) {
  Error error(kind, std::move(setting), message);
  error.names_setting_ = true;
  return error;
}

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
