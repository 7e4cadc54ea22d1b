// Fuzzes `glaswave retrieve`'s inputs (pipeline/retrieval/retrieve_inputs.hpp): GEDI L1B and L2A,
// GLAS GLAH01 and GLAH14 and ICESat-2 ATL08 and ATL03 HDF5 files, whole, cut and malformed, through
// read_retrieve_inputs as retrieve calls it: alone, and beside a fixed GLAH14 (so that a GLAH01 is
// read, which is refused alone) or, for an input naming h_ph, a fixed ATL08 (so that an ATL03's
// photons are attached to its segment). Each input is read first by the program
// glaswave-read-retrieval-input, where a crash, a spin or an endless allocation of HDF5 is a
// refusal by design and libFuzzer's coverage does not reach; what that program read whole is then
// read in this process, as retrieve reads it, and searched here. An input Error is a refusal;
// anything else (a crash, a hang, memory beyond the limit) is a finding. library_leaks.supp
// suppresses leaks with a frame inside HDF5; an HDF5 file or object left open traps instead.
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/retrieve_inputs.hpp"
#include "tests/fuzz/fuzz_support.hpp"
#include "tests/pipeline/retrieval/one_segment_atl08.hpp"

namespace {

// A GLAH14 placing the seeds' GLAH01 shots (records 1000 and 1001).
std::filesystem::path companion_glah14() {
  const std::filesystem::path path = glaswave::fuzz::scratch_dir() / "glah14.h5";
  std::lock_guard lock(glaswave::netcdf_library_mutex());
  glaswave::Hdf5Writer f(path);
  const std::string d = "Data_40HZ/";
  f.write(d + "Time/i_rec_ndx", std::vector<std::int32_t>{1000, 1000, 1001});
  f.write(d + "Time/i_shot_count", std::vector<std::int16_t>{1, 2, 40});
  f.write(d + "Geolocation/d_lat", std::vector<double>{1.0, 1.001, 1.002});
  f.write(d + "Geolocation/d_lon", std::vector<double>{358.0, 358.0, 358.0});
  f.write(d + "Elevation_Surfaces/d_elev", std::vector<double>{101.0, 101.0, 101.0});
  f.write(d + "Elevation_Offsets/d_ldRngOff", std::vector<double>{-1.0, -1.0, -1.0});
  f.close();
  return path;
}

// An ATL08 whose land segment (20 m segments 101-105, gt1l) the seeds' ATL03 photons fall in.
std::filesystem::path companion_atl08() {
  const std::filesystem::path path = glaswave::fuzz::scratch_dir() / "atl08.h5";
  std::lock_guard lock(glaswave::netcdf_library_mutex());
  glaswave::test_support::write_one_segment_atl08(path);
  return path;
}

void attempt(const std::vector<std::filesystem::path>& inputs) {
  try {
    glaswave::read_retrieve_inputs(inputs, std::nullopt, std::nullopt);
  } catch (const glaswave::Error& e) {
    glaswave::fuzz::refused(e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path glah14 = companion_glah14(), atl08 = companion_atl08();
  const auto file = glaswave::fuzz::write_input("granule.h5", data, size);
  attempt({file});
  // Its companion by the names its bytes hold (not by HDF5, which reads it first in the reader
  // program): an ATL03 is read beside an ATL08, a GLAH01 beside a GLAH14.
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  attempt({file, bytes.find("h_ph") != std::string_view::npos ? atl08 : glah14});
  // No HDF5 file or object left open, on refusal too: what library_leaks.supp's HDF5 line would
  // otherwise hide.
  if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) __builtin_trap();
  return 0;
}
