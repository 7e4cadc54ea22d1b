// The keys of what the commands write: `output` (and the switches its writers declare),
// `brf` and `table`.
#include "core/part_switch.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/key_fields.hpp"

namespace glaswave::section_keys {

using nlohmann::json;
using namespace declare;

// `section` with the switches parts declare in it (core/part_switch.hpp) after its own keys;
// its reader reads them into its settings' `switches`.
Key with_part_switches(Key section) {
  for (const auto& entry : Registry<PartSwitch>::instance().entries())
    if (entry.make.section == section.name)
      section.children.push_back(
          declare::boolean(entry.name, entry.make.fallback, entry.make.description));
  return section;
}

Key output_keys() {
  const Fields<OutputSettings> o;
  const Fields<RamiLidarSettings> r;
  using S = OutputSettings;
  const std::string photon_counting = "true with `sensor.receiver: photon_counting`, else false";
  return object(
      "output", "which products to write; at least one of `netcdf`, `footprints` and a granule",
      {o.boolean("netcdf", &S::netcdf, "write `shots.nc`"),
       o.boolean("footprints", &S::footprints,
                 "write the footprints' layer (`footprints.geojson`, or `footprints.gpkg` as "
                 "`footprints_format` says)"),
       declare::boolean("geojson", true,
                        "the old name of `footprints`: it still works, with a warning; not beside "
                        "`footprints`")
           .with_default(nullptr)
           .with_default_text("`footprints`"),
       o.boolean("plots", &S::plots,
                 "PNG plots (drawn from both products: needs `netcdf` and `footprints`)"),
       o.boolean("per_order", &S::per_order, "per-scattering-order waveforms"),
       o.boolean("metrics", &S::metrics,
                 "the waveform metrics and Gaussian decomposition (`energy_tr` ... `rh`); "
                 "false skips them, leaving them fill (`n_peaks` 0): shots are then not "
                 "flagged no or low signal, a detected waveform's `reflectance` is fill, "
                 "and `plots` is refused"),
       o.choice("footprints_format", &S::footprints_format, {"GeoJSON", "GPKG"},
                "the footprints' format: `footprints.geojson`, or `footprints.gpkg` "
                "(GeoPackage)"),
       o.choice("glas_ellipsoid", &S::glas_ellipsoid, {"wgs84", "topex"},
                "the GLAS granules' heights: on WGS84, or on GLAS's TOPEX/Poseidon "
                "ellipsoid (`Geophysical/d_deltaEllip` is WGS84 less T/P height)"),
       o.boolean("atl03", &S::atl03, "the ATL03-like photons `atl03.h5` (photon counting)",
                 photon_counting),
       o.boolean("atl08", &S::atl08, "the ATL08-like land segments `atl08.h5` (photon counting)",
                 photon_counting),
       o.object(
           "rami", &S::rami,
           "RAMI-IV's lidar measurements in ROMC's format, the return binned by height from the "
           "ground up, written to `DIR/rami/` (docs/guide/rami.md); absent: none",
           {r.string_array("measurements", &RamiLidarSettings::measurements,
                           "ROMC's measurement identifiers: `lidar_sgl_co` (light scattered "
                           "once: needs `per_order`) and `lidar_tot` (all of it)"),
            r.string("experiment", &RamiLidarSettings::experiment,
                     "ROMC's experiment identifier; `{band}` is replaced by the band's name, as "
                     "it must be with more than one band")
                .with_required(),
            r.string("model", &RamiLidarSettings::model,
                     "ROMC's model identifier: 1 to 10 letters and digits")
                .with_default("glaswave"),
            r.number("height_bin_m", &RamiLidarSettings::height_bin_m, open_closed(0, 1000), "m",
                     "the files' height interval: a whole number of the window's bins "
                     "(c `bin_ns` / 2 each)")})});
}

Key brf_keys() {
  const Fields<BrfSettings> b;
  const Fields<BrfView> v;
  const Fields<BrfRamiSettings> r;
  const BrfView view;
  using S = BrfSettings;
  return object(
      "brf", "`glaswave brf` (FLIGHT's solar mode)",
      {b.number("sun_zenith_deg", &S::sun_zenith_deg, half_open(0, 90), "deg", "sun zenith angle"),
       b.number("sun_azimuth_deg", &S::sun_azimuth_deg, any_finite(), "deg", "sun azimuth"),
       b.object_array(
            "views", &S::views,
            json::array({{{"zenith_deg", view.zenith_deg}, {"azimuth_deg", view.azimuth_deg}}}),
            "the view directions of the reflectance",
            {v.number("zenith_deg", &BrfView::zenith_deg, half_open(0, 90), "deg",
                      "view zenith angle"),
             v.number("azimuth_deg", &BrfView::azimuth_deg, any_finite(), "deg", "view azimuth")})
           .with_items(1, std::numeric_limits<std::size_t>::max()),
       b.integer("photons", &S::photons, 1, run_limits::rays_per_shot, "",
                 "photons traced from the sun"),
       b.number("image_resolution_m", &S::image_resolution_m, above(0), "m",
                "pixel size of `scene.tif`"),
       b.number("scene_size_m", &S::scene_size_m, open_closed(0, run_limits::brf_scene_m), "m",
                "side of the square scene around the track's first footprint that the sun "
                "lights (periodic over a synthetic plane); rounded up to whole pixels, at most "
                "8192 of them (see Limits)"),
       b.object("rami", &S::rami,
                "RAMI's measurements in ROMC's format, written to `DIR/rami/` beside `brf.json` "
                "(docs/guide/rami.md); absent: none",
                {r.string_array("measurements", &BrfRamiSettings::measurements,
                                "ROMC's measurement identifiers: `brfpp`, `brfop` (76 view "
                                "zeniths from -75 to 75 deg in the principal and orthogonal "
                                "planes), their parts `brfpp_co_sgl`, `brfpp_uc_sgl`, "
                                "`brfpp_mlt` (and `brfop_`'s), `brf1` (the albedo), `fabs`, "
                                "`ftran`, `falb`"),
                 r.string("experiment", &BrfRamiSettings::experiment,
                          "ROMC's experiment identifier (`HET01_DIS_UNI_NIR_20`); `{band}` is "
                          "replaced by the band's name, as it must be with more than one band")
                     .with_required(),
                 r.string("model", &BrfRamiSettings::model,
                          "ROMC's model identifier: 1 to 10 letters and digits")
                     .with_default("glaswave")})});
}

Key table_keys() {
  const Fields<TableSettings> t;
  using S = TableSettings;
  return object(
      "table",
      "`glaswave table`: the forward table of the `rt` retrieval (docs/retrieval.md); ignored "
      "by `run`",
      {map("vary",
           "keys (dotted paths, as `--set` names them) and the range [low, high] each is sampled "
           "over by a seeded low-discrepancy (Halton) design",
           number_pair("NAME", {0.0, 1.0}, any_finite(), "", "the key's range")),
       map("values",
           "keys and the values each takes, chosen evenly by the design (each read as `--set` "
           "reads VALUE: JSON when it parses, else a string)",
           string_array("NAME", "the key's values")),
       t.integer("entries", &S::entries, 1, 1000000, "", "entries of the table"),
       t.integer("shots_per_entry", &S::shots_per_entry, 1, 64, "",
                 "the track's first shots simulated for each entry: their mean is its waveform, "
                 "their scatter the table's Monte Carlo noise (at least 2 to measure it)")});
}

}  // namespace glaswave::section_keys
