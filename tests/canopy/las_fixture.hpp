// Writes small LAS files for the tests, byte by byte from the ASPRS LAS 1.4 tables (independent
// of the reader): a header of the version's size, optional WKT / GeoTIFF-keys records, points of
// any format 0-10. Fields the tests do not set stay zero.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace glaswave::test {

struct LasFixturePoint {
  double x = 0.0, y = 0.0, z = 0.0;
  int return_number = 1, number_of_returns = 1, classification = 1;
  double gps_time = 0.0;
  double scan_angle_deg = 0.0;
};

struct LasFixture {
  int version_minor = 2;
  int point_format = 0;
  int extra_bytes = 0;  // appended to each point record
  double scale = 0.001;
  double offset[3] = {500000.0, 4000000.0, 0.0};
  std::string wkt;            // a LASF_Projection 2112 record when not empty
  std::vector<int> geo_keys;  // a LASF_Projection 34735 record when not empty (id, value pairs)
  std::vector<LasFixturePoint> points;
};

inline void put(std::vector<std::uint8_t>& b, std::size_t at, const void* v, std::size_t n) {
  if (b.size() < at + n) b.resize(at + n);
  std::memcpy(b.data() + at, v, n);
}
template <typename T>
void put_value(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  put(b, at, &v, sizeof v);  // the test machines are little-endian, as LAS is
}

inline std::vector<std::uint8_t> las_bytes(const LasFixture& f) {
  static const int lengths[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  const std::uint16_t header = f.version_minor >= 4 ? 375 : f.version_minor == 3 ? 235 : 227;
  std::vector<std::vector<std::uint8_t>> vlrs;
  auto vlr = [&](std::uint16_t id, const std::vector<std::uint8_t>& data) {
    std::vector<std::uint8_t> r(54, 0);
    std::memcpy(r.data() + 2, "LASF_Projection", 15);
    put_value<std::uint16_t>(r, 18, id);
    put_value<std::uint16_t>(r, 20, static_cast<std::uint16_t>(data.size()));
    r.insert(r.end(), data.begin(), data.end());
    vlrs.push_back(r);
  };
  if (!f.wkt.empty()) {
    std::vector<std::uint8_t> d(f.wkt.begin(), f.wkt.end());
    d.push_back(0);
    vlr(2112, d);
  }
  if (!f.geo_keys.empty()) {
    std::vector<std::uint8_t> d;
    const std::size_t n = f.geo_keys.size() / 2;
    put_value<std::uint16_t>(d, 0, 1);
    put_value<std::uint16_t>(d, 2, 1);
    put_value<std::uint16_t>(d, 4, 0);
    put_value<std::uint16_t>(d, 6, static_cast<std::uint16_t>(n));
    for (std::size_t k = 0; k < n; ++k) {
      put_value<std::uint16_t>(d, 8 + 8 * k, static_cast<std::uint16_t>(f.geo_keys[2 * k]));
      put_value<std::uint16_t>(d, 8 + 8 * k + 2, 0);
      put_value<std::uint16_t>(d, 8 + 8 * k + 4, 1);
      put_value<std::uint16_t>(d, 8 + 8 * k + 6, static_cast<std::uint16_t>(f.geo_keys[2 * k + 1]));
    }
    vlr(34735, d);
  }
  std::vector<std::uint8_t> b(header, 0);
  std::memcpy(b.data(), "LASF", 4);
  b[24] = 1;
  b[25] = static_cast<std::uint8_t>(f.version_minor);
  put_value<std::uint16_t>(b, 94, header);
  std::uint32_t offset = header;
  for (const auto& r : vlrs) offset += static_cast<std::uint32_t>(r.size());
  put_value<std::uint32_t>(b, 96, offset);
  put_value<std::uint32_t>(b, 100, static_cast<std::uint32_t>(vlrs.size()));
  b[104] = static_cast<std::uint8_t>(f.point_format);
  const int length = lengths[f.point_format] + f.extra_bytes;
  put_value<std::uint16_t>(b, 105, static_cast<std::uint16_t>(length));
  const bool legacy = f.point_format <= 5;
  put_value<std::uint32_t>(b, 107, legacy ? static_cast<std::uint32_t>(f.points.size()) : 0u);
  for (int a = 0; a < 3; ++a) {
    put_value<double>(b, 131 + 8 * a, f.scale);
    put_value<double>(b, 155 + 8 * a, f.offset[a]);
    // The points' extent, max then min, as writers fill it.
    double lo = 0.0, hi = 0.0;
    for (std::size_t k = 0; k < f.points.size(); ++k) {
      const LasFixturePoint& p = f.points[k];
      const double v = a == 0 ? p.x : a == 1 ? p.y : p.z;
      lo = k == 0 ? v : std::min(lo, v);
      hi = k == 0 ? v : std::max(hi, v);
    }
    put_value<double>(b, 179 + 16 * a, hi);
    put_value<double>(b, 187 + 16 * a, lo);
  }
  if (f.version_minor >= 4) {
    if (!f.wkt.empty()) put_value<std::uint16_t>(b, 6, 16);  // global encoding: WKT
    put_value<std::uint64_t>(b, 247, f.points.size());
  }
  for (const auto& r : vlrs) b.insert(b.end(), r.begin(), r.end());
  for (const LasFixturePoint& p : f.points) {
    std::vector<std::uint8_t> r(length, 0);
    put_value<std::int32_t>(r, 0,
                            static_cast<std::int32_t>(std::lround((p.x - f.offset[0]) / f.scale)));
    put_value<std::int32_t>(r, 4,
                            static_cast<std::int32_t>(std::lround((p.y - f.offset[1]) / f.scale)));
    put_value<std::int32_t>(r, 8,
                            static_cast<std::int32_t>(std::lround((p.z - f.offset[2]) / f.scale)));
    put_value<std::uint16_t>(r, 12, 100);
    if (f.point_format >= 6) {
      r[14] = static_cast<std::uint8_t>(p.return_number | p.number_of_returns << 4);
      r[16] = static_cast<std::uint8_t>(p.classification);
      put_value<std::int16_t>(r, 18,
                              static_cast<std::int16_t>(std::lround(p.scan_angle_deg / 0.006)));
      put_value<double>(r, 22, p.gps_time);
    } else {
      r[14] = static_cast<std::uint8_t>(p.return_number | p.number_of_returns << 3);
      r[15] = static_cast<std::uint8_t>(p.classification);
      r[16] = static_cast<std::uint8_t>(static_cast<std::int8_t>(std::lround(p.scan_angle_deg)));
      if (f.point_format != 0 && f.point_format != 2) put_value<double>(r, 20, p.gps_time);
    }
    b.insert(b.end(), r.begin(), r.end());
  }
  return b;
}

inline void write_las(const std::filesystem::path& file, const LasFixture& f) {
  const auto b = las_bytes(f);
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

inline void write_bytes(const std::filesystem::path& file, const std::vector<std::uint8_t>& b) {
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

}  // namespace glaswave::test
