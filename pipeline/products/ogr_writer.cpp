// The footprints through GDAL/OGR, so that the GeoJSON and GeoPackage files are those every GIS
// reads: the GeoJSON driver in its RFC 7946 mode (no `crs` member, WGS 84 lon/lat, coordinates
// to 1e-8 degree) and the GPKG driver (EPSG:4326, MultiPolygons, one transaction). The cut at
// the antimeridian and the ring orientation are ours, so both formats get the same geometry.
#include "pipeline/products/ogr_writer.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "core/registry.hpp"
#include "core/write_error.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

// 1e-8 degree is about a millimetre on the ground: finer than any footprint position means.
constexpr const char* kCoordinatePrecision = "COORDINATE_PRECISION=8";

using Ring = std::vector<std::array<double, 2>>;

// RFC 7946 section 3.1.9: a ring that crosses the antimeridian is cut there into two polygons,
// one each side, rather than drawn the long way round the globe. Longitudes are first made
// continuous from the first vertex; a ring that then stays within [-180, 180] is kept whole.
std::vector<Ring> split_at_antimeridian(const Ring& ring) {
  Ring continuous = ring;
  for (std::size_t i = 1; i < continuous.size(); ++i)
    continuous[i][0] = continuous[i - 1][0] + std::remainder(ring[i][0] - ring[i - 1][0], 360.0);
  double west = continuous[0][0], east = west;
  for (const auto& p : continuous) {
    west = std::min(west, p[0]);
    east = std::max(east, p[0]);
  }
  if (west >= -180.0 && east <= 180.0) return {ring};
  const double cut = east > 180.0 ? 180.0 : -180.0;
  // Sutherland-Hodgman against the meridian `cut`, keeping one side and then the other.
  auto clip = [&](bool keep_west) {
    Ring out;
    for (std::size_t i = 0; i + 1 < continuous.size(); ++i) {
      const auto& a = continuous[i];
      const auto& b = continuous[i + 1];
      const bool a_in = keep_west ? a[0] <= cut : a[0] >= cut,
                 b_in = keep_west ? b[0] <= cut : b[0] >= cut;
      if (a_in) out.push_back(a);
      if (a_in != b_in) out.push_back({cut, a[1] + (b[1] - a[1]) * (cut - a[0]) / (b[0] - a[0])});
    }
    if (out.size() >= 3) out.push_back(out.front());
    // Back into [-180, 180]: the part beyond the cut moves by a turn.
    const double shift = (keep_west == (cut > 0.0)) ? 0.0 : (cut > 0.0 ? -360.0 : 360.0);
    for (auto& p : out) p[0] += shift;
    return out;
  };
  std::vector<Ring> parts;
  for (bool keep_west : {true, false}) {
    Ring part = clip(keep_west);
    if (part.size() >= 4) parts.push_back(std::move(part));
  }
  return parts;
}

// Twice the signed area of a closed ring in the lon/lat plane: positive when counter-clockwise.
double twice_signed_area(const Ring& ring) {
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i)
    sum += ring[i][0] * ring[i + 1][1] - ring[i + 1][0] * ring[i][1];
  return sum;
}

// A part as an OGR polygon whose exterior ring is counter-clockwise (RFC 7946 section 3.1.6).
std::unique_ptr<OGRPolygon> make_polygon(Ring part) {
  if (twice_signed_area(part) < 0.0) std::reverse(part.begin(), part.end());
  auto ring = std::make_unique<OGRLinearRing>();
  for (const auto& p : part) ring->addPoint(p[0], p[1]);
  auto polygon = std::make_unique<OGRPolygon>();
  polygon->addRingDirectly(ring.release());
  return polygon;
}

// The OGR type of a product field's properties; OFTMaxType for one that is never a property.
OGRFieldType ogr_type(const ProductField& field) {
  return std::visit(
      [](auto member) {
        using T = std::remove_cvref_t<decltype(std::declval<ShotRecord>().*member)>;
        if constexpr (std::is_same_v<T, std::int64_t>) return OFTInteger64;
        if constexpr (std::is_integral_v<T>) return OFTInteger;
        if constexpr (std::is_same_v<T, std::vector<std::int32_t>>) return OFTInteger;
        if constexpr (std::is_same_v<T, double> || std::is_same_v<T, std::vector<double>> ||
                      std::is_same_v<T, std::vector<std::vector<double>>>)
          return OFTReal;
        return OFTMaxType;  // arrays over orders are never properties
      },
      field.field);
}

// One property column of the layer.
struct Column {
  const ProductField* field;
  GeojsonPropertyName property;
};

void set_real(OGRFeature& feature, int index, double value) {
  if (std::isfinite(value))
    feature.SetField(index, value);
  else
    feature.SetFieldNull(index);  // neither format has NaN: fill reads back as null
}

// Property `index` of `feature` from `shot`; null where the shot has no value (fill).
void set_property(OGRFeature& feature, int index, const ShotRecord& shot, const Column& column) {
  const std::size_t band = column.property.band;
  std::visit(
      [&](auto member) {
        const auto& value = shot.*member;
        using T = std::remove_cvref_t<decltype(value)>;
        if constexpr (std::is_same_v<T, double>) {
          set_real(feature, index, value);
        } else if constexpr (std::is_integral_v<T>) {
          feature.SetField(index, static_cast<GIntBig>(value));
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          set_real(feature, index, band < value.size() ? value[band] : std::nan(""));
        } else if constexpr (std::is_same_v<T, std::vector<std::int32_t>>) {
          if (band < value.size())
            feature.SetField(index, value[band]);
          else
            feature.SetFieldNull(index);
        } else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>>) {
          const auto level = static_cast<std::size_t>(column.property.level);
          const bool known = band < value.size() && level < value[band].size();
          set_real(feature, index, known ? value[band][level] : std::nan(""));
        } else {
          feature.SetFieldNull(index);
        }
      },
      column.field->field);
}

}  // namespace

struct OgrWriter::Impl {
  Impl(std::filesystem::path final_path, std::int64_t shots)
      : file(final_path), ledger(std::move(final_path), shots) {}

  // Features and the dataset go before the .part is removed: the file is closed first, and
  // GDAL's messages about a dataset given up are nobody's business.
  ~Impl() {
    const GdalErrorTrap quiet;
    pending.clear();
    dataset.reset();
  }

  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  AtomicFile file;
  FootprintsFormat format = FootprintsFormat::geojson;
  GDALDatasetUniquePtr dataset;
  OGRLayer* layer = nullptr;  // owned by the dataset
  std::vector<Column> columns;
  RecordLedger ledger;
  std::int64_t next = 0;                                // the next record to go to the file
  std::map<std::int64_t, OGRFeatureUniquePtr> pending;  // records that came before their turn

  [[noreturn]] void fail(const std::string& message) const {
    throw run_error(file.final_path().string(), message);
  }

  void create(const RunInfo& info) {
    prepare_gdal();
    const bool gpkg = format == FootprintsFormat::gpkg;
    // A GeoPackage says when its layer last changed (gpkg_contents.last_change): GDAL takes
    // that time from OGR_CURRENT_DATE where set, so reproducible runs give it theirs (the
    // setting is the process's, as SOURCE_DATE_EPOCH is).
    if (gpkg && info.created.reproducible)
      CPLSetConfigOption("OGR_CURRENT_DATE", info.created.iso8601.c_str());
    const GdalErrorTrap messages;
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(gpkg ? "GPKG" : "GeoJSON");
    if (driver == nullptr)
      fail(std::string("GDAL has no ") + (gpkg ? "GPKG" : "GeoJSON") + " driver");
    const std::string part = file.part_path().string();
    dataset.reset(driver->Create(part.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!dataset) fail(messages.failure("cannot create " + part));

    OGRSpatialReference wgs84;
    wgs84.importFromEPSG(4326);
    wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // lon, lat
    CPLStringList options;
    if (gpkg) {
      options.AddString("DESCRIPTION=glaswave footprints: one per shot, the beam's 1/e^2 contour");
    } else {
      options.AddString("RFC7946=YES");
      options.AddString(kCoordinatePrecision);
    }
    // GeoPackage readers expect one geometry type per layer: every footprint is a MultiPolygon
    // there. GeoJSON keeps a Polygon where the footprint is one piece.
    layer = dataset->CreateLayer("footprints", &wgs84, gpkg ? wkbMultiPolygon : wkbUnknown,
                                 options.List());
    if (layer == nullptr) fail(messages.failure("cannot create the footprints layer in " + part));

    std::vector<std::string> band_names;
    for (const ProductBand& band : info.bands) band_names.push_back(band.name);
    for (const ProductField& field : product_fields()) {
      for (GeojsonPropertyName& property : geojson_properties(field, band_names)) {
        const OGRFieldType type = ogr_type(field);
        if (type == OFTMaxType) continue;
        OGRFieldDefn definition(property.name.c_str(), type);
        if (layer->CreateField(&definition) != OGRERR_NONE)
          fail(messages.failure("cannot create the property " + property.name + " in " + part));
        columns.push_back({&field, std::move(property)});
      }
    }
    if (gpkg && dataset->StartTransaction() != OGRERR_NONE)
      fail(messages.failure("cannot start writing " + part));
  }

  // The footprint as a Polygon (a MultiPolygon where it crosses the antimeridian, and always in
  // a GeoPackage), or null for a shot without one.
  std::unique_ptr<OGRGeometry> geometry(std::int64_t index, const ShotRecord& shot) const {
    const auto& ring = shot.footprint_lonlat;
    if (ring.empty()) return nullptr;
    const std::string place = "footprint ring of record " + std::to_string(index) + " (shot " +
                              std::to_string(shot.shot_number) + ")";
    if (ring.size() < 4 || ring.front() != ring.back()) {
      fail(place + ": a Polygon ring must be closed with at least 4 positions, got " +
           std::to_string(ring.size()));
    }
    for (std::size_t i = 0; i < ring.size(); ++i)
      if (!std::isfinite(ring[i][0]) || !std::isfinite(ring[i][1]))
        fail(place + ": position " + std::to_string(i) + " is not finite");
    std::vector<Ring> parts = split_at_antimeridian(ring);
    if (parts.size() == 1 && format == FootprintsFormat::geojson)
      return make_polygon(std::move(parts.front()));
    auto multi = std::make_unique<OGRMultiPolygon>();
    for (Ring& part : parts) multi->addGeometryDirectly(make_polygon(std::move(part)).release());
    return multi;
  }

  OGRFeatureUniquePtr feature(std::int64_t index, const ShotRecord& shot) const {
    std::unique_ptr<OGRGeometry> shape = geometry(index, shot);
    OGRFeatureUniquePtr result(OGRFeature::CreateFeature(layer->GetLayerDefn()));
    if (shape) result->SetGeometryDirectly(shape.release());
    for (std::size_t k = 0; k < columns.size(); ++k)
      set_property(*result, static_cast<int>(k), shot, columns[k]);
    return result;
  }

  // GDAL buffers its writes and does not always say when one fails: the errno of the write
  // under it does (a full disk). Call with errno cleared before the GDAL call.
  void check_room() const {
    if (no_space(errno)) throw write_error(file.part_path().string(), errno);
  }

  void emit(OGRFeature& feature) {
    const GdalErrorTrap messages;
    errno = 0;
    if (layer->CreateFeature(&feature) != OGRERR_NONE) {
      check_room();
      fail(messages.failure("cannot write record " + std::to_string(next) + " to " +
                            file.part_path().string()));
    }
    check_room();
    ++next;
  }
};

void check_footprint_properties(const std::vector<std::string>& band_names,
                                FootprintsFormat format) {
  if (format != FootprintsFormat::gpkg) return;
  struct Seen {
    std::string name;
    int band;  // -1 for a field of the shot
  };
  std::map<std::string, Seen> seen;  // by the name in lower case
  for (const ProductField& field : product_fields()) {
    for (const GeojsonPropertyName& property : geojson_properties(field, band_names)) {
      std::string folded = property.name;
      std::transform(folded.begin(), folded.end(), folded.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      const int band = field.per_band() ? static_cast<int>(property.band) : -1;
      const auto [it, inserted] = seen.emplace(folded, Seen{property.name, band});
      if (inserted) continue;
      const int later = std::max(band, it->second.band);
      throw config_error(
          later >= 0 ? "/sensor/bands/" + std::to_string(later) + "/name" : "/sensor/bands",
          "the footprint properties " + quoted_excerpt(it->second.name) + " and " +
              quoted_excerpt(property.name) +
              " differ only in case, which a GeoPackage's columns do not tell apart: rename "
              "the band or write GeoJSON (output.footprints_format)");
    }
  }
}

OgrWriter::OgrWriter(std::filesystem::path final_path, FootprintsFormat format, const RunInfo& info)
    : final_path_(std::move(final_path)), impl_(std::make_unique<Impl>(final_path_, info.shots)) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  impl.format = format;
  impl.create(info);
}

OgrWriter::~OgrWriter() = default;

OgrWriter::Impl& OgrWriter::impl() {
  if (!impl_) throw run_error(final_path_.string(), "the product was aborted");
  return *impl_;
}

void OgrWriter::write(std::int64_t index, const ShotRecord& shot) {
  Impl& impl = this->impl();
  impl.ledger.check_write(index);
  OGRFeatureUniquePtr feature = impl.feature(index, shot);
  if (index != impl.next) {
    impl.pending.emplace(index, std::move(feature));
    impl.ledger.taken(index);
    return;
  }
  impl.emit(*feature);  // a record refused here can be written again
  impl.ledger.taken(index);
  for (auto it = impl.pending.begin(); it != impl.pending.end() && it->first == impl.next;) {
    impl.emit(*it->second);
    it = impl.pending.erase(it);
  }
}

void OgrWriter::finish(const RunStats& /*stats*/) {
  Impl& impl = this->impl();
  impl.ledger.check_finish();
  const std::string part = impl.file.part_path().string();
  {
    const GdalErrorTrap messages;
    errno = 0;
    if (impl.format == FootprintsFormat::gpkg && impl.dataset->CommitTransaction() != OGRERR_NONE) {
      impl.check_room();
      impl.fail(messages.failure("cannot write " + part));
    }
    // Closing writes what GDAL still holds: a full disk shows up here.
    impl.layer = nullptr;
    impl.dataset.reset();
    impl.check_room();
    if (messages.failed()) impl.fail(messages.failure("cannot write " + part));
  }
  impl.file.commit();
  impl.ledger.finish();
}

void OgrWriter::abort() noexcept {
  // A finished product stays: only an unfinished one has a .part to give up.
  if (impl_ && !impl_->ledger.finished()) impl_.reset();
}

namespace {

const Registration<ProductWriter> footprints_writer(
    "footprints", 20, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.settings.footprints) return nullptr;
      const bool gpkg = c.settings.footprints_format == FootprintsFormat::gpkg;
      return std::make_unique<OgrWriter>(
          c.out_dir / (gpkg ? "footprints.gpkg" : "footprints.geojson"),
          c.settings.footprints_format, c.info);
    });

}  // namespace

}  // namespace glaswave
