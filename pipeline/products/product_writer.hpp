// The one interface every product writer implements (shots.nc, footprints.geojson or .gpkg,
// the HDF5 granules), and make_writers, which makes a run's writers from the registered ones. A
// writer begins when it is made (from its final path and the RunInfo), takes records by index, then
// finishes or is aborted; its product appears under its final name only when finish() succeeds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/part_switch.hpp"
#include "pipeline/products/icesat2_products.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

struct WriterContext;

class ProductWriter {
 public:
  // Makes the writer a run's settings ask for, begun; null when they ask for none of its kind.
  // Each writer registers its Factory from its own .cpp (core/registry.hpp).
  using Factory = std::function<std::unique_ptr<ProductWriter>(const WriterContext&)>;

  virtual ~ProductWriter() = default;

  // Writes record `index` (0 <= index < RunInfo::shots), each index exactly once, in any order.
  // Not thread-safe: calls must come one at a time. Throws Error (run) on a bad record or a
  // failed write; a refused record can be written again.
  virtual void write(std::int64_t index, const ShotRecord& shot) = 0;

  // Completes the product and moves it to its final name. Throws Error (run) if a record was
  // never written or the file cannot be completed.
  virtual void finish(const RunStats& stats) = 0;

  // Gives the product up: the file is closed without being flushed and its .part removed.
  // Nothing is written after it; destroying an unfinished writer does the same.
  virtual void abort() noexcept = 0;
};

// The checks every writer makes of the calls it gets, as ProductWriter promises them: each
// record index within the run and taken once, none after finish(), finish() once and only with
// every record written. Errors are Error (run) at the product's final path.
class RecordLedger {
 public:
  RecordLedger(std::filesystem::path product, std::int64_t shots);

  std::int64_t shots() const { return static_cast<std::int64_t>(written_.size()); }
  bool finished() const { return finished_; }

  // Before record `index` is taken; then, once it is, taken(index).
  void check_write(std::int64_t index) const;
  void taken(std::int64_t index) { written_[static_cast<std::size_t>(index)] = true; }
  // Before the product is completed; then, once it is, finish().
  void check_finish() const;
  void finish() { finished_ = true; }

 private:
  [[noreturn]] void fail(const std::string& message) const;

  std::filesystem::path product_;
  std::vector<bool> written_;
  bool finished_ = false;
};

// The footprints' format: DIR/footprints.geojson (RFC 7946) or DIR/footprints.gpkg.
enum class FootprintsFormat : std::uint8_t { geojson, gpkg };

// Which products a run writes (the engine fills it from the configuration's `output`).
struct ProductSettings {
  bool netcdf = true;      // DIR/shots.nc
  bool footprints = true;  // DIR/footprints.geojson or DIR/footprints.gpkg
  FootprintsFormat footprints_format = FootprintsFormat::geojson;
  // The GLAS granules' heights on the TOPEX/Poseidon ellipsoid, not WGS84 (PRODUCT.md section 10,
  // docs/granules.md).
  bool glas_topex = false;
  // The switches writers declare in their own files (core/part_switch.hpp), as the configuration's
  // `output` set them: DIR/gedi_l1b.h5, DIR/gedi_l2a.h5, DIR/glah01.h5, DIR/glah14.h5 and a new
  // writer's.
  PartSwitches switches{};
  // GLAH14's elv_cloud_flg: with an `atmosphere` section, the layers its layer finder reports
  // at the band nearest 1064 nm (maybe none); without, absent.
  std::optional<std::vector<CloudLayer>> glas_cloud_layers{};
};

// What a writer's Factory is given: the run's output directory (which exists), the products it
// asks for and what every shot shares.
struct WriterContext {
  const std::filesystem::path& out_dir;
  const ProductSettings& settings;
  const RunInfo& info;
  const Icesat2ProductSettings& icesat2;
};

// The writers of a run, each begun under `out_dir` (which must exist): every registered writer
// (Registry<ProductWriter>) that `settings` ask for, in the registry's order. Empty when they ask
// for nothing. Throws Error (run) when a product cannot be created.
std::vector<std::unique_ptr<ProductWriter>> make_writers(
    const std::filesystem::path& out_dir, const ProductSettings& settings, const RunInfo& info,
    const Icesat2ProductSettings& icesat2 = {});

}  // namespace glaswave
