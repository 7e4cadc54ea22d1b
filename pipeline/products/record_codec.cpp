// The record codec: the product field table's members in table order, then the footprint
// ring. Scalars are their bytes; a vector is its length (uint64) and its elements.
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

template <class T>
void put(const T& value, std::string& bytes) {
  if constexpr (std::is_arithmetic_v<T>) {
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
    if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::array<double, 2>>) {
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
