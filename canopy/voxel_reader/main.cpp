// glaswave-read-voxels: opens and reads one NetCDF-4 voxel grid for VoxelGridFile
// (canopy/voxel_grid.hpp) in a process of its own, where a crash inside HDF5 ends only this
// program.
#include <unistd.h>

#include "canopy/voxel_grid.hpp"

// _exit: what the reader holds goes with the process; HDF5 keeps a few hundred bytes of its own on
// some corrupt files, which LeakSanitizer would report at exit in a sanitized build.
int main(int argc, char** argv) { ::_exit(glaswave::voxel_reader_main(argc, argv)); }
