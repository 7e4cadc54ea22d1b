// The record codec: a record comes back bit for bit (zeros of either sign, NaN, long runs of
// zeros), and bytes that are not a whole record are refused.
#include "pipeline/products/record_codec.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace glaswave {
namespace {

std::vector<std::uint64_t> bits_of(const std::vector<double>& values) {
  std::vector<std::uint64_t> bits;
  for (double v : values) bits.push_back(std::bit_cast<std::uint64_t>(v));
  return bits;
}

ShotRecord make_record() {
  ShotRecord shot;
  shot.shot_number = 1234567890123456789LL;
  shot.quality_reason = reason_low_signal;
  shot.lat_deg = 45.000001;
  shot.slope_deg = std::numeric_limits<double>::quiet_NaN();
  // A waveform as the transport gives it: zeros, a return, zeros; a run of zeros longer than
  // the codec cuts runs at; -0.0 and denormals are values, not zeros.
  std::vector<double> waveform(3000, 0.0);
  for (int i = 400; i < 460; ++i) waveform[i] = 1e-9 * (i - 399);
  waveform[2999] = -0.0;
  waveform[2000] = std::numeric_limits<double>::denorm_min();
  shot.rx_waveform_W = {waveform, std::vector<double>(3000, 0.0)};
  shot.rx_waveform_canopy_W = {{}, {0.0}};
  shot.rx_energy_J = {1e-15, 0.0};
  shot.reflectance = {};
  shot.n_peaks = {2, 0};
  shot.rh_m = {std::vector<double>(101, -0.0), std::vector<double>(101, 1.5)};
  shot.footprint_lonlat = {{7.0, 45.0}, {7.1, 45.0}, {7.0, 45.1}, {7.0, 45.0}};
  return shot;
}

TEST(RecordCodec, RecordsComeBackBitForBit) {
  const ShotRecord a = make_record();
  ShotRecord b = make_record();
  b.shot_number = 7;
  b.rx_waveform_W[0][0] = 3.0;  // a waveform that starts with a value
  std::string bytes;
  encode_record(a, bytes);
  encode_record(b, bytes);
  std::size_t offset = 0;
  const ShotRecord a_back = decode_record(bytes, offset);
  const ShotRecord b_back = decode_record(bytes, offset);
  EXPECT_EQ(offset, bytes.size());
  EXPECT_EQ(a_back.shot_number, a.shot_number);
  EXPECT_EQ(b_back.shot_number, 7);
  EXPECT_EQ(a_back.quality_reason, reason_low_signal);
  EXPECT_TRUE(std::isnan(a_back.slope_deg));
  ASSERT_EQ(a_back.rx_waveform_W.size(), 2u);
  for (std::size_t band = 0; band < 2; ++band) {
    EXPECT_EQ(bits_of(a_back.rx_waveform_W[band]), bits_of(a.rx_waveform_W[band]));
    EXPECT_EQ(bits_of(b_back.rx_waveform_W[band]), bits_of(b.rx_waveform_W[band]));
    EXPECT_EQ(bits_of(a_back.rh_m[band]), bits_of(a.rh_m[band]));
  }
  EXPECT_TRUE(std::signbit(a_back.rx_waveform_W[0][2999]));
  EXPECT_EQ(a_back.rx_waveform_canopy_W, a.rx_waveform_canopy_W);
  EXPECT_EQ(a_back.rx_energy_J, a.rx_energy_J);
  EXPECT_TRUE(a_back.reflectance.empty());
  EXPECT_EQ(a_back.n_peaks, a.n_peaks);
  EXPECT_EQ(a_back.footprint_lonlat, a.footprint_lonlat);
}

TEST(RecordCodec, ZerosTakeLittleRoom) {
  ShotRecord empty;
  ShotRecord zeros;
  zeros.rx_waveform_W.assign(2, std::vector<double>(544, 0.0));
  std::string empty_bytes, zero_bytes;
  encode_record(empty, empty_bytes);
  encode_record(zeros, zero_bytes);
  // The outer length, and per band an inner length and one run.
  EXPECT_EQ(zero_bytes.size() - empty_bytes.size(), 2 * (8 + 8));
}

TEST(RecordCodec, BytesThatAreNotAWholeRecordAreRefused) {
  std::string bytes;
  encode_record(make_record(), bytes);
  for (std::size_t cut : {std::size_t{1}, bytes.size() / 2, bytes.size() - 1}) {
    std::size_t offset = 0;
    EXPECT_THROW(decode_record(std::string_view(bytes).substr(0, cut), offset), Error) << cut;
  }
  // A length that its runs could not give (a corrupt length word) asks for no memory.
  ShotRecord zeros;
  zeros.rx_waveform_W = {std::vector<double>(5443, 0.0)};
  std::string zero_bytes;
  encode_record(zeros, zero_bytes);
  const std::uint64_t length = 5443, corrupt = std::uint64_t{1} << 40;
  const std::size_t at = zero_bytes.find(std::string(reinterpret_cast<const char*>(&length), 8));
  ASSERT_NE(at, std::string::npos);
  zero_bytes.replace(at, 8, std::string(reinterpret_cast<const char*>(&corrupt), 8));
  std::size_t offset = 0;
  EXPECT_THROW(decode_record(zero_bytes, offset), Error);
}

}  // namespace
}  // namespace glaswave
