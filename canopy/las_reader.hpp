// Airborne lidar point clouds in ASPRS LAS 1.0-1.4 (point data record formats 0-10,
// uncompressed), read as the specification lays them out (ASPRS LAS 1.4 R15: the public header
// block, variable length records, point data records, extended variable length records; all
// little-endian). PDAL and LASzip are not packaged in Debian 12, hence a reader of our own.
//
// Nothing is trusted: every size and offset of the header and its records is checked against
// the version's minimum and against the file's size before anything is read or allocated, so a
// truncated file, a header that lies about its size, a point count beyond the file or an
// unknown point format is an input error naming the file (exit status 3), never a crash.
// LAZ (compressed) is refused with one line that says how to decompress it.
//
// The coordinate reference system comes from the OGC WKT record (LASF_Projection 2112) or the
// GeoTIFF keys record (LASF_Projection 34735, with 34736 and 34737), as WKT through GDAL/PROJ.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace glaswave {

struct LasHeader {
  int version_major = 1, version_minor = 0;
  std::uint16_t global_encoding = 0;
  std::uint16_t header_size = 0;
  std::uint32_t point_offset = 0;  // offset to point data, bytes from the file's start
  std::uint32_t vlr_count = 0;
  int point_format = 0;  // 0-10
  std::uint16_t point_record_length = 0;
  std::uint64_t point_count = 0;  // the 1.4 64-bit count when the version has one and it is set
  double scale[3] = {1.0, 1.0, 1.0};
  double offset[3] = {0.0, 0.0, 0.0};
  double min[3] = {0.0, 0.0, 0.0};
  double max[3] = {0.0, 0.0, 0.0};
  std::uint64_t evlr_offset = 0;  // 1.4
  std::uint32_t evlr_count = 0;   // 1.4
};

struct LasPoint {
  double x = 0.0, y = 0.0, z = 0.0;  // in the file's CRS (scale and offset applied)
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 0;  // 1-based; 0 in a file that leaves it unset
  std::uint8_t number_of_returns = 0;
  std::uint8_t classification = 0;  // ASPRS class: 2 ground, 3-5 vegetation, 7 noise, ...
  bool withheld = false;
  double scan_angle_deg = 0.0;  // from nadir, signed (formats 0-5: whole degrees)
  double gps_time = 0.0;        // formats with a GPS time; 0 otherwise
};

// A variable length record (or an extended one) as found: its user and record ids and its data.
struct LasRecord {
  std::string user_id;
  std::uint16_t record_id = 0;
  std::vector<std::uint8_t> data;
};

class LasFile {
 public:
  // Records (VLR or EVLR payloads) larger than this are refused: a LAS CRS or metadata record
  // is a few kB; a waveform or classification lookup far less than this.
  static constexpr std::uint64_t max_record_bytes = std::uint64_t{16} << 20;
  static constexpr std::uint32_t max_records = 65536;

  // Opens the file and reads and checks its header and records (not its points). An input
  // error naming the file when it is not an uncompressed LAS 1.0-1.4 file whose header, records
  // and points all lie within it.
  explicit LasFile(const std::filesystem::path& file);

  const LasHeader& header() const { return header_; }
  const std::vector<LasRecord>& records() const { return records_; }  // VLRs, then EVLRs
  const std::filesystem::path& path() const { return path_; }

  // The CRS of the file as WKT from its WKT or GeoTIFF-keys record; empty when it has neither.
  // An input error when a record is there but cannot be understood.
  std::string crs_wkt() const;

  // Points [first, first + count) (count clipped at the end of the file), appended to `points`.
  void read_points(std::uint64_t first, std::uint64_t count, std::vector<LasPoint>& points) const;

 private:
  std::filesystem::path path_;
  std::uint64_t file_size_ = 0;
  LasHeader header_;
  std::vector<LasRecord> records_;
};

// The CRS of a point cloud (WKT): the file's own, else `fallback` (any definition GDAL takes:
// "EPSG:32633", WKT, PROJ), else an input error naming the file. An error too when the fallback
// cannot be understood (a configuration error placed at `fallback_place`).
std::string las_crs(const LasFile& file, const std::string& fallback,
                    const std::string& fallback_place);

// The minimum point record length of each point data record format (0-10); 0 for others.
int las_point_record_min_length(int format);

}  // namespace glaswave
