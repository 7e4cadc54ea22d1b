// PROJ behind a small RAII layer: one prototype operation, cloned per borrowing thread.
#include "terrain/crs_transform.hpp"

#include <proj.h>
#include <proj_experimental.h>

#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "core/error.hpp"
#include "core/excerpt.hpp"

namespace glaswave {
namespace {

struct ContextDeleter {
  void operator()(PJ_CONTEXT* context) const { proj_context_destroy(context); }
};
struct PjDeleter {
  void operator()(PJ* object) const { proj_destroy(object); }
};
using ContextPtr = std::unique_ptr<PJ_CONTEXT, ContextDeleter>;
using PjPtr = std::unique_ptr<PJ, PjDeleter>;

// A context that keeps PROJ quiet: its messages would reach the user's terminal.
ContextPtr quiet_context() {
  ContextPtr context(proj_context_create());
  proj_log_level(context.get(), PJ_LOG_NONE);
  return context;
}

std::string proj_message(PJ_CONTEXT* context) {
  const int code = proj_context_errno(context);
  const char* text = code ? proj_context_errno_string(context, code) : nullptr;
  return text ? text : "no reason given";
}

// "EPSG:5773", or the CRS's name when it has no identifier.
std::string identifier(const PJ* crs) {
  const char* authority = proj_get_id_auth_name(crs, 0);
  const char* code = proj_get_id_code(crs, 0);
  if (authority && code) return std::string(authority) + ":" + code;
  const char* name = proj_get_name(crs);
  return name ? name : "unnamed vertical CRS";
}

std::string name_of(const PJ* crs) {
  const char* name = proj_get_name(crs);
  return name ? name : "unnamed";
}

// "WGS 84": the name of a CRS's ellipsoid.
std::string ellipsoid_name(PJ_CONTEXT* context, const PJ* crs) {
  const PjPtr ellipsoid(proj_get_ellipsoid(context, crs));
  return ellipsoid ? name_of(ellipsoid.get()) : "unnamed";
}

// The CRS under a bound CRS (WKT1's TOWGS84 wraps one).
PjPtr unbound(PJ_CONTEXT* context, const PJ* crs) {
  if (proj_get_type(crs) == PJ_TYPE_BOUND_CRS) return PjPtr(proj_get_source_crs(context, crs));
  return PjPtr(proj_clone(context, crs));
}

// A pooled operation with its own context.
struct Worker {
  ContextPtr context;
  PjPtr operation;
};

}  // namespace

struct CrsTransform::Impl {
  ContextPtr context;  // of the prototype; used under `mutex` only
  PjPtr prototype;     // normalised operation: (easting, northing, height) -> (lon, lat, h)
  bool geographic = false;
  VerticalDatum datum;
  std::mutex mutex;
  std::vector<std::unique_ptr<Worker>> idle;

  // A worker for the calling thread, returned to the pool when the lease ends.
  class Lease {
   public:
    explicit Lease(Impl& impl) : impl_(impl) {
      std::lock_guard lock(impl_.mutex);
      if (!impl_.idle.empty()) {
        worker_ = std::move(impl_.idle.back());
        impl_.idle.pop_back();
      } else {
        worker_ = std::make_unique<Worker>();
        worker_->context = quiet_context();
        worker_->operation.reset(proj_clone(worker_->context.get(), impl_.prototype.get()));
        if (!worker_->operation) throw run_error("PROJ", "cannot copy a coordinate operation");
      }
    }
    ~Lease() {
      std::lock_guard lock(impl_.mutex);
      impl_.idle.push_back(std::move(worker_));
    }
    PJ* operation() const { return worker_->operation.get(); }

   private:
    Impl& impl_;
    std::unique_ptr<Worker> worker_;
  };
};

namespace {

// A raster's CRS taken apart: the horizontal part decides the units of x and y; the vertical
// part, where heights are from.
struct CrsParts {
  PjPtr crs, horizontal, vertical;  // vertical: the CRS's own, else the configuration's, if any
  bool compound = false;
  bool three_d = false;
  bool geographic = false;
};

CrsParts read_crs(PJ_CONTEXT* context, const std::string& crs_wkt, const std::string& place) {
  CrsParts parts;
  parts.crs.reset(proj_create(context, crs_wkt.c_str()));
  if (!parts.crs)
    throw input_error(place,
                      "PROJ cannot read its coordinate reference system: " + proj_message(context));
  const PJ* crs = parts.crs.get();
  parts.horizontal = unbound(context, crs);
  parts.compound = proj_get_type(crs) == PJ_TYPE_COMPOUND_CRS;
  if (parts.compound) {
    const PjPtr first(proj_crs_get_sub_crs(context, crs, 0));
    parts.vertical.reset(proj_crs_get_sub_crs(context, crs, 1));
    if (!first || !parts.vertical) throw input_error(place, "PROJ cannot split its compound CRS");
    parts.horizontal = unbound(context, first.get());
  }
  const PJ_TYPE type = proj_get_type(parts.horizontal.get());
  parts.geographic = type == PJ_TYPE_GEOGRAPHIC_2D_CRS || type == PJ_TYPE_GEOGRAPHIC_3D_CRS;
  if (!parts.geographic && type != PJ_TYPE_PROJECTED_CRS)
    throw input_error(place, "its CRS (" + name_of(parts.horizontal.get()) +
                                 ") is neither geographic nor projected");
  const PjPtr coordinate_system(proj_crs_get_coordinate_system(context, parts.horizontal.get()));
  parts.three_d =
      coordinate_system && proj_cs_get_axis_count(context, coordinate_system.get()) == 3;
  return parts;
}

// The CRS the raster's (x, y, height) are in, with the datum of its heights: its own vertical
// CRS, its 3-D CRS, or the configuration's vertical datum (which then becomes `parts.vertical`).
PjPtr source_crs(PJ_CONTEXT* context, CrsParts& parts, const std::string& vertical_datum,
                 const std::string& place, VerticalDatum& datum) {
  const PJ* crs = parts.crs.get();
  if (parts.compound) {
    const PJ* vertical = parts.vertical.get();
    datum = {identifier(vertical), "DEM heights in " + name_of(vertical) + " (" +
                                       identifier(vertical) + "), the DEM's own vertical CRS"};
    return PjPtr(proj_clone(context, crs));
  }
  if (parts.three_d) {
    // A 3-D CRS holds ellipsoidal heights by definition.
    datum = {"ellipsoid", "DEM heights above the " + ellipsoid_name(context, crs) +
                              " ellipsoid, by the DEM's 3-D CRS"};
    return PjPtr(proj_clone(context, crs));
  }
  if (vertical_datum == "ellipsoid") {
    PjPtr source(proj_crs_promote_to_3D(context, nullptr, crs));
    if (!source)
      throw input_error(place, "PROJ cannot give its CRS heights: " + proj_message(context));
    datum = {"ellipsoid", "DEM heights above the " + ellipsoid_name(context, crs) +
                              " ellipsoid, from terrain.vertical_datum"};
    return source;
  }
  const std::string definition = vertical_datum == "egm96" ? "EPSG:5773" : vertical_datum;
  parts.vertical.reset(proj_create(context, definition.c_str()));
  const PJ* vertical = parts.vertical.get();
  if (!vertical || proj_get_type(vertical) != PJ_TYPE_VERTICAL_CRS)
    throw setting_error(ErrorKind::config, "vertical_datum",
                        "must be \"ellipsoid\", \"egm96\" or a vertical CRS PROJ knows, got " +
                            quoted_excerpt(vertical_datum));
  PjPtr source(proj_create_compound_crs(context, (name_of(crs) + " + " + name_of(vertical)).c_str(),
                                        parts.crs.get(), parts.vertical.get()));
  if (!source)
    throw input_error(
        place, "PROJ cannot combine its CRS with " + definition + ": " + proj_message(context));
  datum = {vertical_datum, "DEM heights in " + name_of(vertical) + " (" + identifier(vertical) +
                               "), from terrain.vertical_datum"};
  return source;
}

// The user's terrain.vertical_datum against the raster's own heights (a vertical CRS, or a 3-D
// CRS's ellipsoidal heights): the same datum is fine, another one a configuration error.
void refuse_conflicting_datum(PJ_CONTEXT* context, const CrsParts& parts,
                              const std::string& vertical_datum, const std::string& place) {
  if (!parts.compound && !parts.three_d) return;
  std::string own;
  if (parts.compound) {
    const PJ* vertical = parts.vertical.get();
    if (vertical_datum != "ellipsoid") {
      const std::string definition = vertical_datum == "egm96" ? "EPSG:5773" : vertical_datum;
      const PjPtr given(proj_create(context, definition.c_str()));
      if (given && proj_is_equivalent_to(given.get(), vertical, PJ_COMP_EQUIVALENT)) return;
    }
    own = "its own vertical CRS, " + name_of(vertical) + " (" + identifier(vertical) + ")";
  } else {
    if (vertical_datum == "ellipsoid") return;
    own = "a 3-D CRS, whose heights are above its ellipsoid";
  }
  throw setting_error(ErrorKind::config, "vertical_datum",
                      "is \"" + vertical_datum + "\", but the DEM " + place + " has " + own +
                          ": remove terrain.vertical_datum to use the DEM's, or give the DEM's "
                          "(glaswave does not override a DEM's own datum)");
}

// The operation from the source CRS to WGS84 longitude, latitude and ellipsoidal height, axes in
// that order.
PjPtr operation_to_wgs84(PJ_CONTEXT* context, const PJ* source, const CrsParts& parts,
                         const std::string& place) {
  const PjPtr target(proj_create(context, "EPSG:4979"));  // WGS 84, 3-D
  if (!target)
    throw run_error("PROJ", "cannot find EPSG:4979 in its database: " + proj_message(context));
  // No ballpark: a geoid grid PROJ cannot find must be an error, not heights off by tens of
  // metres. Without a vertical CRS a ballpark datum shift is better than nothing.
  const char* const strict[] = {"ALLOW_BALLPARK=NO", nullptr};
  PjPtr operation(proj_create_crs_to_crs_from_pj(context, source, target.get(), nullptr, strict));
  if (!operation && !parts.vertical)
    operation.reset(
        proj_create_crs_to_crs_from_pj(context, source, target.get(), nullptr, nullptr));
  if (!operation) {
    const PJ* vertical = parts.vertical.get();
    const std::string from = vertical ? name_of(vertical) + " (" + identifier(vertical) + ")"
                                      : "its CRS (" + name_of(parts.crs.get()) + ")";
    throw input_error(
        place, "PROJ has no transformation from " + from +
                   " to WGS84 ellipsoidal heights; is the grid it needs installed (proj-data)?");
  }
  PjPtr normalised(proj_normalize_for_visualization(context, operation.get()));
  if (!normalised) throw input_error(place, "PROJ cannot order its axes: " + proj_message(context));
  return normalised;
}

}  // namespace

CrsTransform::CrsTransform(const std::string& crs_wkt, const std::string& vertical_datum,
                           const std::string& place, bool vertical_datum_given)
    : impl_(std::make_unique<Impl>()) {
  impl_->context = quiet_context();
  PJ_CONTEXT* context = impl_->context.get();
  CrsParts parts = read_crs(context, crs_wkt, place);
  if (vertical_datum_given) refuse_conflicting_datum(context, parts, vertical_datum, place);
  impl_->geographic = parts.geographic;
  const PjPtr source = source_crs(context, parts, vertical_datum, place, impl_->datum);
  impl_->prototype = operation_to_wgs84(context, source.get(), parts, place);
}

CrsTransform::~CrsTransform() = default;

void CrsTransform::to_wgs84(std::size_t count, double* x, double* y, double* z) const {
  if (count == 0) return;
  const Impl::Lease lease(*impl_);
  proj_trans_generic(lease.operation(), PJ_FWD, x, sizeof(double), count, y, sizeof(double), count,
                     z, sizeof(double), count, nullptr, 0, 0);
  // PROJ marks what it cannot transform with HUGE_VAL.
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i]))
      x[i] = y[i] = z[i] = std::numeric_limits<double>::quiet_NaN();
  }
}

std::array<double, 2> CrsTransform::from_wgs84(double lon_deg, double lat_deg) const {
  const Impl::Lease lease(*impl_);
  const PJ_COORD out =
      proj_trans(lease.operation(), PJ_INV, proj_coord(lon_deg, lat_deg, 0.0, 0.0));
  if (!std::isfinite(out.xyz.x) || !std::isfinite(out.xyz.y))
    return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  return {out.xyz.x, out.xyz.y};
}

bool CrsTransform::geographic() const { return impl_->geographic; }

const VerticalDatum& CrsTransform::vertical_datum() const { return impl_->datum; }

}  // namespace glaswave
