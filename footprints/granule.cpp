// Reading GEDI L2A and GLAH14 granules with the HDF5 C API.
#include "footprints/granule.hpp"

#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <type_traits>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/input_file.hpp"
#include "core/netcdf_lock.hpp"

namespace glaswave {
namespace {

// An HDF5 identifier closed with its own function.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

bool has_link(hid_t location, const std::string& path) {
  // Every part of the path must exist before H5Lexists may be asked about the next.
  std::size_t slash = 0;
  while (true) {
    slash = path.find('/', slash + 1);
    const std::string part = path.substr(0, slash);
    if (H5Lexists(location, part.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
  }
}

// Where a dataset lives, for messages: "FILE: GROUP".
struct Place {
  const std::string& file;
  const std::string& group;
  std::string text() const { return file + ": " + group; }
};

// A one-dimensional dataset of at most kMostGranuleShots values, opened; its length and the
// class (integer, float) and sign of its stored type.
struct Dataset {
  std::unique_ptr<Handle> handle;
  std::size_t size = 0;
  H5T_class_t type_class = H5T_NO_CLASS;
  bool is_signed = false;
};

Dataset open_dataset(hid_t group, const std::string& name, const Place& place) {
  if (!has_link(group, name)) throw input_error(place.text(), "no dataset \"" + name + "\"");
  Dataset d;
  d.handle = std::make_unique<Handle>(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!d.handle->valid()) throw input_error(place.text(), "\"" + name + "\" is not a dataset");
  Handle space(H5Dget_space(d.handle->get()), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space.get()) : -1;
  if (rank != 1) throw input_error(place.text(), "\"" + name + "\" is not one-dimensional");
  hsize_t size = 0;
  H5Sget_simple_extent_dims(space.get(), &size, nullptr);
  // The declared length decides the allocation: it is checked before anything is read.
  if (size > static_cast<hsize_t>(kMostGranuleShots))
    throw input_error(place.text(), "\"" + name + "\" declares " + std::to_string(size) +
                                        " values, more than the " +
                                        std::to_string(kMostGranuleShots) +
                                        " shots a beam of a granule may hold");
  d.size = static_cast<std::size_t>(size);
  Handle type(H5Dget_type(d.handle->get()), H5Tclose);
  d.type_class = type.valid() ? H5Tget_class(type.get()) : H5T_NO_CLASS;
  d.is_signed = d.type_class == H5T_INTEGER && H5Tget_sign(type.get()) == H5T_SGN_2;
  if (d.type_class != H5T_INTEGER && d.type_class != H5T_FLOAT)
    throw input_error(place.text(), "\"" + name + "\" does not hold numbers");
  return d;
}

template <typename T>
std::vector<T> read_values(const Dataset& d, hid_t memory_type, const std::string& name,
                           const Place& place) {
  std::vector<T> values(d.size);
  if (d.size > 0 &&
      H5Dread(d.handle->get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
    throw input_error(place.text(), "cannot read \"" + name + "\" (truncated or corrupt)");
  return values;
}

std::vector<double> read_doubles(hid_t group, const std::string& name, const Place& place) {
  const Dataset d = open_dataset(group, name, place);
  return read_values<double>(d, H5T_NATIVE_DOUBLE, name, place);
}

// An integer dataset read exactly, each value checked to lie in [low, high]: HDF5 would round
// floating point and clip what does not fit, silently.
std::vector<std::int64_t> read_integers(hid_t group, const std::string& name, std::int64_t low,
                                        std::int64_t high, const Place& place) {
  const Dataset d = open_dataset(group, name, place);
  if (d.type_class != H5T_INTEGER)
    throw input_error(place.text(), "\"" + name +
                                        "\" is stored as floating point: it must hold integers, "
                                        "and is not rounded");
  auto out_of_range = [&](const std::string& value) {
    return input_error(place.text(), "\"" + name + "\" holds " + value + ", outside " +
                                         std::to_string(low) + ".." + std::to_string(high));
  };
  std::vector<std::int64_t> values;
  if (d.is_signed) {
    values = read_values<std::int64_t>(d, H5T_NATIVE_INT64, name, place);
    for (std::int64_t v : values)
      if (v < low || v > high) throw out_of_range(std::to_string(v));
  } else {
    const auto raw = read_values<std::uint64_t>(d, H5T_NATIVE_UINT64, name, place);
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

void read_gedi_beam(hid_t file, const std::string& beam, const std::string& path,
                    std::vector<GranuleShot>& shots, Skipped& skipped) {
  const Place place{path, beam};
  Handle group(H5Gopen2(file, beam.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) throw input_error(place.text(), "is not a group");
  const auto numbers =
      read_integers(group.get(), "shot_number", 0, std::numeric_limits<std::int64_t>::max(), place);
  const auto lat = read_doubles(group.get(), "lat_lowestmode", place);
  const auto lon = read_doubles(group.get(), "lon_lowestmode", place);
  const auto time = read_doubles(group.get(), "delta_time", place);
  check_lengths(numbers.size(), {lat.size(), lon.size(), time.size()}, place);
  std::vector<std::int64_t> degrade;
  if (has_link(group.get(), "degrade_flag")) {
    degrade = read_integers(group.get(), "degrade_flag", 0, 255, place);
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

void read_glah14(hid_t file, const std::string& path, std::vector<GranuleShot>& shots,
                 Skipped& skipped) {
  const std::string beam = "Data_40HZ";
  const Place place{path, beam};
  Handle group(H5Gopen2(file, beam.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) throw input_error(place.text(), "is not a group");
  const auto lat = read_doubles(group.get(), "Geolocation/d_lat", place);
  const auto lon = read_doubles(group.get(), "Geolocation/d_lon", place);
  const auto time = read_doubles(group.get(), "Time/d_UTCTime_40", place);
  // i_rec_ndx * 40 + 39 must fit a shot number.
  const auto record = read_integers(group.get(), "Time/i_rec_ndx", 0,
                                    (std::numeric_limits<std::int64_t>::max() - 39) / 40, place);
  const auto count = read_integers(group.get(), "Time/i_shot_count", 1, 40, place);
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

// The root's groups named BEAM..., in name order.
std::vector<std::string> gedi_beams(hid_t file) {
  std::vector<std::string> names;
  H5Literate(
      file, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        if (std::string(name).rfind("BEAM", 0) == 0)
          static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

std::vector<GranuleShot> read_in_process(const std::filesystem::path& file,
                                         const std::vector<std::string>& beams,
                                         std::vector<std::string>* warnings) {
  const std::string path = file.string();
  // HDF5 (Debian's, not built thread-safe) is the library under libnetcdf: one lock for both,
  // held until every handle below is closed.
  const std::lock_guard lock(netcdf_library_mutex());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
  require_input_file(path, "the granule");
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw input_error(path, "the granule is not an HDF5 file (GEDI L2A or GLAH14)");
  Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!h5.valid()) throw input_error(path, "cannot open the granule");
  for (std::size_t i = 0; i < beams.size(); ++i)
    if (std::find(beams.begin(), beams.begin() + static_cast<std::ptrdiff_t>(i), beams[i]) !=
        beams.begin() + static_cast<std::ptrdiff_t>(i))
      throw input_error(path + ": " + beams[i],
                        "the beam is named twice in track.beams: its shots would be simulated "
                        "twice");

  std::vector<GranuleShot> shots;
  Skipped skipped;
  const std::vector<std::string> all_beams = gedi_beams(h5.get());
  if (!all_beams.empty()) {
    for (const std::string& beam : beams)
      if (std::find(all_beams.begin(), all_beams.end(), beam) == all_beams.end())
        throw input_error(path + ": " + beam, "no such beam in the GEDI granule (it has " +
                                                  std::to_string(all_beams.size()) +
                                                  " BEAM groups, from " + all_beams.front() + ")");
    for (const std::string& beam : beams.empty() ? all_beams : beams) {
      read_gedi_beam(h5.get(), beam, path, shots, skipped);
      if (shots.size() > static_cast<std::size_t>(kMostGranuleShots))
        throw input_error(path, "the beams hold more than " + std::to_string(kMostGranuleShots) +
                                    " shots together: name fewer in track.beams");
    }
  } else if (has_link(h5.get(), "Data_40HZ")) {
    for (const std::string& beam : beams)
      if (beam != "Data_40HZ")
        throw input_error(path + ": " + beam,
                          "no such beam in the GLAH14 granule (its one beam is Data_40HZ)");
    read_glah14(h5.get(), path, shots, skipped);
  } else {
    throw input_error(path,
                      "neither a GEDI L2A granule (no BEAMxxxx group) nor a GLAH14 granule (no "
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

// What the child sends its parent: a tag, then the shots or the error, then warnings.
void put_bytes(std::string& out, const void* data, std::size_t size) {
  out.append(static_cast<const char*>(data), size);
}
void put_string(std::string& out, const std::string& text) {
  const std::uint64_t size = text.size();
  put_bytes(out, &size, sizeof size);
  out += text;
}

class Reader {
 public:
  explicit Reader(const std::string& data) : data_(data) {}
  void get(void* out, std::size_t size) {
    if (data_.size() - at_ < size) throw std::length_error("granule reader's reply cut");
    std::memcpy(out, data_.data() + at_, size);
    at_ += size;
  }
  std::string get_string() {
    std::uint64_t size = 0;
    get(&size, sizeof size);
    if (data_.size() - at_ < size) throw std::length_error("granule reader's reply cut");
    std::string text = data_.substr(at_, size);
    at_ += size;
    return text;
  }

 private:
  const std::string& data_;
  std::size_t at_ = 0;
};

// In the child: reads the granule and encodes the outcome.
std::string read_encoded(const std::filesystem::path& file, const std::vector<std::string>& beams) {
  std::string out;
  std::vector<std::string> warnings;
  try {
    const std::vector<GranuleShot> shots = read_in_process(file, beams, &warnings);
    out += 'S';
    const std::uint64_t count = shots.size();
    put_bytes(out, &count, sizeof count);
    put_bytes(out, shots.data(), shots.size() * sizeof(GranuleShot));
  } catch (const Error& e) {
    out += 'E';
    const auto kind = static_cast<std::int32_t>(e.kind());
    put_bytes(out, &kind, sizeof kind);
    put_string(out, e.place());
    put_string(out, e.message());
  } catch (const std::exception& e) {
    out += 'E';
    const auto kind = static_cast<std::int32_t>(ErrorKind::input);
    put_bytes(out, &kind, sizeof kind);
    put_string(out, file.string());
    put_string(out, std::string("cannot read the granule: ") + e.what());
  }
  const std::uint64_t lines = warnings.size();
  put_bytes(out, &lines, sizeof lines);
  for (const std::string& line : warnings) put_string(out, line);
  return out;
}

std::vector<GranuleShot> decode(const std::string& reply, std::vector<std::string>* warnings) {
  static_assert(std::is_trivially_copyable_v<GranuleShot>);
  Reader in(reply);
  char tag = 0;
  in.get(&tag, 1);
  std::vector<GranuleShot> shots;
  std::optional<Error> error;
  if (tag == 'S') {
    std::uint64_t count = 0;
    in.get(&count, sizeof count);
    if (count > static_cast<std::uint64_t>(kMostGranuleShots) * 64)
      throw std::length_error("granule reader's reply too long");
    shots.resize(count);
    in.get(shots.data(), count * sizeof(GranuleShot));
  } else {
    std::int32_t kind = 0;
    in.get(&kind, sizeof kind);
    std::string place = in.get_string();
    error.emplace(static_cast<ErrorKind>(kind), std::move(place), in.get_string());
  }
  std::uint64_t lines = 0;
  in.get(&lines, sizeof lines);
  for (std::uint64_t i = 0; i < lines; ++i) {
    std::string line = in.get_string();
    if (warnings) warnings->push_back(std::move(line));
  }
  if (error) throw *error;
  return shots;
}

}  // namespace

// HDF5 1.10 (Debian 12's) reads through a null pointer on some corrupt files (a fuzzed GEDI
// granule crashes H5Literate): the granule is read in a child process, so that a crash inside
// the library refuses the file instead of ending the program. The child holds the HDF5 lock
// from the fork on, as the parent does until the fork.
std::vector<GranuleShot> read_granule(const std::filesystem::path& file,
                                      const std::vector<std::string>& beams,
                                      std::vector<std::string>* warnings) {
  const std::string path = file.string();
  int ends[2];
  if (::pipe(ends) != 0) throw input_error(path, "cannot read the granule: no pipe");
  pid_t child = -1;
  {
    const std::lock_guard lock(netcdf_library_mutex());
    child = ::fork();
  }
  if (child == 0) {
    ::close(ends[0]);
    const std::string reply = read_encoded(file, beams);
    std::size_t sent = 0;
    while (sent < reply.size()) {
      const ssize_t n = ::write(ends[1], reply.data() + sent, reply.size() - sent);
      if (n <= 0) ::_exit(2);
      sent += static_cast<std::size_t>(n);
    }
    ::_exit(0);
  }
  ::close(ends[1]);
  if (child < 0) {
    ::close(ends[0]);
    throw input_error(path, "cannot read the granule: no process to read it in");
  }
  std::string reply;
  char buffer[1 << 16];
  for (ssize_t n; (n = ::read(ends[0], buffer, sizeof buffer)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(ends[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw input_error(path, "HDF5 failed reading the granule (a corrupt file): it is refused");
  try {
    return decode(reply, warnings);
  } catch (const std::length_error&) {
    throw input_error(path, "HDF5 failed reading the granule (a corrupt file): it is refused");
  }
}

}  // namespace glaswave
