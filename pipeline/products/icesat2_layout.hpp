// The ICESat-2 granules' shared layout, for atl03_granule.cpp and atl08_granule.cpp alone: a
// granule written through the one HDF5 layer (core/hdf5_file.hpp) with the data dictionaries'
// attributes, the file's ancillary_data/ and orbit_info/, the beams' groups, ATL03's 20 m
// segments and the photons as the classification sees them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/hdf5_file.hpp"
#include "pipeline/products/icesat2_products.hpp"

namespace glaswave::icesat2 {

inline constexpr float fill_float = std::numeric_limits<float>::max();  // ATL08's 3.4028235e+38
inline constexpr double segment_20m = 20.0;

// A dataset's attributes, as the data dictionaries give them: units, long_name, contentType
// (physicalMeasurement, referenceInformation, modelResult, qualityInformation,
// auxiliaryInformation) and a description (where the simulation's value comes from).
struct Meta {
  std::string units, long_name, content_type, description;
};

// A group of the granule, named by its path.
class Group {
 public:
  explicit Group(std::string path) : path_(std::move(path)) {}
  const std::string& get() const { return path_; }

 private:
  std::string path_;
};

// A granule written under FINAL.part through the one HDF5 layer (core/hdf5_file.hpp), renamed
// when finished.
class Granule {
 public:
  explicit Granule(const std::filesystem::path& path)
      : file_(path), h5_(file_.part_path(), Hdf5Chunking::every) {}

  const std::string& file() const { return root_; }

  Group group(const std::string& parent, const std::string& name) {
    Group g(parent == "/" ? "/" + name : parent + "/" + name);
    h5_.group(g.get());
    return g;
  }

  // A dataset of `rows` x `columns` (columns 0: one dimension) with its attributes; with
  // `fill`, the type's largest value is its _FillValue (the products' 3.4028235e+38 for
  // float32, 127 for int8).
  template <typename T>
  void dataset(const std::string& parent, const std::string& name, const std::vector<T>& values,
               const Meta& meta, std::size_t columns = 0, bool fill = false) {
    std::vector<std::uint64_t> dims;
    if (columns) dims = {values.size() / columns, columns};
    std::optional<T> fill_value;
    if (fill) fill_value = std::numeric_limits<T>::max();
    h5_.write(parent + "/" + name, values, attributes(meta), dims, fill_value);
  }

  // A one-dimensional dataset whose _FillValue is `fill` (ph_index_beg's 0).
  template <typename T>
  void dataset_filled(const std::string& parent, const std::string& name,
                      const std::vector<T>& values, const Meta& meta, T fill) {
    h5_.write(parent + "/" + name, values, attributes(meta), {}, std::optional<T>(fill));
  }

  // A one-element dataset of fixed-length text (ancillary_data's UTC times).
  void text_dataset(const std::string& parent, const std::string& name, const std::string& text,
                    const Meta& meta) {
    h5_.write_text(parent + "/" + name, text, attributes(meta));
  }

  void text_attribute(const std::string& object, const std::string& name, const std::string& text) {
    h5_.text_attribute(object, name, text);
  }

  void ancillary(const GranuleInfo& info, const std::string& short_name,
                 const std::vector<BeamTrack>& beams);

  void finish() {
    h5_.close();
    file_.commit();
  }

 private:
  static std::vector<Hdf5Attribute> attributes(const Meta& meta) {
    std::vector<Hdf5Attribute> list{{"units", meta.units}, {"long_name", meta.long_name}};
    if (!meta.content_type.empty()) list.push_back({"contentType", meta.content_type});
    if (!meta.description.empty()) list.push_back({"description", meta.description});
    return list;
  }

  AtomicFile file_;
  Hdf5Writer h5_;
  std::string root_ = "/";
};

inline const Meta delta_time_meta{
    "seconds since 2018-01-01", "Elapsed GPS seconds", "referenceInformation",
    "Seconds since the ATLAS Standard Data Product epoch, "
    "ancillary_data/atlas_sdp_gps_epoch GPS seconds after the GPS epoch"};

// The first and last shot times of all beams (the ATLAS epoch when there is none).
std::pair<double, double> time_span(const std::vector<BeamTrack>& beams);

// A field of the simulation's truth, in no real product.
Meta truth_meta(const std::string& units, const std::string& long_name);

// The 20 m segment (ATL03's geolocation/segment_id, from 1) of a distance along track.
std::int32_t segment_of(double along_m);

// The 20 m segments a beam spans: from the first shot's to the last shot's.
struct Segments {
  std::int32_t first = 1;
  std::vector<std::int64_t> ph_index_beg;
  std::vector<std::int32_t> ph_cnt;
  std::vector<std::size_t> first_shot;  // the first shot in each segment (or its nearest before)
};

Segments segments_of(const BeamTrack& beam);

template <typename T>
constexpr T fill_of() {
  return std::numeric_limits<T>::max();
}

// A beam group's attributes, as real granules give them: its strength, ATLAS's spot behind it,
// its name and the spacecraft's orientation.
void write_beam_attributes(Granule& g, const std::string& beam_group, const BeamTrack& beam,
                           std::int8_t sc_orient);

// What the granules' ancillary_data/ and orbit_info/ hold beside Granule::ancillary's, as
// read-ICESat-2's read_granule reads them (each a one-element array): the GPS week and seconds
// of week of the first and last shots, the first and last 20 m segments, the granule's UTC span
// (the data's); the cycle, reference ground track, orbit and region, which a simulation has
// not, as the fill value; orbit_info/{orbit_number, crossing_time, lan}, fill likewise.
void write_ancillary_rest(Granule& g, const std::vector<BeamTrack>& beams);

// Each photon's shot, in the photons' order.
std::vector<std::size_t> shot_of_photons(const BeamTrack& beam);

// The photons as the classification sees them. A shot's background rate becomes a density per
// m along track and m of height: rate * 2 / c photons a metre of height a shot, over the mean
// spacing of the shots.
std::vector<CloudPhoton> cloud_of(const BeamTrack& beam);

}  // namespace glaswave::icesat2
