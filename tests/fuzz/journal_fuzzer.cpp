// Fuzzes the run journal's reader (pipeline/engine/journal, what --resume reads): a journal of
// this run's identity whose frames the input describes, then damages. A frame holds up to three
// small records (shot numbers, a short waveform); the input picks the frames, then repeats or
// drops whole frames, cuts the file or flips a byte. An input that starts "GWJRNL" is
// instead the bytes after the header, as they are. The reader must hand on records in order,
// each once, never beyond those written, or refuse with an Error (issue 28: frames repeated with
// valid checksums resumed into doubled and lost shots); anything else is a finding.
#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "pipeline/engine/journal.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

constexpr const char* kIdentity = "fuzz";

glaswave::ShotRecord record(std::int64_t shot) {
  glaswave::ShotRecord r;
  r.shot_number = shot;
  r.time_s = 0.5 * static_cast<double>(shot);
  r.rx_waveform_W = {{1e-9 * static_cast<double>(shot), 0.0, 2e-9}};
  return r;
}

std::string read_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  const std::filesystem::path file = fuzz::scratch_dir() / "glaswave.journal";
  std::int64_t written = 0;  // records the journal was given, in order
  {
    RunJournal journal(file, kIdentity);
    if (size >= 6 && std::memcmp(data, "GWJRNL", 6) == 0) {
      journal.sync();
      std::ofstream(file, std::ios::binary | std::ios::app)
          .write(reinterpret_cast<const char*>(data) + 6, static_cast<std::streamsize>(size - 6));
      written = -1;  // unknown
    } else {
      FuzzedDataProvider in(data, size);
      const int frames = in.ConsumeIntegralInRange(0, 6);
      for (int f = 0; f < frames; ++f) {
        std::vector<ShotRecord> records;
        const int count = in.ConsumeIntegralInRange(0, 3);
        for (int k = 0; k < count; ++k) records.push_back(record(written++));
        journal.append(records, in.ConsumeIntegralInRange(0, 100));
      }
      journal.sync();
      // The damage: whole frames moved (found by their marker words), a cut, a flipped byte.
      std::string bytes = read_bytes(file);
      std::vector<std::size_t> starts;
      // The header of no input files: magic, identity, the stamps' length and their count.
      constexpr std::size_t kHeader = 32;
      for (std::size_t at = kHeader; at + 8 <= bytes.size(); ++at) {
        std::uint64_t word = 0;
        std::memcpy(&word, bytes.data() + at, sizeof word);
        if (at + 48 <= bytes.size() && word != 0 && bytes.compare(at, 8, bytes, kHeader, 8) == 0)
          starts.push_back(at);
      }
      starts.push_back(bytes.size());
      const std::size_t whole = starts.size() - 1;
      switch (in.ConsumeIntegralInRange(0, 4)) {
        case 1:  // a frame repeated after itself
          if (whole > 0) {
            const std::size_t f = in.ConsumeIntegralInRange<std::size_t>(0, whole - 1);
            bytes.insert(starts[f + 1], bytes.substr(starts[f], starts[f + 1] - starts[f]));
          }
          break;
        case 2:  // a frame dropped
          if (whole > 0) {
            const std::size_t f = in.ConsumeIntegralInRange<std::size_t>(0, whole - 1);
            bytes.erase(starts[f], starts[f + 1] - starts[f]);
          }
          break;
        case 3:  // the file cut
          bytes.resize(in.ConsumeIntegralInRange<std::size_t>(0, bytes.size()));
          break;
        case 4:  // a byte flipped
          if (!bytes.empty())
            bytes[in.ConsumeIntegralInRange<std::size_t>(0, bytes.size() - 1)] ^=
                static_cast<char>(in.ConsumeIntegralInRange(1, 255));
          break;
        default:
          break;
      }
      std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
    }
  }
  try {
    std::int64_t next = 0, ray_queries = 0;
    RunJournal::resume(
        file, kIdentity,
        [&](const ShotRecord& r) {
          // In order, each once, and only what was written (raw bytes: anything decoded).
          if (written >= 0 && (r.shot_number != next || next >= written)) __builtin_trap();
          ++next;
        },
        ray_queries);
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  std::filesystem::remove(file);
  return 0;
}
