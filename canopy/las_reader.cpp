// LAS 1.0-1.4 reader: offsets and sizes from the ASPRS LAS 1.4 (R15) specification's public
// header block and point data record format tables.
#include "canopy/las_reader.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>

#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "core/input_file.hpp"

namespace glaswave {

namespace {

// Public header block: the sizes the versions define (1.0-1.2: through Min Z; 1.3 adds the
// start of waveform data; 1.4 the EVLRs and the 64-bit point counts).
constexpr std::uint16_t header_size_12 = 227;
constexpr std::uint16_t header_size_13 = 235;
constexpr std::uint16_t header_size_14 = 375;
constexpr std::uint64_t vlr_header_bytes = 54;
constexpr std::uint64_t evlr_header_bytes = 60;

constexpr std::array<int, 11> min_record_length = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

std::uint16_t u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
std::uint32_t u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}
std::uint64_t u64(const std::uint8_t* p) {
  return std::uint64_t{u32(p)} | std::uint64_t{u32(p + 4)} << 32;
}
std::int32_t i32(const std::uint8_t* p) { return static_cast<std::int32_t>(u32(p)); }
double f64(const std::uint8_t* p) {
  const std::uint64_t bits = u64(p);
  double value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

// A fixed-size text field: up to its first NUL.
std::string text_field(const std::uint8_t* p, std::size_t size) {
  std::size_t n = 0;
  while (n < size && p[n] != 0) ++n;
  return std::string(reinterpret_cast<const char*>(p), n);
}

class Bytes {
 public:
  Bytes(const std::filesystem::path& file, std::uint64_t size)
      : in_(file, std::ios::binary), path_(file.string()), size_(size) {
    if (!in_) throw input_error(path_, "cannot open the point cloud");
  }
  // `count` bytes at `offset`, which the caller has checked lie within the file.
  void read(std::uint64_t offset, std::uint64_t count, std::uint8_t* to) {
    if (offset > size_ || count > size_ - offset)
      throw input_error(path_, "truncated LAS file: " + std::to_string(count) + " bytes at " +
                                   std::to_string(offset) + " lie beyond its " +
                                   std::to_string(size_) + " bytes");
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char*>(to), static_cast<std::streamsize>(count));
    if (!in_)
      throw input_error(path_, "cannot read the point cloud at byte " + std::to_string(offset));
  }

 private:
  std::ifstream in_;
  std::string path_;
  std::uint64_t size_;
};

// The header of a variable length record at `at` (54 bytes, its data's length in 16 bits) or of
// an extended one (60 bytes, 64 bits): its user and record ids; `length` receives its data's
// length and `at` moves past the header.
LasRecord record_header(Bytes& bytes, std::uint64_t& at, bool extended, std::uint64_t& length) {
  std::array<std::uint8_t, evlr_header_bytes> r{};
  const std::uint64_t size = extended ? evlr_header_bytes : vlr_header_bytes;
  bytes.read(at, size, r.data());
  LasRecord record;
  record.user_id = text_field(r.data() + 2, 16);
  record.record_id = u16(r.data() + 18);
  length = extended ? u64(r.data() + 20) : u16(r.data() + 20);
  at += size;
  return record;
}

[[noreturn]] void refuse(const std::filesystem::path& file, const std::string& message) {
  throw input_error(file.string(), message);
}

const char* laz_advice =
    "a LAZ (compressed) point cloud; glaswave reads uncompressed LAS: decompress it first "
    "(`laszip -i CLOUD.laz -o CLOUD.las` or `pdal translate CLOUD.laz CLOUD.las`)";

// An OGR spatial reference from any definition GDAL takes, as WKT2; empty when it takes none.
std::string wkt_of(const std::string& definition) {
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  std::string wkt;
  {
    const GdalErrorTrap trap;
    if (OSRSetFromUserInput(srs, definition.c_str()) == OGRERR_NONE) {
      char* text = nullptr;
      const char* options[] = {"FORMAT=WKT2_2019", nullptr};
      if (OSRExportToWktEx(srs, &text, options) == OGRERR_NONE && text) wkt = text;
      CPLFree(text);
    }
  }
  OSRDestroySpatialReference(srs);
  return wkt;
}

// Why a CRS cannot place a cloud's voxels, which are cubes in the cloud's own x, y and z: a
// geographic one (x, y in degrees) or a linear unit other than the metre (US survey feet read as
// metres); empty when it can.
std::string short_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", x);
  return text;
}

std::string unusable_crs(const std::string& wkt) {
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  std::string why;
  {
    const GdalErrorTrap trap;
    if (OSRSetFromUserInput(srs, wkt.c_str()) == OGRERR_NONE) {
      char* name = nullptr;
      if (OSRIsGeographic(srs) || OSRIsGeocentric(srs)) {
        why =
            "is geographic (x and y in degrees), and voxels are cubes in metres: reproject "
            "the cloud to a projected CRS in metres first (`pdal translate` with "
            "filters.reprojection, or las2las -target_epsg)";
      } else if (const double metres = OSRGetLinearUnits(srs, &name); metres != 1.0) {
        why = "measures x and y in " + std::string(name ? name : "an unnamed unit") + " (" +
              short_number(metres) +
              " m), and voxels and heights are in metres: reproject the cloud to a CRS in "
              "metres first";
      } else if (OSRIsVertical(srs) || OSRIsCompound(srs)) {
        const double z_metres = OSRGetTargetLinearUnits(srs, "VERT_CS", &name);
        if (z_metres != 1.0)
          why = "measures heights in " + std::string(name ? name : "an unnamed unit") + " (" +
                short_number(z_metres) +
                " m), and voxels are in metres: convert the cloud's "
                "heights to metres first";
      }
    }
  }
  OSRDestroySpatialReference(srs);
  return why;
}

}  // namespace

int las_point_record_min_length(int format) {
  return format >= 0 && format < static_cast<int>(min_record_length.size())
             ? min_record_length[format]
             : 0;
}

LasFile::LasFile(const std::filesystem::path& file) : path_(file) {
  std::error_code error;
  require_input_file(file.native(), "the point cloud");  // a FIFO or device is refused unopened
  file_size_ = std::filesystem::file_size(file, error);
  if (error) refuse(file, "cannot read the point cloud's size");
  if (file.extension() == ".laz" || file.extension() == ".LAZ") refuse(file, laz_advice);
  Bytes bytes(file, file_size_);

  if (file_size_ < header_size_12)
    refuse(file, "truncated LAS file: " + std::to_string(file_size_) +
                     " bytes, fewer than the 227 of a LAS header");
  std::array<std::uint8_t, header_size_14> h{};
  bytes.read(0, std::min<std::uint64_t>(file_size_, header_size_14), h.data());
  if (std::memcmp(h.data(), "LASF", 4) != 0)
    refuse(file, "not a LAS file (no \"LASF\" signature at its start)");
  LasHeader& H = header_;
  H.global_encoding = u16(h.data() + 6);
  H.version_major = h[24];
  H.version_minor = h[25];
  if (H.version_major != 1 || H.version_minor > 4)
    refuse(file, "LAS version " + std::to_string(H.version_major) + "." +
                     std::to_string(H.version_minor) + " is not one of 1.0-1.4");
  const std::uint16_t version_header = H.version_minor >= 4   ? header_size_14
                                       : H.version_minor == 3 ? header_size_13
                                                              : header_size_12;
  H.header_size = u16(h.data() + 94);
  if (H.header_size < version_header)
    refuse(file, "header size " + std::to_string(H.header_size) + " is smaller than the " +
                     std::to_string(version_header) + " bytes of a LAS 1." +
                     std::to_string(H.version_minor) + " header");
  if (H.header_size > file_size_)
    refuse(file, "truncated LAS file: its header claims " + std::to_string(H.header_size) +
                     " bytes, the file has " + std::to_string(file_size_));
  H.point_offset = u32(h.data() + 96);
  H.vlr_count = u32(h.data() + 100);
  const int format_byte = h[104];
  // LASzip marks compressed points by setting the two high bits of the format (and by its VLR).
  if (format_byte & 0xC0) refuse(file, laz_advice);
  H.point_format = format_byte;
  if (H.point_format > 10)
    refuse(file, "point data record format " + std::to_string(H.point_format) +
                     " is not one of LAS's 0-10");
  if (H.point_format > 5 && H.version_minor < 4)
    refuse(file, "point data record format " + std::to_string(H.point_format) +
                     " needs LAS 1.4, the file says 1." + std::to_string(H.version_minor));
  H.point_record_length = u16(h.data() + 105);
  if (H.point_record_length < min_record_length[H.point_format])
    refuse(file, "point record length " + std::to_string(H.point_record_length) +
                     " is shorter than the " + std::to_string(min_record_length[H.point_format]) +
                     " bytes of point format " + std::to_string(H.point_format));
  H.point_count = u32(h.data() + 107);
  for (int a = 0; a < 3; ++a) {
    H.scale[a] = f64(h.data() + 131 + 8 * a);
    H.offset[a] = f64(h.data() + 155 + 8 * a);
    H.max[a] = f64(h.data() + 179 + 16 * a);
    H.min[a] = f64(h.data() + 187 + 16 * a);
    if (!std::isfinite(H.scale[a]) || H.scale[a] == 0.0 || !std::isfinite(H.offset[a]))
      refuse(file, std::string("the ") + "xyz"[a] + " scale or offset is zero or not finite");
  }
  if (H.version_minor >= 4) {
    H.evlr_offset = u64(h.data() + 235);
    H.evlr_count = u32(h.data() + 243);
    const std::uint64_t count64 = u64(h.data() + 247);
    // The legacy 32-bit count is 0 in a 1.4 file of formats 6-10 (or over 2^32 points).
    if (count64 != 0 || H.point_format > 5) H.point_count = count64;
  }

  if (H.point_offset < H.header_size)
    refuse(file, "its points start at byte " + std::to_string(H.point_offset) + ", inside its " +
                     std::to_string(H.header_size) + "-byte header");
  if (H.point_offset > file_size_)
    refuse(file, "truncated LAS file: its points start at byte " + std::to_string(H.point_offset) +
                     ", beyond its " + std::to_string(file_size_) + " bytes");
  if (H.vlr_count > max_records || H.evlr_count > max_records)
    refuse(file, "more than " + std::to_string(max_records) + " variable length records");
  const std::uint64_t points_end_limit = file_size_ - H.point_offset;
  if (H.point_count > points_end_limit / H.point_record_length)
    refuse(file, "truncated LAS file: its header counts " + std::to_string(H.point_count) +
                     " points of " + std::to_string(H.point_record_length) + " bytes from byte " +
                     std::to_string(H.point_offset) + ", beyond its " + std::to_string(file_size_) +
                     " bytes");

  // Variable length records lie between the header and the points.
  std::uint64_t at = H.header_size;
  for (std::uint32_t i = 0; i < H.vlr_count; ++i) {
    if (H.point_offset - at < vlr_header_bytes)
      refuse(file, "variable length record " + std::to_string(i) + " runs into the points");
    std::uint64_t length = 0;
    LasRecord record = record_header(bytes, at, false, length);
    if (H.point_offset - at < length)
      refuse(file, "variable length record " + std::to_string(i) + " (" + std::to_string(length) +
                       " bytes) runs into the points");
    record.data.resize(length);
    bytes.read(at, length, record.data.data());
    at += length;
    if (record.user_id == "laszip encoded") refuse(file, laz_advice);
    records_.push_back(std::move(record));
  }
  if (H.evlr_count > 0) {
    const std::uint64_t points_end = H.point_offset + H.point_count * H.point_record_length;
    if (H.evlr_offset < points_end || H.evlr_offset > file_size_)
      refuse(file, "its extended records start at byte " + std::to_string(H.evlr_offset) +
                       ", not between its points' end (" + std::to_string(points_end) +
                       ") and its end (" + std::to_string(file_size_) + ")");
    at = H.evlr_offset;
    for (std::uint32_t i = 0; i < H.evlr_count; ++i) {
      if (file_size_ - at < evlr_header_bytes)
        refuse(file,
               "truncated LAS file: extended record " + std::to_string(i) + " lies beyond its end");
      std::uint64_t length = 0;
      LasRecord record = record_header(bytes, at, true, length);
      if (length > file_size_ - at)
        refuse(file, "truncated LAS file: extended record " + std::to_string(i) + " (" +
                         std::to_string(length) + " bytes) lies beyond its end");
      // Only the records a reader of points needs are kept (the CRS); waveforms are skipped.
      if (record.user_id == "LASF_Projection") {
        if (length > max_record_bytes)
          refuse(file, "extended record " + std::to_string(i) + " of " + std::to_string(length) +
                           " bytes is larger than a CRS record can be");
        record.data.resize(length);
        bytes.read(at, length, record.data.data());
      }
      at += length;
      records_.push_back(std::move(record));
    }
  }
}

std::string LasFile::crs_wkt() const {
  const LasRecord* wkt = nullptr;
  const LasRecord *keys = nullptr, *doubles = nullptr, *ascii = nullptr;
  for (const LasRecord& r : records_) {
    if (r.user_id != "LASF_Projection") continue;
    if (r.record_id == 2112) wkt = &r;
    if (r.record_id == 34735) keys = &r;
    if (r.record_id == 34736) doubles = &r;
    if (r.record_id == 34737) ascii = &r;
  }
  (void)doubles;
  (void)ascii;
  const std::string place = path_.string();
  if (wkt) {
    const std::string text = text_field(wkt->data.data(), wkt->data.size());
    const std::string result = wkt_of(text);
    if (result.empty())
      throw input_error(place, "its WKT record (LASF_Projection 2112) is not a CRS GDAL reads");
    return result;
  }
  if (!keys) return {};
  // GeoKeyDirectoryTag: a header of four shorts (version 1, revision, minor, number of keys),
  // then four shorts a key (id, TIFF tag holding the value or 0 for inline, count, value).
  const auto& d = keys->data;
  if (d.size() < 8 || d.size() % 2 != 0)
    throw input_error(place, "its GeoTIFF keys record (LASF_Projection 34735) is truncated");
  const std::size_t key_count = u16(d.data() + 6);
  if (u16(d.data()) != 1 || d.size() < 8 + 8 * key_count)
    throw input_error(place, "its GeoTIFF keys record (LASF_Projection 34735) is malformed");
  int model = 0, geographic = 0, projected = 0, vertical = 0;
  for (std::size_t k = 0; k < key_count; ++k) {
    const std::uint8_t* e = d.data() + 8 + 8 * k;
    const int id = u16(e), location = u16(e + 2), value = u16(e + 6);
    if (location != 0) continue;  // our keys are all inline shorts
    if (id == 1024) model = value;
    if (id == 2048) geographic = value;
    if (id == 3072) projected = value;
    if (id == 4096) vertical = value;
  }
  const auto known = [](int code) { return code > 0 && code != 32767; };
  std::string horizontal;
  if (known(projected) && model != 2)
    horizontal = "EPSG:" + std::to_string(projected);
  else if (known(geographic))
    horizontal = "EPSG:" + std::to_string(geographic);
  if (horizontal.empty())
    throw input_error(place,
                      "its GeoTIFF keys name no EPSG coordinate system (user-defined "
                      "keys are not read): give canopy.point_cloud.crs, or add a WKT "
                      "record to the file");
  std::string result;
  if (known(vertical)) result = wkt_of(horizontal + "+" + std::to_string(vertical));
  if (result.empty()) result = wkt_of(horizontal);
  if (result.empty())
    throw input_error(place, "its GeoTIFF keys name " + horizontal + ", which PROJ does not know");
  return result;
}

void LasFile::read_points(std::uint64_t first, std::uint64_t count,
                          std::vector<LasPoint>& points) const {
  const LasHeader& H = header_;
  if (first >= H.point_count) return;
  count = std::min(count, H.point_count - first);
  Bytes bytes(path_, file_size_);
  const std::uint64_t chunk_points =
      std::max<std::uint64_t>(1, (std::uint64_t{1} << 20) / H.point_record_length);
  std::vector<std::uint8_t> buffer;
  const bool extended = H.point_format >= 6;
  const bool has_time = H.point_format != 0 && H.point_format != 2;
  points.reserve(points.size() + count);
  for (std::uint64_t done = 0; done < count;) {
    const std::uint64_t n = std::min(chunk_points, count - done);
    buffer.resize(n * H.point_record_length);
    bytes.read(H.point_offset + (first + done) * H.point_record_length, buffer.size(),
               buffer.data());
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint8_t* p = buffer.data() + i * H.point_record_length;
      LasPoint point;
      point.x = i32(p) * H.scale[0] + H.offset[0];
      point.y = i32(p + 4) * H.scale[1] + H.offset[1];
      point.z = i32(p + 8) * H.scale[2] + H.offset[2];
      point.intensity = u16(p + 12);
      if (extended) {
        point.return_number = p[14] & 0x0F;
        point.number_of_returns = p[14] >> 4;
        point.withheld = (p[15] & 0x04) != 0;
        point.classification = p[16];
        point.scan_angle_deg = static_cast<std::int16_t>(u16(p + 18)) * 0.006;
        point.gps_time = f64(p + 22);
      } else {
        point.return_number = p[14] & 0x07;
        point.number_of_returns = (p[14] >> 3) & 0x07;
        point.classification = p[15] & 0x1F;
        point.withheld = (p[15] & 0x80) != 0;
        point.scan_angle_deg = static_cast<std::int8_t>(p[16]);
        if (has_time) point.gps_time = f64(p + 20);
      }
      // The specification's angles lie within 90 degrees of nadir; beyond, the gap fraction's
      // cosine weights turn negative and every voxel's density 0.
      if (!(std::abs(point.scan_angle_deg) <= 90.0))
        throw input_error(path_.string(),
                          "point " + std::to_string(first + done + i) + " has a scan angle of " +
                              short_number(point.scan_angle_deg) +
                              " degrees, beyond the LAS specification's -90 to 90 (from nadir)");
      points.push_back(point);
    }
    done += n;
  }
}

std::string las_crs(const LasFile& file, const std::string& fallback,
                    const std::string& fallback_place) {
  std::string wkt = file.crs_wkt();
  if (!wkt.empty()) {
    if (const std::string why = unusable_crs(wkt); !why.empty())
      throw input_error(file.path().string(), "the point cloud's CRS " + why);
    return wkt;
  }
  if (fallback.empty())
    throw input_error(file.path().string(),
                      "the point cloud has no CRS (no WKT or GeoTIFF-keys record) and none is "
                      "given (canopy.point_cloud.crs, or voxelize --crs)");
  wkt = wkt_of(fallback);
  if (wkt.empty())
    throw config_error(fallback_place,
                       "\"" + fallback.substr(0, 60) + "\" is not a CRS GDAL reads");
  if (const std::string why = unusable_crs(wkt); !why.empty())
    throw config_error(fallback_place, "\"" + fallback.substr(0, 60) + "\" " + why);
  return wkt;
}

}  // namespace glaswave
