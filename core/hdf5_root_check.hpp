// A check of an HDF5 file's root group made on its bytes, before the HDF5 library reads it:
// Debian 12's HDF5 1.10.8 reads through whatever address a root group's symbol table names, and
// one of HDF5's "undefined" (all ones) or beyond the file's end crashes it (the granule fuzzer
// found it; any access to the root, H5Lexists or H5Literate alike, reaches it). A library must
// not fork to survive that, so such a file is refused before the library opens it.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace glaswave {

// What is wrong with the root group of `file` (superblock versions 0 and 1, 8-byte addresses:
// what h5py, netCDF-4 and the missions' granules write), as words for an error; empty when
// nothing is found wrong or the layout is another (later superblocks, other address sizes),
// which HDF5 then reads alone.
std::optional<std::string> hdf5_root_fault(const std::filesystem::path& file);

}  // namespace glaswave
