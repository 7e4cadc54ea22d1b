// The memory check: a shot's waveforms, which a run holds many times over, must stay small.
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/names.hpp"
#include "pipeline/config/section_readers.hpp"

namespace glaswave {

using nlohmann::json;

ShotSize shot_size(const Config& c) {
  ShotSize size;
  size.bands = static_cast<double>(c.sensor.bands.size());
  size.window_bins = c.sensor.bins;
  size.margin_bins = 2.0 * pulse_margin_bins(c.sensor);
  size.waveforms = 3.0 + (c.output.per_order ? c.simulation.max_order : 0);
  size.bytes = size.bands * (size.window_bins + size.margin_bins) * size.waveforms * 8.0;
  return size;
}

std::string mebibytes(double bytes) {
  return format_number(std::round(bytes / 1048576.0 * 10) / 10) + " MiB";
}

// A run holds a shot's waveforms many times over (the transport tallies each shot's rays in 65
// copies, and every thread simulates a shot): one shot's must stay small. Refused beyond the
// limit, at the key that makes it large.
void check_shot_size(const Config& c) {
  const ShotSize size = shot_size(c);
  if (size.bytes <= run_limits::shot_waveform_bytes) return;
  std::string place = "/sensor/bins";
  if (size.margin_bins > size.window_bins) place = "/sensor/pulse_sigma_ns";
  if (c.output.per_order && size.waveforms > 3.0 &&
      size.bytes * 3.0 / size.waveforms <= run_limits::shot_waveform_bytes)
    place = "/output/per_order";
  std::ostringstream why;
  why << "a shot's waveforms would take " << mebibytes(size.bytes) << " ("
      << format_number(size.bands) << " bands x " << format_number(size.window_bins) << " bins + "
      << format_number(size.margin_bins) << " bins of pulse margin x "
      << format_number(size.waveforms) << " waveforms x 8 bytes), more than the limit of "
      << mebibytes(run_limits::shot_waveform_bytes) << " a shot";
  throw config_error(place, why.str());
}

}  // namespace glaswave
