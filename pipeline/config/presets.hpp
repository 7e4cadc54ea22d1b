// The sensor presets of share/presets/, compiled into the binary: name -> JSON text of a
// `sensor` object.
#pragma once

#include <map>
#include <string>

namespace glaswave {

const std::map<std::string, std::string>& sensor_presets();

}  // namespace glaswave
