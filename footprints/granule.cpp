// Reading GEDI L2A and GLAH14 granules through the one HDF5 layer (core/hdf5_file.hpp).
#include "footprints/granule.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <type_traits>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/hdf5_file.hpp"
#include "core/input_file.hpp"
#include "core/netcdf_lock.hpp"
#include "core/spawned_reader.hpp"

namespace glaswave {
namespace {

// Where a dataset lives, for messages: "FILE: GROUP".
struct Place {
  const std::string& file;
  const std::string& group;
  std::string text() const { return file + ": " + group; }
};

// A one-dimensional numeric dataset of at most kMostGranuleShots values: its shape, checked.
Hdf5DatasetShape checked_shape(const Hdf5Reader& h5, const std::string& path,
                               const std::string& name, const Place& place) {
  if (!h5.has(path)) throw input_error(place.text(), "no dataset \"" + name + "\"");
  const std::optional<Hdf5DatasetShape> shape = h5.shape(path);
  if (!shape) throw input_error(place.text(), "\"" + name + "\" is not a dataset");
  if (shape->dims.size() != 1)
    throw input_error(place.text(), "\"" + name + "\" is not one-dimensional");
  // The declared length decides the allocation: it is checked before anything is read.
  if (shape->dims[0] > static_cast<std::uint64_t>(kMostGranuleShots))
    throw input_error(place.text(), "\"" + name + "\" declares " + std::to_string(shape->dims[0]) +
                                        " values, more than the " +
                                        std::to_string(kMostGranuleShots) +
                                        " shots a beam of a granule may hold");
  if (!shape->numeric) throw input_error(place.text(), "\"" + name + "\" does not hold numbers");
  // Only the reader program reads datasets (read_in_process): its CPU bound raised for what the
  // shots may cost, GEDI's 8 beams of this length, up to the limit (5 million shots, 2.5 s of
  // CPU even from a granule of 1 MB: spawned_reader.cpp).
  bound_request_cpu(
      place.file.c_str(),
      std::min<std::uint64_t>(shape->dims[0] * 8, kMostGranuleShots) * sizeof(GranuleShot));
  return *shape;
}

template <typename T>
std::vector<T> read_values(const Hdf5Reader& h5, const std::string& path, const std::string& name,
                           const Place& place) {
  std::vector<T> values;
  if (!h5.read(path, values))
    throw input_error(place.text(), "cannot read \"" + name + "\" (truncated or corrupt)");
  return values;
}

std::vector<double> read_doubles(const Hdf5Reader& h5, const std::string& group,
                                 const std::string& name, const Place& place) {
  const std::string path = group + "/" + name;
  checked_shape(h5, path, name, place);
  return read_values<double>(h5, path, name, place);
}

// An integer dataset read exactly, each value checked to lie in [low, high]: HDF5 would round
// floating point and clip what does not fit, silently.
std::vector<std::int64_t> read_integers(const Hdf5Reader& h5, const std::string& group,
                                        const std::string& name, std::int64_t low,
                                        std::int64_t high, const Place& place) {
  const std::string path = group + "/" + name;
  const Hdf5DatasetShape shape = checked_shape(h5, path, name, place);
  if (!shape.integer)
    throw input_error(place.text(), "\"" + name +
                                        "\" is stored as floating point: it must hold integers, "
                                        "and is not rounded");
  auto out_of_range = [&](const std::string& value) {
    return input_error(place.text(), "\"" + name + "\" holds " + value + ", outside " +
                                         std::to_string(low) + ".." + std::to_string(high));
  };
  std::vector<std::int64_t> values;
  if (shape.is_signed) {
    values = read_values<std::int64_t>(h5, path, name, place);
    for (std::int64_t v : values)
      if (v < low || v > high) throw out_of_range(std::to_string(v));
  } else {
    const auto raw = read_values<std::uint64_t>(h5, path, name, place);
    values.reserve(raw.size());
    for (std::uint64_t v : raw) {
      if (v > static_cast<std::uint64_t>(high) || static_cast<std::int64_t>(v) < low)
        throw out_of_range(std::to_string(v));
      values.push_back(static_cast<std::int64_t>(v));
    }
  }
  return values;
}

bool valid_position(double lat_deg, double lon_deg) {
  return std::isfinite(lat_deg) && std::isfinite(lon_deg) && std::abs(lat_deg) <= 90.0 &&
         lon_deg >= -180.0 && lon_deg <= 360.0;
}

void check_lengths(std::size_t n, std::initializer_list<std::size_t> others, const Place& place) {
  for (std::size_t other : others)
    if (other != n)
      throw input_error(place.text(), "its datasets differ in length (" + std::to_string(n) +
                                          " and " + std::to_string(other) + " values)");
}

// The footprints skipped for a fill position, for the warning.
struct Skipped {
  std::int64_t count = 0;
  std::string first;  // "BEAM0101 shot_number 123"
};

// BEAMxxxx's digits in binary; -1 for a name that is not four binary digits.
int beam_number(const std::string& name) {
  if (name.size() != 8) return -1;
  int number = 0;
  for (std::size_t i = 4; i < 8; ++i) {
    if (name[i] != '0' && name[i] != '1') return -1;
    number = number * 2 + (name[i] - '0');
  }
  return number;
}

void read_gedi_beam(const Hdf5Reader& h5, const std::string& beam, const std::string& path,
                    std::vector<GranuleShot>& shots, Skipped& skipped) {
  const Place place{path, beam};
  if (!h5.is_group(beam)) throw input_error(place.text(), "is not a group");
  const auto numbers =
      read_integers(h5, beam, "shot_number", 0, std::numeric_limits<std::int64_t>::max(), place);
  const auto lat = read_doubles(h5, beam, "lat_lowestmode", place);
  const auto lon = read_doubles(h5, beam, "lon_lowestmode", place);
  const auto time = read_doubles(h5, beam, "delta_time", place);
  check_lengths(numbers.size(), {lat.size(), lon.size(), time.size()}, place);
  std::vector<std::int64_t> degrade;
  if (h5.has(beam + "/degrade_flag")) {
    degrade = read_integers(h5, beam, "degrade_flag", 0, 255, place);
    check_lengths(numbers.size(), {degrade.size()}, place);
  }
  static const double gedi_epoch_s = parse_iso8601_utc("2018-01-01T00:00:00Z");
  const int number = beam_number(beam);
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    if (!valid_position(lat[i], lon[i])) {
      if (skipped.count++ == 0) skipped.first = beam + " shot_number " + std::to_string(numbers[i]);
      continue;
    }
    GranuleShot shot;
    shot.shot_number = numbers[i];
    shot.time_s = gedi_epoch_s + time[i];
    shot.lat_deg = lat[i];
    shot.lon_deg = lon[i];
    shot.beam = number;
    shot.degrade_flag = degrade.empty() ? 0 : static_cast<std::uint8_t>(degrade[i]);
    shots.push_back(shot);
  }
}

void read_glah14(const Hdf5Reader& h5, const std::string& path, std::vector<GranuleShot>& shots,
                 Skipped& skipped) {
  const std::string beam = "Data_40HZ";
  const Place place{path, beam};
  if (!h5.is_group(beam)) throw input_error(place.text(), "is not a group");
  const auto lat = read_doubles(h5, beam, "Geolocation/d_lat", place);
  const auto lon = read_doubles(h5, beam, "Geolocation/d_lon", place);
  const auto time = read_doubles(h5, beam, "Time/d_UTCTime_40", place);
  // i_rec_ndx * 40 + 39 must fit a shot number.
  const auto record = read_integers(h5, beam, "Time/i_rec_ndx", 0,
                                    (std::numeric_limits<std::int64_t>::max() - 39) / 40, place);
  const auto count = read_integers(h5, beam, "Time/i_shot_count", 1, 40, place);
  check_lengths(lat.size(), {lon.size(), time.size(), record.size(), count.size()}, place);
  for (std::size_t i = 0; i < lat.size(); ++i) {
    const std::int64_t number = record[i] * 40 + count[i] - 1;
    if (!valid_position(lat[i], lon[i])) {
      if (skipped.count++ == 0)
        skipped.first =
            "i_rec_ndx " + std::to_string(record[i]) + " i_shot_count " + std::to_string(count[i]);
      continue;
    }
    GranuleShot shot;
    shot.shot_number = number;
    shot.time_s = time[i];
    shot.lat_deg = lat[i];
    shot.lon_deg = lon[i];
    shot.record_index = record[i];
    shot.shot_count = static_cast<int>(count[i]);
    shots.push_back(shot);
  }
}

// GEDI's eight beams (the L2A dictionary's BEAM0000 to BEAM1011), in name order: a root group
// of any other name (BEAM2222) is no beam. Asked by name: listing the root (H5Literate) is what
// Debian 12's HDF5 1.10.8 crashes in on a corrupted local heap.
constexpr const char* kGediBeams[] = {"BEAM0000", "BEAM0001", "BEAM0010", "BEAM0011",
                                      "BEAM0101", "BEAM0110", "BEAM1000", "BEAM1011"};

std::vector<std::string> gedi_beams(const Hdf5Reader& h5) {
  std::vector<std::string> names;
  for (const char* name : kGediBeams)
    if (h5.has(name)) names.push_back(name);
  return names;
}

std::vector<GranuleShot> read_in_process(const std::filesystem::path& file,
                                         const std::vector<std::string>& beams,
                                         std::vector<std::string>* warnings) {
  const std::string path = file.string();
  // HDF5 (Debian's, not built thread-safe) is the library under libnetcdf: one lock for both,
  // held until every handle below is closed.
  const std::lock_guard lock(netcdf_library_mutex());
  require_input_file(path, "the granule");
  if (!Hdf5Reader::is_hdf5(file))
    throw input_error(path, "the granule is not an HDF5 file (GEDI L2A or GLAH14)");
  const Hdf5Reader h5(file);
  for (std::size_t i = 0; i < beams.size(); ++i)
    if (std::find(beams.begin(), beams.begin() + static_cast<std::ptrdiff_t>(i), beams[i]) !=
        beams.begin() + static_cast<std::ptrdiff_t>(i))
      throw input_error(path + ": " + beams[i],
                        "the beam is named twice in track.beams: its shots would be simulated "
                        "twice");

  std::vector<GranuleShot> shots;
  Skipped skipped;
  const std::vector<std::string> all_beams = gedi_beams(h5);
  if (!all_beams.empty()) {
    for (const std::string& beam : beams)
      if (std::find(all_beams.begin(), all_beams.end(), beam) == all_beams.end())
        throw input_error(path + ": " + beam,
                          "no such beam in the GEDI granule (it has " +
                              std::to_string(all_beams.size()) + " of GEDI's 8, from " +
                              all_beams.front() +
                              "; the 8 are BEAM0000, BEAM0001, BEAM0010, BEAM0011, BEAM0101, "
                              "BEAM0110, BEAM1000 and BEAM1011)");
    for (const std::string& beam : beams.empty() ? all_beams : beams) {
      read_gedi_beam(h5, beam, path, shots, skipped);
      if (shots.size() > static_cast<std::size_t>(kMostGranuleShots))
        throw input_error(path, "the beams hold more than " + std::to_string(kMostGranuleShots) +
                                    " shots together: name fewer in track.beams");
    }
  } else if (h5.has("Data_40HZ")) {
    for (const std::string& beam : beams)
      if (beam != "Data_40HZ")
        throw input_error(path + ": " + beam,
                          "no such beam in the GLAH14 granule (its one beam is Data_40HZ)");
    read_glah14(h5, path, shots, skipped);
  } else {
    throw input_error(path,
                      "neither a GEDI L2A granule (no group named as a GEDI beam, BEAM0000 to "
                      "BEAM1011) nor a GLAH14 granule (no "
                      "Data_40HZ group)");
  }
  if (shots.empty())
    throw input_error(path, "the granule holds no shot with a valid latitude and longitude");
  if (skipped.count > 0 && warnings)
    warnings->push_back(path + ": " + std::to_string(skipped.count) +
                        " footprints with a fill latitude or longitude are no shots of the track "
                        "(the first: " +
                        skipped.first + ")");
  return shots;
}

// The reader program's reply: 'S', the shots, or 'E', the error; then the warnings.
// The hello's number changes with the reply's layout or GranuleShot's.
constexpr std::string_view kHello = "glaswave-read-granule 2\n";

std::string read_encoded(const std::filesystem::path& file, const std::vector<std::string>& beams) {
  MessageOut out;
  std::vector<std::string> warnings;
  try {
    const std::vector<GranuleShot> shots = read_in_process(file, beams, &warnings);
    out.put('S');
    out.put(std::uint64_t{shots.size()});
    out.put_bytes(shots.data(), shots.size() * sizeof(GranuleShot));
  } catch (const Error& e) {
    out.put('E');
    out.put_error(e);
  } catch (const std::exception& e) {
    out.put('E');
    out.put_error(input_error(file.string(), std::string("cannot read the granule: ") + e.what()));
  }
  out.put(std::uint64_t{warnings.size()});
  for (const std::string& line : warnings) out.put_string(line);
  return out.text();
}

std::vector<GranuleShot> decode(const std::string& reply, std::vector<std::string>* warnings) {
  static_assert(std::is_trivially_copyable_v<GranuleShot>);
  MessageIn in(reply);
  std::vector<GranuleShot> shots;
  std::optional<Error> error;
  if (in.get<char>() == 'S') {
    const auto count = in.get<std::uint64_t>();
    if (count > in.left() / sizeof(GranuleShot))
      throw std::length_error("granule reader's reply cut");
    shots.resize(count);
    in.get_bytes(shots.data(), count * sizeof(GranuleShot));
  } else {
    error.emplace(in.get_error());
  }
  const auto lines = in.get<std::uint64_t>();
  for (std::uint64_t i = 0; i < lines; ++i) {
    std::string line = in.get_string();
    if (warnings) warnings->push_back(std::move(line));
  }
  if (error) throw *error;
  return shots;
}

}  // namespace

int granule_reader_main(int argc, char** argv) {
  const int channel = take_reply_channel();
  if (argc < 2 || channel < 0) return 2;
  bound_request_cpu(argv[1]);
  const std::vector<std::string> beams(argv + 2, argv + argc);
  const std::string reply = read_encoded(argv[1], beams);
  return write_hello(channel, kHello) && write_message(channel, reply) ? 0 : 2;
}

std::vector<GranuleShot> read_granule(const std::filesystem::path& file,
                                      const std::vector<std::string>& beams,
                                      std::vector<std::string>* warnings) {
  const std::string path = file.string();
  require_input_file(path, "the granule");
  const std::filesystem::path program = find_reader_program(
      "glaswave-read-granule", {GLASWAVE_GRANULE_READER_BUILT, GLASWAVE_GRANULE_READER_INSTALLED});
  if (program.empty())
    throw run_error(path,
                    "cannot read the granule: the program glaswave-read-granule, which reads "
                    "granules, is missing from this installation (install it as `cmake --install` "
                    "does, in PREFIX/libexec/glaswave/)");
  std::vector<std::string> arguments{path};
  arguments.insert(arguments.end(), beams.begin(), beams.end());
  SpawnedReader reader(program, arguments, path, "the granule", std::string(kHello));
  const std::string reply = reader.receive();
  reader.finish();
  try {
    return decode(reply, warnings);
  } catch (const std::length_error&) {
    throw input_error(path, "HDF5 failed reading the granule (a corrupt file): it is refused");
  }
}

}  // namespace glaswave
