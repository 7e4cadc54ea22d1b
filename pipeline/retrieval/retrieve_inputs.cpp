#include "pipeline/retrieval/retrieve_inputs.hpp"

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string_view>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "core/spawned_reader.hpp"
#include "pipeline/retrieval/atl03_reader.hpp"
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
  if (is_atl03(file)) return RetrieveInputKind::atl03;
  if (is_gedi_l1b(file)) return RetrieveInputKind::gedi_l1b;
  if (is_gedi_l2a(file)) return RetrieveInputKind::gedi_l2a;
  return RetrieveInputKind::shots_nc;
}

namespace {

// The reader program's reply: 'K' when the file was read whole, or 'E' and the error. The hello's
// number changes with the reply's layout.
constexpr std::string_view kHello = "glaswave-read-retrieval-input 1\n";

// `file` read whole by its kind, as retrieve reads it: the reader program's work.
void read_whole(const std::filesystem::path& file) {
  switch (retrieve_input_kind(file)) {
    case RetrieveInputKind::gedi_l1b:
      read_gedi_l1b(file, {}, {}, {});
      break;
    case RetrieveInputKind::gedi_l2a:
      read_gedi_l2a(file);
      break;
    case RetrieveInputKind::glah01:
      read_glah01(file, {}, {}, {});
      break;
    case RetrieveInputKind::glah14:
      read_glah14(file);
      break;
    case RetrieveInputKind::atl08:
      read_atl08(file, {}, {});
      break;
    case RetrieveInputKind::atl03: {
      MeasuredShots none;
      attach_atl03(file, none);
      break;
    }
    case RetrieveInputKind::shots_nc:
      read_shots(file, {}, {});
      break;
  }
}

// `file` read first by the reader program: a file on which HDF5 or libnetcdf crashes, spins or
// allocates without end ends that program (within its CPU budget), not glaswave, and is refused;
// one the program read whole is then read here, where the same libraries do the same on it.
void vet(const std::filesystem::path& file) {
  const std::string path = file.string();
  const std::filesystem::path program =
      find_reader_program("glaswave-read-retrieval-input",
                          {GLASWAVE_RETRIEVAL_READER_BUILT, GLASWAVE_RETRIEVAL_READER_INSTALLED});
  if (program.empty())
    throw run_error(path,
                    "cannot read the input: the program glaswave-read-retrieval-input, which "
                    "reads retrieve's inputs first, is missing from this installation (install "
                    "it as `cmake --install` does, in PREFIX/libexec/glaswave/)");
  SpawnedReader reader(program, {path}, path, "the input", std::string(kHello));
  const std::string reply = reader.receive();
  reader.finish();
  try {
    MessageIn in(reply);
    if (in.get<char>() != 'K') throw in.get_error();
  } catch (const std::length_error&) {
    throw input_error(path, "the input's reader failed reading it (a corrupt file): it is refused");
  }
}

}  // namespace

int retrieval_input_reader_main(int argc, char** argv) {
  const int channel = take_reply_channel();
  if (argc != 2 || channel < 0) return 2;
  bound_request_cpu(argv[1]);
  MessageOut out;
  try {
    read_whole(argv[1]);
    out.put('K');
  } catch (const Error& e) {
    out.put('E');
    out.put_error(e);
  } catch (const std::exception& e) {
    out.put('E');
    out.put_error(input_error(argv[1], std::string("cannot read the input: ") + e.what()));
  }
  return write_hello(channel, kHello) && write_message(channel, out.text()) ? 0 : 2;
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
    vet(file);
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
      case RetrieveInputKind::atl03:
        continue;  // onto the ATL08's segments, below
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
  // ATL03's photons onto the land segments of the one ATL08 given beside it: segment numbers
  // are a granule's own, so that two pairs could not be told apart.
  const auto atl03 = std::find(kinds.begin(), kinds.end(), RetrieveInputKind::atl03);
  if (atl03 != kinds.end()) {
    const std::filesystem::path& file = inputs[static_cast<std::size_t>(atl03 - kinds.begin())];
    const auto count = [&](RetrieveInputKind kind) {
      return std::count(kinds.begin(), kinds.end(), kind);
    };
    if (count(RetrieveInputKind::atl08) != 1)
      throw input_error(file.string(),
                        "an ATL03 granule is read beside the ATL08 granule of its land segments: "
                        "give one ATL08 (and one ATL03) with it");
    if (count(RetrieveInputKind::atl03) > 1)
      throw input_error(file.string(), "one ATL03 granule is read beside one ATL08: give one pair");
    attach_atl03(file, input);
  }
  return input;
}

}  // namespace glaswave
