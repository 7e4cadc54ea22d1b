// The record codec: the product field table's members in table order, then the footprint
// ring. Scalars are their bytes; a vector is its length (uint64) and its elements, except that a
// vector of doubles gives its elements as runs: the count of zeros (+0.0, bit for bit), the
// count of values that follow (uint32 each), those values, until the length is reached. A
// waveform is mostly zeros before and after its return: this keeps a 19-ray shot's record a
// fifth of its size, which the journal would otherwise spend its time deflating.
#include "pipeline/products/record_codec.hpp"

#include <cstdint>
#include <cstring>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/error.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

// Runs of zeros are cut at this length, so that corrupt bytes cannot ask for more than this
// many elements per 8 bytes.
constexpr std::uint32_t kMostZerosPerRun = 1024;

bool is_zero(double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  return bits == 0;
}

template <class T>
void put(const T& value, std::string& bytes);

// A vector of doubles as runs of zeros and of values.
void put_runs(const std::vector<double>& values, std::string& bytes) {
  put(static_cast<std::uint64_t>(values.size()), bytes);
  std::size_t i = 0;
  while (i < values.size()) {
    const std::size_t zeros_from = i;
    while (i < values.size() && i - zeros_from < kMostZerosPerRun && is_zero(values[i])) ++i;
    const std::size_t values_from = i;
    while (i < values.size() && !is_zero(values[i])) ++i;
    put(static_cast<std::uint32_t>(values_from - zeros_from), bytes);
    put(static_cast<std::uint32_t>(i - values_from), bytes);
    bytes.append(reinterpret_cast<const char*>(values.data() + values_from),
                 (i - values_from) * sizeof(double));
  }
}

template <class T>
void put(const T& value, std::string& bytes) {
  if constexpr (std::is_same_v<T, std::vector<double>>) {
    put_runs(value, bytes);
  } else if constexpr (std::is_arithmetic_v<T>) {
    bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
  } else if constexpr (std::is_same_v<T, std::array<double, 2>>) {
    bytes.append(reinterpret_cast<const char*>(value.data()), sizeof value);
  } else {
    put(static_cast<std::uint64_t>(value.size()), bytes);
    for (const auto& element : value) put(element, bytes);
  }
}

class Reader {
 public:
  Reader(std::span<const char> bytes, std::size_t& offset) : bytes_(bytes), offset_(offset) {}

  template <class T>
  void get(T& value) {
    if constexpr (std::is_same_v<T, std::vector<double>>) {
      get_runs(value);
    } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::array<double, 2>>) {
      take(&value, sizeof value);
    } else {
      std::uint64_t size = 0;
      get(size);
      // Each element takes at least a byte: a length beyond what is left is corrupt.
      if (size > bytes_.size() - offset_) fail();
      value.resize(size);
      for (auto& element : value) get(element);
    }
  }

 private:
  void get_runs(std::vector<double>& values) {
    std::uint64_t size = 0;
    get(size);
    // 8 bytes give at most kMostZerosPerRun elements: a length beyond that is corrupt.
    if (size > (bytes_.size() - offset_) / 8 * kMostZerosPerRun) fail();
    values.assign(size, 0.0);
    std::size_t i = 0;
    while (i < size) {
      std::uint32_t zeros = 0, nonzero = 0;
      get(zeros);
      get(nonzero);
      if (zeros > kMostZerosPerRun || zeros + std::uint64_t{nonzero} == 0 ||
          zeros + std::uint64_t{nonzero} > size - i)
        fail();
      i += zeros;
      take(values.data() + i, nonzero * sizeof(double));
      i += nonzero;
    }
  }

  void take(void* out, std::size_t size) {
    if (size > bytes_.size() - offset_) fail();
    std::memcpy(out, bytes_.data() + offset_, size);
    offset_ += size;
  }
  [[noreturn]] static void fail() {
    throw run_error("record", "truncated or corrupt record bytes");
  }

  std::span<const char> bytes_;
  std::size_t& offset_;
};

}  // namespace

void encode_record(const ShotRecord& record, std::string& bytes) {
  for (const ProductField& field : product_fields())
    std::visit([&](auto member) { put(record.*member, bytes); }, field.field);
  put(record.footprint_lonlat, bytes);
}

ShotRecord decode_record(std::span<const char> bytes, std::size_t& offset) {
  ShotRecord record;
  Reader reader(bytes, offset);
  for (const ProductField& field : product_fields())
    std::visit([&](auto member) { reader.get(record.*member); }, field.field);
  reader.get(record.footprint_lonlat);
  return record;
}

}  // namespace glaswave
