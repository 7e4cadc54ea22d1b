#include "pipeline/retrieval/retrieve_inputs.hpp"

#include <algorithm>
#include <mutex>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/atl08_reader.hpp"
#include "pipeline/retrieval/gedi_l1b_reader.hpp"
#include "pipeline/retrieval/glas_granule_reader.hpp"

namespace glaswave {

RetrieveInputKind retrieve_input_kind(const std::filesystem::path& file) {
  {
    std::lock_guard lock(netcdf_library_mutex());
    if (!Hdf5Reader::is_hdf5(file)) return RetrieveInputKind::shots_nc;
    const Hdf5Reader reader(file);
    if (reader.has("Data_40HZ/Waveform/RecWaveform/r_rng_wf")) return RetrieveInputKind::glah01;
    if (reader.has("Data_40HZ/Elevation_Surfaces/d_elev")) return RetrieveInputKind::glah14;
  }
  if (is_atl08(file)) return RetrieveInputKind::atl08;
  if (is_gedi_l1b(file)) return RetrieveInputKind::gedi_l1b;
  if (is_gedi_l2a(file)) return RetrieveInputKind::gedi_l2a;
  return RetrieveInputKind::shots_nc;
}

MeasuredShots read_retrieve_inputs(const std::vector<std::filesystem::path>& inputs,
                                   std::optional<std::int64_t> first,
                                   std::optional<std::int64_t> last) {
  // The granules read beside others first: L2A beside L1B, GLAH14 beside GLAH01.
  std::vector<RetrieveInputKind> kinds;
  std::vector<std::pair<std::uint64_t, GediL2aShot>> l2a;
  Glah14Shots glah14;
  bool any_glah14 = false;
  for (const std::filesystem::path& file : inputs) {
    kinds.push_back(retrieve_input_kind(file));
    if (kinds.back() == RetrieveInputKind::gedi_l2a) {
      auto more = read_gedi_l2a(file);
      l2a.insert(l2a.end(), more.begin(), more.end());
    } else if (kinds.back() == RetrieveInputKind::glah14) {
      Glah14Shots more = read_glah14(file);
      glah14.simulated = (!any_glah14 || glah14.simulated) && more.simulated;
      glah14.shots.insert(glah14.shots.end(), more.shots.begin(), more.shots.end());
      any_glah14 = true;
    }
  }
  std::sort(l2a.begin(), l2a.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::sort(glah14.shots.begin(), glah14.shots.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  const auto any = [&](RetrieveInputKind kind) {
    return std::find(kinds.begin(), kinds.end(), kind) != kinds.end();
  };
  MeasuredShots input;
  bool empty = true;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const std::filesystem::path& file = inputs[k];
    MeasuredShots more;
    switch (kinds[k]) {
      case RetrieveInputKind::gedi_l2a:
        if (!any(RetrieveInputKind::gedi_l1b))
          throw input_error(file.string(),
                            "a GEDI L2A granule is read beside its L1B granule: give the L1B too");
        continue;
      case RetrieveInputKind::glah14:
        if (!any(RetrieveInputKind::glah01))
          throw input_error(file.string(),
                            "a GLAH14 granule is read beside its GLAH01 granule: give the GLAH01 "
                            "too");
        continue;
      case RetrieveInputKind::glah01:
        if (!any_glah14)
          throw input_error(file.string(),
                            "a GLAH01 granule does not say where its waveforms lie: give its "
                            "GLAH14 granule beside it");
        more = read_glah01(file, glah14, first, last);
        break;
      case RetrieveInputKind::atl08:
        more = read_atl08(file, first, last);
        break;
      case RetrieveInputKind::gedi_l1b:
        more = read_gedi_l1b(file, l2a, first, last);
        break;
      case RetrieveInputKind::shots_nc:
        more = read_shots(file, first, last);
        break;
    }
    if (empty) {
      input = std::move(more);
      empty = false;
      continue;
    }
    if (more.atl08 != input.atl08)
      throw input_error(file.string(), "ATL08's land segments and waveforms are retrieved apart");
    if (!more.atl08 && (more.band_names != input.band_names || more.bin_ns != input.bin_ns))
      throw input_error(file.string(),
                        "its bands or bins are not those of " + inputs.front().string());
    input.simulated = input.simulated && more.simulated;
    input.gedi_l1b = input.gedi_l1b || more.gedi_l1b;
    for (MeasuredShot& s : more.shots) input.shots.push_back(std::move(s));
  }
  return input;
}

}  // namespace glaswave
