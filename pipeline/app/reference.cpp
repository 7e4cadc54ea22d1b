// The product field table as JSON, for the manual's product reference (scripts/docs-reference).
#include "pipeline/app/reference.hpp"

#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

const char* type_name(StorageType type) {
  switch (type) {
    case StorageType::int64:
      return "int64";
    case StorageType::uint8:
      return "uint8";
    case StorageType::int32:
      return "int32";
    case StorageType::float32:
      return "float32";
    case StorageType::float64:
      return "float64";
  }
  return "";
}

const char* source_name(FieldSource source) {
  switch (source) {
    case FieldSource::shot:
      return "shot";
    case FieldSource::geolocation:
      return "geolocation";
    case FieldSource::simulation:
      return "simulation";
    case FieldSource::metrics:
      return "metrics";
    case FieldSource::truth:
      return "truth";
  }
  return "";
}

const char* geojson_name(GeojsonProperty property) {
  switch (property) {
    case GeojsonProperty::none:
      return "none";
    case GeojsonProperty::value:
      return "value";
    case GeojsonProperty::levels:
      return "levels";
  }
  return "";
}

// An optional text of the table: null where the row has none.
nlohmann::json text(const char* value) { return value ? nlohmann::json(value) : nlohmann::json(); }

}  // namespace

nlohmann::json product_fields_json() {
  nlohmann::json rows = nlohmann::json::array();
  for (const ProductField& field : product_fields()) {
    nlohmann::json dims = {field.ragged() ? "photon" : "shot"};
    if (field.per_band()) dims.push_back("band");
    for (const char* dim : field.inner_dims)
      if (dim && !field.ragged()) dims.push_back(dim);
    rows.push_back({{"name", field.name},
                    {"type", type_name(field.type)},
                    {"dims", dims},
                    {"units", text(field.units)},
                    {"long_name", text(field.long_name)},
                    {"standard_name", text(field.standard_name)},
                    {"comment", text(field.comment)},
                    {"gedi_name", text(field.gedi_name)},
                    {"glas_name", text(field.glas_name)},
                    {"source", source_name(field.source)},
                    {"geojson", geojson_name(field.geojson)}});
  }
  return rows;
}

}  // namespace glaswave
