// _glaswave, the C++ half of the Python module: the engine run into a directory, brf, and check,
// with glaswave's errors raised as Python exceptions of a fitting class. glaswave/__init__.py is
// the face users see; it reads the products back into an xarray.Dataset.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/engine/brf.hpp"
#include "pipeline/engine/run.hpp"
#include "pipeline/products/netcdf_writer.hpp"

namespace py = pybind11;

namespace glaswave {
namespace {

// A run abandoned because Python's signal handler raised (Ctrl-C): the exception stays set in
// the interpreter and is raised once the engine has unwound and removed its parts.
struct Interrupted {};

// The exception classes, owned by the module (kept alive as its attributes).
PyObject* config_error_type = nullptr;
PyObject* input_error_type = nullptr;
PyObject* run_error_type = nullptr;

// A configuration file, or a JSON document whose relative paths are taken from `folder`.
Config load(const std::optional<std::string>& path, const std::optional<std::string>& document,
            const std::string& folder, const std::vector<std::string>& overrides) {
  if (path) return load_config(*path, overrides);
  nlohmann::json parsed;
  try {
    // Checked as a file is: nesting and duplicate keys refused before anything recurses.
    parsed = parse_json_checked(document.value_or("null"));
  } catch (const nlohmann::json::exception& e) {
    throw config_error("", std::string("not a JSON document: ") + e.what());
  }
  return load_config_document(std::move(parsed), folder, overrides);
}

py::dict run(const std::optional<std::string>& path, const std::optional<std::string>& document,
             const std::string& folder, const std::vector<std::string>& overrides,
             const std::string& out_dir, int threads, std::optional<std::int64_t> first_shot,
             std::optional<std::int64_t> last_shot, const std::string& command_line) {
  RunSummary summary;
  try {
    py::gil_scoped_release release;
    Config config = load(path, document, folder, overrides);
    // Python reads shots.nc back; the configuration written into it stays the user's.
    config.output.netcdf = true;
    config.output.footprints = false;
    config.output.plots = false;
    RunRequest request;
    request.out_dir = out_dir;
    request.threads = threads;
    request.first_shot = first_shot;
    request.last_shot = last_shot;
    request.command_line = command_line;
    // Between batches: Python's signal handlers run here, and one that raises stops the run.
    const ProgressCallback progress = [](std::int64_t, std::int64_t) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) throw Interrupted{};
    };
    summary = run_simulation(config, request, progress);
  } catch (const Interrupted&) {
    throw py::error_already_set();  // the GIL is held again: raise what the handler raised
  }
  py::dict result;
  result["shots"] = summary.shots;
  result["shots_flagged"] = summary.shots_flagged;
  result["ray_queries"] = summary.ray_queries;
  result["wall_s"] = summary.wall_s;
  result["vertical_datum"] = summary.vertical_datum;
  result["warnings"] = summary.warnings;
  return result;
}

// `glaswave brf` without its products: brf.json's document as JSON text.
std::string brf(const std::optional<std::string>& path, const std::optional<std::string>& document,
                const std::string& folder, const std::vector<std::string>& overrides, int threads) {
  try {
    py::gil_scoped_release release;
    const Config config = load(path, document, folder, overrides);
    BrfRequest request;
    request.threads = threads;
    const ProgressCallback progress = [](std::int64_t, std::int64_t) {
      py::gil_scoped_acquire acquire;
      if (PyErr_CheckSignals() != 0) throw Interrupted{};
    };
    return run_brf(config, request, progress).document.dump();
  } catch (const Interrupted&) {
    throw py::error_already_set();
  }
}

py::dict check(const std::optional<std::string>& path, const std::optional<std::string>& document,
               const std::string& folder, const std::vector<std::string>& overrides) {
  CheckSummary summary;
  {
    py::gil_scoped_release release;
    summary = check_inputs(load(path, document, folder, overrides));
  }
  py::dict result;
  result["shots"] = summary.shots;
  result["sequence_length"] = summary.sequence_length;
  result["shots_off_terrain"] = summary.shots_off_terrain;
  result["warnings"] = summary.warnings;
  return result;
}

// libnetcdf's lock (core/netcdf_lock.hpp) for Python's own netCDF reads (netCDF4-python, under
// xarray, calls the same libnetcdf and HDF5 with the GIL released). Waited for without the GIL:
// a run holding the lock never takes the GIL while it does.
class NetcdfLock {
 public:
  void enter() {
    py::gil_scoped_release release;
    lock_ = std::unique_lock(netcdf_library_mutex());
    quiet_hdf5_in_this_thread();  // netCDF4-python's reads print HDF5's probes otherwise
  }
  void exit(const py::args&) {
    if (lock_.owns_lock()) lock_.unlock();
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

PyObject* add_exception(py::module_& m, const char* name, PyObject* base, const char* doc) {
  const std::string qualified = std::string("glaswave.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // the module holds one reference, this file another
  return type;
}

}  // namespace
}  // namespace glaswave

PYBIND11_MODULE(_glaswave, m) {
  using namespace glaswave;
  m.doc() = "glaswave's engine (use the glaswave package, which wraps it)";
  m.attr("__version__") = GLASWAVE_VERSION;
  m.attr("max_json_depth") = max_json_depth;  // the package checks a dict's depth before json
  config_error_type = add_exception(
      m, "ConfigError", PyExc_ValueError,
      "A bad configuration or argument; the message names the key as a JSON path "
      "(\"/canopy/pai: must be >= 0, got -1\"). The command line exits with status 2.");
  input_error_type = add_exception(
      m, "InputError", PyExc_ValueError,
      "Unusable input data (DEM, track, stands file), named by its path. The command line exits "
      "with status 3.");
  run_error_type = add_exception(
      m, "RunError", PyExc_RuntimeError,
      "A failure while running (a full disk...). The command line exits with status 4.");

  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& e) {
      PyObject* type = e.kind() == ErrorKind::config  ? config_error_type
                       : e.kind() == ErrorKind::input ? input_error_type
                                                      : run_error_type;
      py::object error = py::reinterpret_borrow<py::object>(type)(e.what());
      error.attr("place") = e.place();
      error.attr("reason") = e.message();
      PyErr_SetObject(type, error.ptr());
    }
  });

  using py::arg;
  m.def("run", &run, arg("path"), arg("document"), arg("folder"), arg("overrides"), arg("out_dir"),
        arg("threads"), arg("first_shot"), arg("last_shot"), arg("command_line"),
        "Runs the engine and writes shots.nc under out_dir (which must not exist); returns the "
        "run's summary.");
  m.def("brf", &brf, arg("path"), arg("document"), arg("folder"), arg("overrides"), arg("threads"),
        "Runs `glaswave brf` without writing its products; returns brf.json's text.");
  py::class_<NetcdfLock>(m, "netcdf_lock",
                         "A context manager holding the engine's libnetcdf/HDF5 lock (for reading "
                         "its products with netCDF4-python while another thread runs).")
      .def(py::init<>())
      .def("__enter__", &NetcdfLock::enter)
      .def("__exit__", &NetcdfLock::exit);
  m.def("check", &check, arg("path"), arg("document"), arg("folder"), arg("overrides"),
        "Loads the configuration and opens its inputs, simulating nothing; returns what it found.");
}
