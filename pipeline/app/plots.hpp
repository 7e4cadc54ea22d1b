// The PNG quick-looks of a run (PRODUCT.md section 4, DIR/plots/): drawn by matplotlib in
// share/plots/plot_products.py, which this runs as a child process after the products are
// written.
#pragma once

#include <filesystem>
#include <string>

namespace glaswave {

// Runs `python3 <share>/plots/plot_products.py out_dir`, which reads out_dir/shots.nc and
// out_dir/footprints.geojson and writes out_dir/plots/*.png. <share> is the environment
// variable GLASWAVE_SHARE when set and non-empty, else the source tree's share/ folder
// (GLASWAVE_SHARE_DIR, fixed at build time). Python is /usr/bin/python3 when it exists (the
// one that has Debian's matplotlib), else python3 on PATH. Throws Error (run, place "plots")
// when the script cannot be started or fails: one line, the last of the script's stderr, the
// whole of it in out_dir/plots.log.
// script_name: another script in <share>/plots/ run the same way (`glaswave retrieve --plots`
// runs plot_retrieval.py on its DIR).
void write_plots(const std::filesystem::path& out_dir,
                 const std::string& script_name = "plot_products.py");

// write_plots after a run's products are complete: a plot that fails does not fail the run
// (issue 28), so its Error comes back as the warning to print (empty when the plots are drawn).
std::string plots_after_products(const std::filesystem::path& out_dir,
                                 const std::string& script_name = "plot_products.py");

}  // namespace glaswave
