// The `voxels` NetCDF format written (canopy/voxel_grid.hpp): `voxelize`'s product.
#include <netcdf.h>

#include <algorithm>
#include <mutex>
#include <string>
#include <vector>

#include "canopy/voxel_grid.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/netcdf_lock.hpp"

namespace glaswave {

namespace {

void check_nc(int status, const std::string& place) {
  if (status != NC_NOERR) throw run_error(place, std::string("NetCDF: ") + nc_strerror(status));
}

}  // namespace

void write_voxel_netcdf(const std::filesystem::path& file, const VoxelBlock& block,
                        const std::vector<float>& ground_m, const std::string& history) {
  AtomicFile product(file);
  const std::string place = file.string();
  std::lock_guard lock(netcdf_library_mutex());
  int nc = -1;
  check_nc(nc_create(product.part_path().c_str(), NC_NETCDF4 | NC_CLOBBER, &nc), place);
  try {
    int dz, dy, dx, dnv;
    check_nc(nc_def_dim(nc, "z", block.nz, &dz), place);
    check_nc(nc_def_dim(nc, "y", block.ny, &dy), place);
    check_nc(nc_def_dim(nc, "x", block.nx, &dx), place);
    check_nc(nc_def_dim(nc, "nv", 2, &dnv), place);
    auto text = [&](int var, const char* name, const std::string& value) {
      check_nc(nc_put_att_text(nc, var, name, value.size(), value.c_str()), place);
    };
    int vx, vy, vz, vzb, vcrs, vpad, vground = -1;
    check_nc(nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx), place);
    text(vx, "standard_name", "projection_x_coordinate");
    text(vx, "long_name", "x of the column centres in the grid's CRS");
    text(vx, "units", "m");
    check_nc(nc_def_var(nc, "y", NC_DOUBLE, 1, &dy, &vy), place);
    text(vy, "standard_name", "projection_y_coordinate");
    text(vy, "long_name", "y of the column centres in the grid's CRS");
    text(vy, "units", "m");
    check_nc(nc_def_var(nc, "z", NC_DOUBLE, 1, &dz, &vz), place);
    text(vz, "long_name", "height above the ground of the layer centres");
    text(vz, "units", "m");
    text(vz, "positive", "up");
    text(vz, "axis", "Z");
    text(vz, "bounds", "z_bounds");
    const int zb_dims[2] = {dz, dnv};
    check_nc(nc_def_var(nc, "z_bounds", NC_DOUBLE, 2, zb_dims, &vzb), place);
    check_nc(nc_def_var(nc, "crs", NC_INT, 0, nullptr, &vcrs), place);
    text(vcrs, "crs_wkt", block.crs_wkt);
    text(vcrs, "spatial_ref", block.crs_wkt);
    const int pad_dims[3] = {dz, dy, dx};
    check_nc(nc_def_var(nc, "pad", NC_FLOAT, 3, pad_dims, &vpad), place);
    const std::size_t chunk[3] = {std::size_t(block.nz), std::size_t(std::min(block.ny, 64)),
                                  std::size_t(std::min(block.nx, 64))};
    check_nc(nc_def_var_chunking(nc, vpad, NC_CHUNKED, chunk), place);
    check_nc(nc_def_var_deflate(nc, vpad, 1, 1, 4), place);
    text(vpad, "long_name", "plant area density (one-sided)");
    text(vpad, "units", "m2 m-3");
    text(vpad, "grid_mapping", "crs");
    if (!ground_m.empty()) {
      const int g_dims[2] = {dy, dx};
      check_nc(nc_def_var(nc, "ground_elevation", NC_FLOAT, 2, g_dims, &vground), place);
      text(vground, "long_name", "ground elevation under each column, in the CRS's heights");
      text(vground, "units", "m");
      text(vground, "grid_mapping", "crs");
    }
    text(NC_GLOBAL, "Conventions", "CF-1.10");
    text(NC_GLOBAL, "title", "plant area density voxel grid (glaswave voxels format)");
    if (!history.empty()) text(NC_GLOBAL, "history", history);
    check_nc(nc_enddef(nc), place);
    std::vector<double> c(block.nx);
    for (int i = 0; i < block.nx; ++i) c[i] = block.x0 + (i + 0.5) * block.dx;
    check_nc(nc_put_var_double(nc, vx, c.data()), place);
    c.resize(block.ny);
    for (int j = 0; j < block.ny; ++j) c[j] = block.y0 + (j + 0.5) * block.dy;
    check_nc(nc_put_var_double(nc, vy, c.data()), place);
    std::vector<double> zc(block.nz), zb(2 * block.nz);
    for (int k = 0; k < block.nz; ++k) {
      zc[k] = (block.z_edges_m[k] + block.z_edges_m[k + 1]) / 2;
      zb[2 * k] = block.z_edges_m[k];
      zb[2 * k + 1] = block.z_edges_m[k + 1];
    }
    check_nc(nc_put_var_double(nc, vz, zc.data()), place);
    check_nc(nc_put_var_double(nc, vzb, zb.data()), place);
    check_nc(nc_put_var_float(nc, vpad, block.pad.data()), place);
    if (vground >= 0) check_nc(nc_put_var_float(nc, vground, ground_m.data()), place);
    check_nc(nc_close(nc), place);
  } catch (...) {
    nc_close(nc);
    throw;
  }
  product.commit();
}

}  // namespace glaswave
