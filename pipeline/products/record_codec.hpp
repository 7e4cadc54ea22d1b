// A ShotRecord as bytes and back, bit for bit: what the run journal keeps of a finished shot
// (--resume) and what MPI ranks send to the rank that writes. Every field of the product field
// table and the footprint ring are kept, so a decoded record writes the same products as the
// original. Native byte order: a journal is resumed, and a run's ranks run, on one kind of
// machine.
#pragma once

#include <cstddef>
#include <span>
#include <string>

#include "pipeline/products/shot_record.hpp"

namespace glaswave {

// Appends `record` to `bytes`.
void encode_record(const ShotRecord& record, std::string& bytes);

// Decodes the record that starts at `offset` in `bytes` and moves `offset` past it. Throws
// Error (run) on bytes that are not a whole record.
ShotRecord decode_record(std::span<const char> bytes, std::size_t& offset);

}  // namespace glaswave
