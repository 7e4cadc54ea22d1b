// What the manual's generated reference pages are made from, as the program itself knows it:
// the product field table as JSON (`glaswave check --fields-json`, hidden), read by
// scripts/docs-reference, so that the pages follow the code rather than a parse of its text.
#pragma once

#include <nlohmann/json.hpp>

namespace glaswave {

// Every row of product_fields(), in shots.nc's order: name, storage type, dimensions (shot,
// band for a per-band field, then its inner ones), units, long_name, standard_name, comment,
// gedi_name, glas_name, where its value comes from and how it appears in the footprints.
nlohmann::json product_fields_json();

}  // namespace glaswave
