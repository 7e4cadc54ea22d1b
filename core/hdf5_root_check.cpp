// The root group of a version 0 or 1 superblock, checked on the file's bytes (the HDF5 file
// format specification, version 2.0: the superblock, the symbol table entry, version 1 object
// headers, the symbol table message and the local heap).
#include "core/hdf5_root_check.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

namespace glaswave {
namespace {

constexpr std::uint64_t kUndefined = ~std::uint64_t{0};

// The file's bytes [at, at + size), or none when the file is shorter.
std::optional<std::vector<unsigned char>> read_at(std::ifstream& in, std::uint64_t at,
                                                  std::size_t size) {
  std::vector<unsigned char> bytes(size);
  in.clear();
  in.seekg(static_cast<std::streamoff>(at));
  if (!in || !in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
    return std::nullopt;
  return bytes;
}

std::uint64_t word(const unsigned char* p, int bytes) {
  std::uint64_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = value << 8 | p[i];  // little-endian
  return value;
}

}  // namespace

std::optional<std::string> hdf5_root_fault(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::error_code error;
  const std::uint64_t file_bytes = std::filesystem::file_size(file, error);
  if (!in || error) return std::nullopt;  // HDF5 says what is wrong
  // The superblock at 0 (a user block before it moves it: left to HDF5).
  const auto head = read_at(in, 0, 100);
  if (!head || std::memcmp(head->data(), "\x89HDF\r\n\x1a\n", 8) != 0) return std::nullopt;
  const int version = (*head)[8];
  if (version > 1 || (*head)[13] != 8 || (*head)[14] != 8) return std::nullopt;
  const std::size_t at = version == 0 ? 24 : 28;  // v1 adds the indexed storage K and 2 bytes
  const std::uint64_t base = word(head->data() + at, 8);
  const std::uint64_t eof = word(head->data() + at + 16, 8);
  if (base != 0) return std::nullopt;  // addresses relative to a moved base: left to HDF5
  const std::uint64_t end = std::min(eof, file_bytes);
  const std::size_t entry = at + 32;  // the root group's symbol table entry
  const std::uint64_t header = word(head->data() + entry + 8, 8);
  if (header == kUndefined || header + 16 > end)
    return "its root group's object header lies beyond the file's end";
  // A version 1 object header: version, reserved, messages (2), references (4), size (4), then
  // messages from the next multiple of 8: type (2), size (2), flags, 3 reserved, the data.
  const auto object = read_at(in, header, 16);
  if (!object || (*object)[0] != 1) return std::nullopt;  // another layout: left to HDF5
  const std::uint64_t messages_bytes = word(object->data() + 8, 4);
  if (header + 16 + messages_bytes > end)
    return "its root group's object header runs past the file's end";
  const auto messages = read_at(in, header + 16, static_cast<std::size_t>(messages_bytes));
  if (!messages) return "its root group's object header is cut short";
  for (std::size_t m = 0; m + 8 <= messages->size();) {
    const std::uint64_t type = word(messages->data() + m, 2);
    const std::uint64_t size = word(messages->data() + m + 2, 2);
    if (m + 8 + size > messages->size()) break;  // HDF5 says what is wrong
    if (type == 0x11 && size >= 16) {            // the symbol table: its B-tree and local heap
      const std::uint64_t tree = word(messages->data() + m + 8, 8);
      const std::uint64_t heap = word(messages->data() + m + 16, 8);
      if (tree == kUndefined || tree >= end || heap == kUndefined || heap + 32 > end)
        return "its root group's symbol table names an address beyond the file's end";
      // The local heap: "HEAP", version 0, 3 reserved, data size (8), free list (8), address.
      const auto local = read_at(in, heap, 32);
      if (!local || std::memcmp(local->data(), "HEAP", 4) != 0)
        return "its root group's local heap is not where its symbol table says";
      const std::uint64_t data_bytes = word(local->data() + 8, 8);
      const std::uint64_t data = word(local->data() + 24, 8);
      if (data == kUndefined || data > end || data_bytes > end - data)
        return "its root group's local heap runs past the file's end";
    }
    m += 8 + static_cast<std::size_t>(size);
  }
  return std::nullopt;
}

}  // namespace glaswave
