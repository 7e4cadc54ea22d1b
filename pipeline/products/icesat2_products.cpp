// The ATL03- and ATL08-like granules, written with the HDF5 C library: no object time stamps, so
// that the same photons give the same bytes.
#include "pipeline/products/icesat2_products.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/netcdf_lock.hpp"

namespace glaswave {
namespace {

constexpr float fill_float = std::numeric_limits<float>::max();  // ATL08's 3.4028235e+38
constexpr double segment_20m = 20.0;

// An HDF5 identifier closed with its own close function when it goes.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id_ < 0) throw run_error(what, "HDF5 could not create it");
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  void close(const std::string& what) {
    const herr_t status = close_(id_);
    id_ = -1;
    if (status < 0) throw run_error(what, "HDF5 could not complete it");
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

template <typename T>
hid_t memory_type() {
  if constexpr (std::is_same_v<T, double>) return H5T_NATIVE_DOUBLE;
  if constexpr (std::is_same_v<T, float>) return H5T_NATIVE_FLOAT;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5T_NATIVE_INT64;
  if constexpr (std::is_same_v<T, std::int32_t>) return H5T_NATIVE_INT32;
  if constexpr (std::is_same_v<T, std::int8_t>) return H5T_NATIVE_INT8;
  if constexpr (std::is_same_v<T, std::uint8_t>) return H5T_NATIVE_UINT8;
}

template <typename T>
hid_t file_type() {
  if constexpr (std::is_same_v<T, double>) return H5T_IEEE_F64LE;
  if constexpr (std::is_same_v<T, float>) return H5T_IEEE_F32LE;
  if constexpr (std::is_same_v<T, std::int64_t>) return H5T_STD_I64LE;
  if constexpr (std::is_same_v<T, std::int32_t>) return H5T_STD_I32LE;
  if constexpr (std::is_same_v<T, std::int8_t>) return H5T_STD_I8LE;
  if constexpr (std::is_same_v<T, std::uint8_t>) return H5T_STD_U8LE;
}

class Granule {
 public:
  explicit Granule(const std::filesystem::path& path)
      : file_(path),
        where_(path.string()),
        id_(H5Fcreate(file_.part_path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
            where_) {}

  hid_t file() const { return id_.get(); }

  Handle group(hid_t parent, const std::string& name) const {
    Handle properties(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, where_);
    H5Pset_obj_track_times(properties.get(), false);
    return Handle(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                  H5Gclose, where_ + ": " + name);
  }

  // A dataset of `rows` x `columns` (columns 0: one dimension), chunked and compressed when
  // large, with its units and long name.
  template <typename T>
  void dataset(hid_t parent, const std::string& name, const std::vector<T>& values,
               const std::string& units, const std::string& long_name, std::size_t columns = 0,
               bool fill = false) const {
    const std::string what = where_ + ": " + name;
    const hsize_t rows = columns ? values.size() / columns : values.size();
    const hsize_t dims[2] = {rows, static_cast<hsize_t>(columns)};
    Handle space(H5Screate_simple(columns ? 2 : 1, dims, nullptr), H5Sclose, what);
    Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, what);
    H5Pset_obj_track_times(properties.get(), false);
    if (rows >= 1024) {
      const hsize_t chunk[2] = {std::min<hsize_t>(rows, 10000), static_cast<hsize_t>(columns)};
      H5Pset_chunk(properties.get(), columns ? 2 : 1, chunk);
      H5Pset_shuffle(properties.get());
      H5Pset_deflate(properties.get(), 4);
    }
    fill = fill && std::is_same_v<T, float>;  // ATL08's fill value is a float's
    if (fill) H5Pset_fill_value(properties.get(), H5T_NATIVE_FLOAT, &fill_float);
    Handle set(H5Dcreate2(parent, name.c_str(), file_type<T>(), space.get(), H5P_DEFAULT,
                          properties.get(), H5P_DEFAULT),
               H5Dclose, what);
    if (!values.empty() &&
        H5Dwrite(set.get(), memory_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
      throw run_error(what, "HDF5 could not write it");
    text_attribute(set.get(), "units", units);
    text_attribute(set.get(), "long_name", long_name);
    if (fill) {
      Handle scalar(H5Screate(H5S_SCALAR), H5Sclose, what);
      Handle attribute(H5Acreate2(set.get(), "_FillValue", H5T_IEEE_F32LE, scalar.get(),
                                  H5P_DEFAULT, H5P_DEFAULT),
                       H5Aclose, what);
      H5Awrite(attribute.get(), H5T_NATIVE_FLOAT, &fill_float);
    }
  }

  void text_attribute(hid_t object, const std::string& name, const std::string& text) const {
    const std::string what = where_ + ": attribute " + name;
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose, what);
    H5Tset_size(type.get(), std::max<std::size_t>(text.size(), 1));
    H5Tset_strpad(type.get(), H5T_STR_NULLTERM);
    Handle scalar(H5Screate(H5S_SCALAR), H5Sclose, what);
    Handle attribute(
        H5Acreate2(object, name.c_str(), type.get(), scalar.get(), H5P_DEFAULT, H5P_DEFAULT),
        H5Aclose, what);
    if (H5Awrite(attribute.get(), type.get(), text.c_str()) < 0)
      throw run_error(what, "HDF5 could not write it");
  }

  void ancillary(const GranuleInfo& info, const std::string& short_name) {
    text_attribute(file(), "short_name", short_name);
    text_attribute(file(), "title", "glaswave simulation of ICESat-2 " + short_name);
    text_attribute(file(), "source", std::string("glaswave ") + GLASWAVE_VERSION);
    text_attribute(file(), "history", info.history);
    text_attribute(file(), "glaswave_config", info.config_json);
    const Handle group_id = group(file(), "ancillary_data");
    dataset(group_id.get(), "atlas_sdp_gps_epoch", std::vector<double>{atlas_sdp_gps_epoch_s},
            "seconds since 1980-01-06T00:00:00.000000Z",
            "ATLAS Standard Data Product epoch (2018-01-01T00:00:00Z) in GPS seconds");
  }

  void beam_attributes(hid_t beam_group, const BeamTrack& beam) const {
    text_attribute(beam_group, "atlas_beam_type", beam.strong ? "strong" : "weak");
    text_attribute(beam_group, "atlas_spot_number", std::to_string(beam.spot_number));
    text_attribute(beam_group, "groundtrack_id", beam.name);
  }

  void finish() {
    id_.close(where_);
    file_.commit();
  }

 private:
  AtomicFile file_;
  std::string where_;
  Handle id_;
};

std::int32_t segment_of(double along_m) {
  return static_cast<std::int32_t>(std::floor(along_m / segment_20m)) + 1;
}

// The 20 m segments a beam spans: from the first shot's to the last shot's.
struct Segments {
  std::int32_t first = 1;
  std::vector<std::int64_t> ph_index_beg;
  std::vector<std::int32_t> ph_cnt;
  std::vector<std::size_t> first_shot;  // the first shot in each segment (or its nearest before)
};

Segments segments_of(const BeamTrack& beam) {
  Segments s;
  if (beam.shots.empty()) return s;
  s.first = segment_of(beam.shots.front().along_m);
  const std::size_t count =
      static_cast<std::size_t>(segment_of(beam.shots.back().along_m) - s.first + 1);
  s.ph_index_beg.assign(count, 0);
  s.ph_cnt.assign(count, 0);
  s.first_shot.assign(count, beam.shots.size());
  for (std::size_t k = 0; k < beam.shots.size(); ++k) {
    const BeamShot& shot = beam.shots[k];
    const std::size_t j = static_cast<std::size_t>(segment_of(shot.along_m) - s.first);
    if (s.first_shot[j] == beam.shots.size()) s.first_shot[j] = k;
    if (shot.photon_count == 0) continue;
    if (s.ph_cnt[j] == 0) s.ph_index_beg[j] = static_cast<std::int64_t>(shot.first_photon) + 1;
    s.ph_cnt[j] += static_cast<std::int32_t>(shot.photon_count);
  }
  for (std::size_t j = 1; j < count; ++j)
    if (s.first_shot[j] == beam.shots.size()) s.first_shot[j] = s.first_shot[j - 1];
  return s;
}

// Each photon's shot, in the photons' order.
std::vector<std::size_t> shot_of_photons(const BeamTrack& beam) {
  std::vector<std::size_t> shot(beam.photons.size(), 0);
  for (std::size_t k = 0; k < beam.shots.size(); ++k)
    for (std::uint32_t i = 0; i < beam.shots[k].photon_count; ++i)
      shot[beam.shots[k].first_photon + i] = k;
  return shot;
}

// The photons as the classification sees them. A shot's background rate becomes a density per
// m along track and m of height: rate * 2 / c photons a metre of height a shot, over the mean
// spacing of the shots.
std::vector<CloudPhoton> cloud_of(const BeamTrack& beam) {
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  const double spacing_m = beam.shots.size() > 1
                               ? (beam.shots.back().along_m - beam.shots.front().along_m) /
                                     static_cast<double>(beam.shots.size() - 1)
                               : 1.0;
  std::vector<CloudPhoton> cloud(beam.photons.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const BeamShot& s = beam.shots[shot[i]];
    cloud[i] = {s.along_m, beam.photons[i].h_m,
                s.background_rate_Hz * 2.0 / 299792458.0 / std::max(spacing_m, 1e-3)};
  }
  return cloud;
}

template <typename T, typename F>
std::vector<T> each_photon(const BeamTrack& beam, F f) {
  std::vector<T> out;
  out.reserve(beam.photons.size());
  for (const BeamPhoton& p : beam.photons) out.push_back(static_cast<T>(f(p)));
  return out;
}

void write_heights(Granule& g, hid_t beam_group, const BeamTrack& beam, const Atl08Classes& c) {
  const Handle heights = g.group(beam_group, "heights");
  const hid_t h = heights.get();
  g.dataset(h, "h_ph", each_photon<float>(beam, [](auto& p) { return p.h_m; }), "meters",
            "Photon WGS84 height");
  g.dataset(h, "lat_ph", each_photon<double>(beam, [](auto& p) { return p.lat_deg; }),
            "degrees_north", "Latitude");
  g.dataset(h, "lon_ph", each_photon<double>(beam, [](auto& p) { return p.lon_deg; }),
            "degrees_east", "Longitude");
  g.dataset(h, "delta_time", each_photon<double>(beam, [](auto& p) { return p.delta_time_s; }),
            "seconds since 2018-01-01", "Elapsed GPS seconds");
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  std::vector<float> along(beam.photons.size());
  for (std::size_t i = 0; i < along.size(); ++i) {
    const double x = beam.shots[shot[i]].along_m;
    along[i] = static_cast<float>(x - (segment_of(x) - 1) * segment_20m);
  }
  g.dataset(h, "dist_ph_along", along, "meters", "Distance from the segment's start");
  std::vector<std::int8_t> confidence(beam.photons.size() * 5, -1);
  for (std::size_t i = 0; i < beam.photons.size(); ++i) confidence[5 * i] = c.confidence[i];
  g.dataset(h, "signal_conf_ph", confidence, "counts",
            "Photon signal confidence (land, ocean, sea ice, land ice, inland water): -1 not "
            "considered, 0 noise, 2 low, 3 medium, 4 high",
            5);
  g.dataset(h, "glaswave_truth_class",
            each_photon<std::uint8_t>(beam, [](auto& p) { return p.truth_class; }), "1",
            "Simulation truth: 0 background, 1 ground, 2 canopy, 3 top of canopy");
  g.dataset(h, "glaswave_order", each_photon<std::uint8_t>(beam, [](auto& p) { return p.order; }),
            "1", "Simulation truth: scattering order, 0 for background");
}

void write_geolocation(Granule& g, hid_t beam_group, const BeamTrack& beam) {
  const Segments s = segments_of(beam);
  const Handle geolocation = g.group(beam_group, "geolocation");
  const hid_t h = geolocation.get();
  std::vector<std::int32_t> id(s.ph_cnt.size());
  std::vector<double> dist(id.size()), lat(id.size()), lon(id.size()), time(id.size());
  std::vector<float> length(id.size(), static_cast<float>(segment_20m));
  for (std::size_t j = 0; j < id.size(); ++j) {
    id[j] = s.first + static_cast<std::int32_t>(j);
    dist[j] = (id[j] - 1) * segment_20m;
    const BeamShot& shot = beam.shots[s.first_shot[j]];
    lat[j] = shot.lat_deg;
    lon[j] = shot.lon_deg;
    time[j] = shot.delta_time_s;
  }
  g.dataset(h, "segment_id", id, "1", "Along-track segment ID number (20 m, from 1)");
  g.dataset(h, "ph_index_beg", s.ph_index_beg, "1",
            "1-based index of the segment's first photon in heights/ (0: none)");
  g.dataset(h, "segment_ph_cnt", s.ph_cnt, "1", "Number of photons in the segment");
  g.dataset(h, "segment_dist_x", dist, "meters", "Along-track distance of the segment's start");
  g.dataset(h, "segment_length", length, "meters", "Along-track length of the segment");
  g.dataset(h, "reference_photon_lat", lat, "degrees_north",
            "Latitude of the segment's first shot");
  g.dataset(h, "reference_photon_lon", lon, "degrees_east",
            "Longitude of the segment's first shot");
  g.dataset(h, "delta_time", time, "seconds since 2018-01-01", "Time of the segment's first shot");
}

void write_background(Granule& g, hid_t beam_group, const BeamTrack& beam) {
  const Handle background = g.group(beam_group, "bckgrd_atlas");
  std::vector<float> rate;
  std::vector<double> time;
  for (const BeamShot& shot : beam.shots) {
    rate.push_back(static_cast<float>(shot.background_rate_Hz));
    time.push_back(shot.delta_time_s);
  }
  g.dataset(background.get(), "bckgrd_rate", rate, "counts / second",
            "Background count rate (each shot's; ATLAS's is per 50 shots)");
  g.dataset(background.get(), "delta_time", time, "seconds since 2018-01-01",
            "Elapsed GPS seconds");
}

}  // namespace

std::vector<Atl08Classes> classify_beams(const std::vector<BeamTrack>& beams,
                                         const Atl08Settings& settings) {
  std::vector<Atl08Classes> out;
  for (const BeamTrack& beam : beams) out.push_back(classify_photons(cloud_of(beam), settings));
  return out;
}

void write_atl03(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const GranuleInfo& info) {
  const std::lock_guard<std::mutex> hdf5(netcdf_library_mutex());  // HDF5 is not thread-safe
  Granule g(path);
  g.ancillary(info, "ATL03");
  for (std::size_t b = 0; b < beams.size(); ++b) {
    const Handle beam_group = g.group(g.file(), beams[b].name);
    g.beam_attributes(beam_group.get(), beams[b]);
    write_heights(g, beam_group.get(), beams[b], classes[b]);
    write_geolocation(g, beam_group.get(), beams[b]);
    write_background(g, beam_group.get(), beams[b]);
  }
  g.finish();
}

namespace {

struct SegmentTruth {
  std::vector<float> h_te, h_canopy, cover, pai, lat, lon;
  std::vector<double> time;
  std::vector<std::int32_t> id_beg, id_end;
};

// The shots' positions and the simulation's truth averaged over each land segment.
SegmentTruth segment_truth(const BeamTrack& beam, double first_m, std::size_t count,
                           double segment_m) {
  SegmentTruth t;
  std::vector<double> n(count, 0.0), h(count, 0.0), ch(count, 0.0), cv(count, 0.0), pai(count, 0.0);
  std::vector<std::size_t> middle(count, beam.shots.size());
  std::vector<double> best(count, 1e300);
  for (std::size_t k = 0; k < beam.shots.size(); ++k) {
    const BeamShot& s = beam.shots[k];
    const std::size_t j = static_cast<std::size_t>(
        std::clamp(std::floor((s.along_m - first_m) / segment_m), 0.0, double(count - 1)));
    n[j] += 1.0;
    h[j] += s.ground_h_m;
    ch[j] += s.canopy_height_m;
    cv[j] += s.canopy_cover;
    pai[j] += s.pai;
    const double off = std::abs(s.along_m - (first_m + (j + 0.5) * segment_m));
    if (off < best[j]) best[j] = off, middle[j] = k;
  }
  for (std::size_t j = 0; j < count; ++j) {
    const bool any = n[j] > 0.0;
    const auto mean = [&](double sum) { return any ? static_cast<float>(sum / n[j]) : fill_float; };
    t.h_te.push_back(mean(h[j]));
    t.h_canopy.push_back(mean(ch[j]));
    t.cover.push_back(mean(cv[j]));
    t.pai.push_back(mean(pai[j]));
    const BeamShot* s = any ? &beam.shots[middle[j]] : nullptr;
    t.lat.push_back(s ? static_cast<float>(s->lat_deg) : fill_float);
    t.lon.push_back(s ? static_cast<float>(s->lon_deg) : fill_float);
    t.time.push_back(s ? s->delta_time_s : fill_float);
    const double start = first_m + static_cast<double>(j) * segment_m;
    t.id_beg.push_back(segment_of(start));
    t.id_end.push_back(segment_of(start + segment_m) - 1);
  }
  return t;
}

std::vector<float> as_float(const std::vector<LandSegment>& s, double LandSegment::*member) {
  std::vector<float> out;
  for (const LandSegment& x : s) {
    const double v = x.*member;
    out.push_back(std::isnan(v) ? fill_float : static_cast<float>(v));
  }
  return out;
}

std::vector<std::int32_t> as_int(const std::vector<LandSegment>& s,
                                 std::int32_t LandSegment::*member) {
  std::vector<std::int32_t> out;
  for (const LandSegment& x : s) out.push_back(x.*member);
  return out;
}

void write_land_segments(Granule& g, hid_t beam_group, const BeamTrack& beam,
                         const Atl08Classes& classes, const Atl08Settings& settings) {
  if (beam.shots.empty()) return;
  const double first_m =
      std::floor(beam.shots.front().along_m / settings.segment_m) * settings.segment_m;
  const double end_m = beam.shots.back().along_m + 1e-9;
  const std::vector<LandSegment> s =
      land_segments(cloud_of(beam), classes, first_m, end_m, settings);
  const SegmentTruth t = segment_truth(beam, first_m, s.size(), settings.segment_m);
  const Handle land = g.group(beam_group, "land_segments");
  const hid_t h = land.get();
  g.dataset(h, "latitude", t.lat, "degrees_north", "Latitude of the segment's centre", 0, true);
  g.dataset(h, "longitude", t.lon, "degrees_east", "Longitude of the segment's centre", 0, true);
  g.dataset(h, "delta_time", t.time, "seconds since 2018-01-01", "Time of the segment's centre");
  g.dataset(h, "segment_id_beg", t.id_beg, "1", "First ATL03 20 m segment of the segment");
  g.dataset(h, "segment_id_end", t.id_end, "1", "Last ATL03 20 m segment of the segment");
  const Handle terrain = g.group(h, "terrain");
  g.dataset(terrain.get(), "h_te_best_fit", as_float(s, &LandSegment::h_te_best_fit), "meters",
            "Best fit terrain elevation at the segment's centre", 0, true);
  g.dataset(terrain.get(), "n_te_photons", as_int(s, &LandSegment::n_te_photons), "1",
            "Number of ground photons");
  const Handle canopy = g.group(h, "canopy");
  g.dataset(canopy.get(), "h_canopy", as_float(s, &LandSegment::h_canopy), "meters",
            "98th percentile of the canopy heights above the terrain", 0, true);
  g.dataset(canopy.get(), "canopy_openness", as_float(s, &LandSegment::canopy_openness), "meters",
            "Standard deviation of the canopy heights above the terrain", 0, true);
  g.dataset(canopy.get(), "n_ca_photons", as_int(s, &LandSegment::n_ca_photons), "1",
            "Number of canopy photons");
  g.dataset(canopy.get(), "n_toc_photons", as_int(s, &LandSegment::n_toc_photons), "1",
            "Number of top of canopy photons");
  const Handle truth = g.group(h, "glaswave_truth");
  g.dataset(truth.get(), "h_te", t.h_te, "meters",
            "Simulation truth: mean terrain height at the segment's footprint centres", 0, true);
  g.dataset(truth.get(), "h_canopy", t.h_canopy, "meters",
            "Simulation truth: mean of the footprints' canopy heights", 0, true);
  g.dataset(truth.get(), "canopy_cover", t.cover, "1",
            "Simulation truth: mean of the footprints' crown cover", 0, true);
  g.dataset(truth.get(), "pai", t.pai, "1", "Simulation truth: mean of the footprints' PAI", 0,
            true);
}

void write_signal_photons(Granule& g, hid_t beam_group, const BeamTrack& beam,
                          const Atl08Classes& classes) {
  const std::vector<std::size_t> shot = shot_of_photons(beam);
  std::vector<std::int8_t> flag;
  std::vector<std::int32_t> index, segment;
  std::vector<float> height;
  std::vector<double> time;
  std::int32_t current = 0, first_in_segment = 0;
  for (std::size_t i = 0; i < beam.photons.size(); ++i) {
    const std::int32_t id = segment_of(beam.shots[shot[i]].along_m);
    if (id != current) current = id, first_in_segment = static_cast<std::int32_t>(i);
    if (classes.classes[i] == 0) continue;
    flag.push_back(static_cast<std::int8_t>(classes.classes[i]));
    index.push_back(static_cast<std::int32_t>(i) - first_in_segment + 1);
    segment.push_back(id);
    height.push_back(
        static_cast<float>(beam.photons[i].h_m - classes.ground_at(beam.shots[shot[i]].along_m)));
    time.push_back(beam.photons[i].delta_time_s);
  }
  const Handle signal = g.group(beam_group, "signal_photons");
  const hid_t h = signal.get();
  g.dataset(h, "classed_pc_flag", flag, "1",
            "Photon land classification: 1 ground, 2 canopy, 3 top of canopy");
  g.dataset(h, "classed_pc_indx", index, "1", "1-based index of the photon in its ATL03 segment");
  g.dataset(h, "ph_segment_id", segment, "1", "The photon's ATL03 20 m segment");
  g.dataset(h, "ph_h", height, "meters", "Photon height above the fitted terrain");
  g.dataset(h, "delta_time", time, "seconds since 2018-01-01", "Elapsed GPS seconds");
}

}  // namespace

void write_atl08(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const Atl08Settings& settings,
                 const GranuleInfo& info) {
  const std::lock_guard<std::mutex> hdf5(netcdf_library_mutex());  // HDF5 is not thread-safe
  Granule g(path);
  g.ancillary(info, "ATL08");
  for (std::size_t b = 0; b < beams.size(); ++b) {
    const Handle beam_group = g.group(g.file(), beams[b].name);
    g.beam_attributes(beam_group.get(), beams[b]);
    write_land_segments(g, beam_group.get(), beams[b], classes[b], settings);
    write_signal_photons(g, beam_group.get(), beams[b], classes[b]);
  }
  g.finish();
}

}  // namespace glaswave
