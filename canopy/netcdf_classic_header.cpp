// A classic NetCDF header walked, each declared size checked against the bytes left, as the
// format's specification lays it out (NetCDF Users Guide, "File Format Specifications"):
//   header   = magic numrecs dim_list gatt_list var_list
//   dim_list = ABSENT | NC_DIMENSION nelems [dim ...]     dim  = name dim_length
//   gatt_list, vatt_list = ABSENT | NC_ATTRIBUTE nelems [attr ...]
//   attr     = name nc_type nelems [values ...]            (padded to 4 bytes)
//   var_list = ABSENT | NC_VARIABLE nelems [var ...]
//   var      = name nelems [dimid ...] vatt_list nc_type vsize begin
//   name     = nelems namestring                           (padded to 4 bytes)
// Tags and nc_type are 4 bytes; a count, length or dimension id 4 (CDF-1, CDF-2) or 8 (CDF-5);
// vsize 4 (8 in CDF-5); begin 4 (CDF-1) or 8.
#include "canopy/netcdf_classic_header.hpp"

#include <cstdint>
#include <fstream>

#include "core/error.hpp"

namespace glaswave {
namespace {

class HeaderWalk {
 public:
  HeaderWalk(const std::filesystem::path& file, const std::string& place)
      : in_(file, std::ios::binary), place_(place) {
    std::error_code error;
    size_ = std::filesystem::file_size(file, error);
    if (error) size_ = 0;
  }

  std::uint64_t left() const { return size_ - at_; }

  // A big-endian number of `bytes` bytes.
  std::uint64_t number(int bytes, const char* what) {
    if (left() < static_cast<std::uint64_t>(bytes)) cut(what);
    unsigned char raw[8] = {};
    in_.read(reinterpret_cast<char*>(raw), bytes);
    if (!in_) cut(what);
    at_ += static_cast<std::uint64_t>(bytes);
    std::uint64_t value = 0;
    for (int i = 0; i < bytes; ++i) value = value << 8 | raw[i];
    return value;
  }

  // Skips `bytes` bytes, which must be in the file.
  void skip(std::uint64_t bytes, const char* what) {
    if (left() < bytes) cut(what);
    in_.seekg(static_cast<std::streamoff>(bytes), std::ios::cur);
    at_ += bytes;
  }

  // A count of items of at least `item_bytes` bytes each, which the bytes left must hold.
  std::uint64_t count(int bytes, std::uint64_t item_bytes, const char* what) {
    const std::uint64_t n = number(bytes, what);
    if (n > left() / item_bytes)
      throw input_error(place_, "the classic NetCDF header declares " + std::to_string(n) + " " +
                                    what + ", more than the file's " + std::to_string(size_) +
                                    " bytes hold (a corrupt file)");
    return n;
  }

  [[noreturn]] void cut(const char* what) {
    throw input_error(place_, std::string("the classic NetCDF header is cut short (at its ") +
                                  what + ", byte " + std::to_string(at_) + " of " +
                                  std::to_string(size_) + ")");
  }

 private:
  std::ifstream in_;
  const std::string& place_;
  std::uint64_t size_ = 0, at_ = 0;
};

std::uint64_t padded(std::uint64_t bytes) { return (bytes + 3) / 4 * 4; }

// The bytes of one value of an nc_type; 0 for no type of the format.
std::uint64_t type_bytes(std::uint64_t type) {
  switch (type) {
    case 1:  // NC_BYTE
    case 2:  // NC_CHAR
    case 7:  // NC_UBYTE
      return 1;
    case 3:  // NC_SHORT
    case 8:  // NC_USHORT
      return 2;
    case 4:  // NC_INT
    case 5:  // NC_FLOAT
    case 9:  // NC_UINT
      return 4;
    case 6:   // NC_DOUBLE
    case 10:  // NC_INT64
    case 11:  // NC_UINT64
      return 8;
    default:
      return 0;
  }
}

void name(HeaderWalk& walk, int count_bytes, const char* what) {
  walk.skip(padded(walk.count(count_bytes, 1, what)), what);
}

// An attribute list (the file's or a variable's); nothing left to read when its tag is ABSENT's.
void attributes(HeaderWalk& walk, int count_bytes, const std::string& place) {
  walk.number(4, "attribute list's tag");
  const std::uint64_t min_attribute = 2 * count_bytes + 4;
  const std::uint64_t n = walk.count(count_bytes, min_attribute, "attributes");
  for (std::uint64_t a = 0; a < n; ++a) {
    name(walk, count_bytes, "bytes of an attribute's name");
    const std::uint64_t bytes = type_bytes(walk.number(4, "attribute's type"));
    if (bytes == 0) throw input_error(place, "the classic NetCDF header names an unknown type");
    const std::uint64_t values = walk.count(count_bytes, bytes, "attribute values");
    walk.skip(padded(values * bytes), "attribute's values");
  }
}

}  // namespace

void check_classic_netcdf_header(const std::filesystem::path& file, const std::string& place) {
  HeaderWalk walk(file, place);
  if (walk.left() < 4) return;
  const std::uint64_t magic = walk.number(4, "magic number");
  if (magic >> 8 != 0x434446) return;  // not "CDF"
  const int version = static_cast<int>(magic & 0xff);
  if (version != 1 && version != 2 && version != 5)
    throw input_error(place, "not a classic NetCDF file of a version libnetcdf reads (CDF-" +
                                 std::to_string(version) + ")");
  const int count_bytes = version == 5 ? 8 : 4;
  walk.number(count_bytes, "record count");
  // Dimensions: a name (its length and at least 0 bytes) and a length each.
  walk.number(4, "dimension list's tag");
  const std::uint64_t dimensions = walk.count(count_bytes, 2 * count_bytes, "dimensions");
  for (std::uint64_t d = 0; d < dimensions; ++d) {
    name(walk, count_bytes, "bytes of a dimension's name");
    walk.number(count_bytes, "dimension's length");
  }
  attributes(walk, count_bytes, place);
  // Variables: a name, its dimensions' ids, its attributes (a tag and a count), type, vsize and
  // begin.
  walk.number(4, "variable list's tag");
  const int begin_bytes = version == 1 ? 4 : 8;
  const std::uint64_t min_variable = 3 * count_bytes + 4 + 4 + count_bytes + begin_bytes;
  const std::uint64_t variables = walk.count(count_bytes, min_variable, "variables");
  for (std::uint64_t v = 0; v < variables; ++v) {
    name(walk, count_bytes, "bytes of a variable's name");
    const std::uint64_t ids = walk.count(count_bytes, count_bytes, "dimensions of a variable");
    walk.skip(ids * count_bytes, "variable's dimension ids");
    attributes(walk, count_bytes, place);
    walk.number(4, "variable's type");
    walk.number(count_bytes, "variable's size");
    walk.number(begin_bytes, "variable's offset");
  }
}

}  // namespace glaswave
