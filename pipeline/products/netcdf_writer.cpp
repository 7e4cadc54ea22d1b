// shots.nc through the netCDF-C API: the writer's life (the file made, then finished under its
// name or given up, each call under libnetcdf's lock) and its records, each held by chunk until
// the chunk is whole, the photon events appended in record order. The per-shot variables are the
// rows of the product field table (product_fields.hpp): definition, attributes, chunking and
// writing are driven by it, so a new product variable is one row there; netcdf_layout.cpp
// defines them and the variables shared by every shot.
#include "pipeline/products/netcdf_writer.hpp"

#include <sys/resource.h>
#include <sys/statvfs.h>

#include <mutex>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/glas_time.hpp"
#include "core/netcdf_lock.hpp"
#include "core/registry.hpp"
#include "pipeline/products/netcdf_writer_impl.hpp"

namespace glaswave {
namespace {

// Whether writing what HDF5 still holds into `file` could fail: less than this room left on its
// file system (HDF5's caches are tens of megabytes at most), or a file size limit.
bool flush_may_fail(const std::filesystem::path& file) {
  constexpr double kRoomNeeded_B = 1e9;
  struct statvfs fs {};
  if (::statvfs(file.parent_path().empty() ? "." : file.parent_path().c_str(), &fs) != 0)
    return true;
  rlimit limit{};
  const bool limited = ::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY;
  return limited ||
         static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize) < kRoomNeeded_B;
}

// libnetcdf's lock, with HDF5's error printing off in the calling thread (see
// quiet_hdf5_in_this_thread).
class LibraryLock {
 public:
  LibraryLock() : lock_(netcdf_library_mutex()) { quiet_hdf5_in_this_thread(); }

 private:
  std::lock_guard<std::mutex> lock_;
};

}  // namespace

// An unfinished file is given up. Aborting still flushes HDF5's caches, and a flush that
// fails crashes both netCDF-C's close (H5Iget_name from reportopenobjects) and HDF5's own at
// exit (H5F__close_cb). Where a flush could fail (little room left, a file size limit) the
// file is abandoned instead: removed unclosed (the command ends without HDF5's exit handlers).
NetcdfWriter::Impl::~Impl() {
  if (nc.id() >= 0 && flush_may_fail(file.part_path())) nc.abandon();
}

using shots_nc::copy_flat;
using shots_nc::describe_shape;
using shots_nc::has_shape;
using shots_nc::join_shape;

std::string NetcdfWriter::Impl::writing(const char* name, std::size_t index,
                                        const ShotRecord& shot) const {
  return std::string("writing variable '") + name + "' of record " + std::to_string(index) +
         " (shot " + std::to_string(shot.shot_number) + ")";
}

// Every array of the record checked against its variable's shape before anything is held,
// so that a refused record leaves the product as it was. An empty array keeps the fill: a
// flagged shot may carry none.
void NetcdfWriter::Impl::check_shapes(std::size_t index, const ShotRecord& shot) const {
  for (const DefinedVariable& variable : variables) {
    std::visit(
        [&](auto field) {
          const auto& value = shot.*field;
          if constexpr (!std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>) {
            if (value.empty() && shot.quality_flag != quality_good) return;
            if (!has_shape(value, variable.shape)) {
              fail(writing(variable.def->name, index, shot) + ": expected " +
                   join_shape(variable.shape) + " values, got " + describe_shape(value));
            }
          }
        },
        variable.def->field);
  }
  check_ragged(index, shot);
}

// A record's photon events: as many of each ragged field, and none in a run without them.
void NetcdfWriter::Impl::check_ragged(std::size_t index, const ShotRecord& shot) const {
  for (const ProductField& def : product_fields()) {
    if (!def.ragged()) continue;
    const std::size_t n = ragged_size(def, shot), expected = shot.photon_time_ns.size();
    if (!shape.photons && n > 0)
      fail(writing(def.name, index, shot) + ": the run declared no photon events");
    if (n != expected)
      fail(writing(def.name, index, shot) + ": " + std::to_string(n) + " photons, photon_time " +
           std::to_string(expected));
  }
}

std::size_t NetcdfWriter::Impl::ragged_size(const ProductField& def, const ShotRecord& shot) {
  return std::visit(
      [&](auto field) -> std::size_t {
        const auto& value = shot.*field;
        if constexpr (std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>)
          return 0;
        else
          return value.size();
      },
      def.field);
}

// Record `index`'s photon events, appended along `photon` once every record before it has.
void NetcdfWriter::Impl::hold_ragged(std::size_t index, const ShotRecord& shot) {
  RaggedShot& events = waiting[index];
  for (const RaggedVariable& variable : ragged)
    std::visit(
        [&](auto field) {
          const auto& value = shot.*field;
          using T = std::remove_cvref_t<decltype(value)>;
          if constexpr (std::is_same_v<T, std::vector<double>> ||
                        std::is_same_v<T, std::vector<std::int32_t>>)
            events.emplace_back(value.begin(), value.end());
        },
        variable.def->field);
  for (auto next = waiting.find(next_ragged); next != waiting.end();
       next = waiting.find(next_ragged)) {
    put_ragged(next_ragged, next->second);
    waiting.erase(next);
    ++next_ragged;
  }
}

void NetcdfWriter::Impl::put_ragged(std::size_t index, const RaggedShot& events) {
  const std::size_t count = events.empty() ? 0 : events.front().size();
  for (std::size_t i = 0; i < ragged.size() && count > 0; ++i)
    check(nc_put_vara_double(nc.id(), ragged[i].varid, &photons_written, &count, events[i].data()),
          std::string("writing variable '") + ragged[i].def->name + "' of record " +
              std::to_string(index));
  const int n = static_cast<int>(count);
  check(nc_put_var1_int(nc.id(), photon_count, &index, &n),
        "writing variable 'photon_count' of record " + std::to_string(index));
  photons_written += count;
}

// The buffer of the chunk that holds record `index` of variable `i`, begun full of fill.
NetcdfWriter::Impl::ChunkBuffer& NetcdfWriter::Impl::chunk_of(std::size_t i, std::size_t index) {
  const DefinedVariable& variable = variables[i];
  const std::size_t chunk = index / variable.chunk_shots;
  auto [it, begun] = open_chunks[i].try_emplace(chunk);
  ChunkBuffer& buffer = it->second;
  if (begun) {
    buffer.first = chunk * variable.chunk_shots;
    buffer.count = std::min(variable.chunk_shots, shots - buffer.first);
    if (variable.held == Held::int64s) buffer.int64s.assign(buffer.count, 0);
    if (variable.held == Held::bytes) buffer.bytes.assign(buffer.count, 0);
    if (variable.held == Held::reals)
      buffer.reals.assign(buffer.count * variable.per_shot, variable.fill);
  }
  return buffer;
}

// Writes a complete chunk in one call.
void NetcdfWriter::Impl::put_chunk(const DefinedVariable& variable,
                                   const ChunkBuffer& buffer) const {
  std::vector<std::size_t> start(variable.shape.size() + 1, 0);
  std::vector<std::size_t> count = {buffer.count};
  start[0] = buffer.first;
  count.insert(count.end(), variable.shape.begin(), variable.shape.end());
  int status = NC_NOERR;
  const int id = nc.id();
  if (variable.held == Held::int64s)
    status =
        nc_put_vara_longlong(id, variable.varid, start.data(), count.data(), buffer.int64s.data());
  else if (variable.held == Held::bytes)
    status = nc_put_vara_uchar(id, variable.varid, start.data(), count.data(), buffer.bytes.data());
  else
    status =
        nc_put_vara_double(id, variable.varid, start.data(), count.data(), buffer.reals.data());
  check(status, std::string("writing variable '") + variable.def->name + "' of records " +
                    std::to_string(buffer.first) + " to " +
                    std::to_string(buffer.first + buffer.count - 1));
}

// Record `index`'s value of variable `i` into its chunk's buffer; a chunk whose records
// have all come is written.
void NetcdfWriter::Impl::hold_value(std::size_t i, std::size_t index, const ShotRecord& shot) {
  const DefinedVariable& variable = variables[i];
  ChunkBuffer& buffer = chunk_of(i, index);
  const std::size_t slot = index - buffer.first;
  std::visit(
      [&](auto field) {
        const auto& value = shot.*field;
        using T = std::remove_cvref_t<decltype(value)>;
        if constexpr (std::is_same_v<T, std::int64_t>) {
          buffer.int64s[slot] = value;
        } else if constexpr (std::is_same_v<T, std::uint8_t>) {
          buffer.bytes[slot] = value;
        } else if constexpr (std::is_same_v<T, double>) {
          buffer.reals[slot] = value;
        } else if (!value.empty()) {
          copy_flat(value, buffer.reals.data() + slot * variable.per_shot);
        }
      },
      variable.def->field);
  if (++buffer.filled < buffer.count) return;
  put_chunk(variable, buffer);
  open_chunks[i].erase(index / variable.chunk_shots);
}

void NetcdfWriter::Impl::write_record(std::size_t index, const ShotRecord& shot) {
  check_shapes(index, shot);
  broken = true;  // until every value is held: a failed chunk write loses records taken
  for (std::size_t i = 0; i < variables.size(); ++i) hold_value(i, index, shot);
  if (shape.photons) hold_ragged(index, shot);
  broken = false;
  time_s.add(shot.time_s);
  lat_deg.add(shot.lat_deg);
  lon_deg.add(shot.lon_deg);
  elev_m.add(shot.elev_m);
}

void NetcdfWriter::Impl::put_double(const char* name, double value) const {
  check(nc_put_att_double(nc.id(), NC_GLOBAL, name, NC_DOUBLE, 1, &value),
        std::string("global attribute '") + name + "'");
}

// ACDD's time and place of the data, from the records; none where no record has a value.
void NetcdfWriter::Impl::define_coverage() const {
  if (!time_s.empty()) {
    put_text(NC_GLOBAL, "global", "time_coverage_start",
             format_iso8601_utc_microseconds(time_s.min));
    put_text(NC_GLOBAL, "global", "time_coverage_end", format_iso8601_utc_microseconds(time_s.max));
  }
  if (!lat_deg.empty()) {
    put_double("geospatial_lat_min", lat_deg.min);
    put_double("geospatial_lat_max", lat_deg.max);
    put_text(NC_GLOBAL, "global", "geospatial_lat_units", "degrees_north");
  }
  if (!lon_deg.empty()) {
    put_double("geospatial_lon_min", lon_deg.min);
    put_double("geospatial_lon_max", lon_deg.max);
    put_text(NC_GLOBAL, "global", "geospatial_lon_units", "degrees_east");
  }
  if (!elev_m.empty()) {
    put_double("geospatial_vertical_min", elev_m.min);
    put_double("geospatial_vertical_max", elev_m.max);
    put_text(NC_GLOBAL, "global", "geospatial_vertical_units", "m");
    put_text(NC_GLOBAL, "global", "geospatial_vertical_positive", "up");
  }
}

NetcdfWriter::NetcdfWriter(std::filesystem::path final_path, const RunInfo& info)
    : final_path_(std::move(final_path)), impl_(std::make_unique<Impl>(final_path_, info.shots)) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  if (info.bands.empty()) impl.fail("a product needs at least one band");
  if (info.bin_time_ns.empty() || info.tx_time_ns.empty())
    impl.fail("a product needs bins and tx bins");
  if (info.orders < 0) impl.fail("orders must be >= 0, got " + std::to_string(info.orders));
  impl.shots = static_cast<std::size_t>(info.shots);
  impl.shape = {info.bands.size(), info.bin_time_ns.size(), static_cast<std::size_t>(info.orders),
                info.photon_events, info.atmosphere};
  impl.tx_bins = info.tx_time_ns.size();

  const std::string part = impl.file.part_path().string();
  // libnetcdf is called under its lock only: another run in this process (two Python threads)
  // may be writing, or reading a netCDF DEM, meanwhile.
  const LibraryLock lock;
  try {
    impl.check(nc_create(part.c_str(), NC_NETCDF4 | NC_CLOBBER, impl.nc.out()),
               "cannot create " + part);
    impl.define(info);
  } catch (...) {
    impl_.reset();  // the half-defined file is aborted here, still under the lock
    throw;
  }
}

NetcdfWriter::~NetcdfWriter() {
  // An unfinished product's id is aborted as Impl goes: under the library's lock too.
  const LibraryLock lock;
  impl_.reset();
}

NetcdfWriter::Impl& NetcdfWriter::impl() {
  if (!impl_) throw run_error(final_path_.string(), "the product was aborted");
  return *impl_;
}

void NetcdfWriter::write(std::int64_t index, const ShotRecord& shot) {
  const LibraryLock lock;  // a DEM may be read meanwhile
  Impl& impl = this->impl();
  impl.ledger.check_write(index);
  if (impl.broken) impl.fail("a write failed before: the product lacks records");
  impl.write_record(static_cast<std::size_t>(index), shot);
  impl.ledger.taken(index);
}

void NetcdfWriter::finish(const RunStats& stats) {
  const LibraryLock lock;
  Impl& impl = this->impl();
  if (impl.broken && !impl.ledger.finished())
    impl.fail("a write failed before: the product lacks records");
  impl.ledger.check_finish();
  const int id = impl.nc.id();
  impl.check(nc_redef(id), "reopening definitions");
  impl.define_coverage();
  const long long ray_queries = stats.ray_queries;
  const long long shots_flagged = stats.shots_flagged;
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_ray_queries", NC_INT64, 1, &ray_queries),
             "global attribute 'stats_ray_queries'");
  if (!impl.reproducible)
    impl.check(nc_put_att_double(id, NC_GLOBAL, "stats_wall_s", NC_DOUBLE, 1, &stats.wall_s),
               "global attribute 'stats_wall_s'");
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_shots_flagged", NC_INT64, 1, &shots_flagged),
             "global attribute 'stats_shots_flagged'");
  impl.check(nc_enddef(id), "ending definitions");
  // Everything is written before the close: a close whose flush fails crashes in HDF5, a
  // failed sync only says so.
  impl.check(nc_sync(id), "writing " + impl.file.part_path().string());
  impl.check(impl.nc.close(), "closing " + impl.file.part_path().string());
  impl.file.commit();
  impl.ledger.finish();
}

void NetcdfWriter::abort() noexcept {
  // A finished product stays: only an unfinished one has a .part to give up.
  const LibraryLock lock;
  if (impl_ && !impl_->ledger.finished()) impl_.reset();
}

namespace {

// shots.nc, first of a run's products.
const Registration<ProductWriter> netcdf_writer(
    "shots.nc", 10, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.settings.netcdf) return nullptr;
      return std::make_unique<NetcdfWriter>(c.out_dir / "shots.nc", c.info);
    });

}  // namespace

}  // namespace glaswave
