// The run journal on its own: a batch larger than a frame goes into several frames, each
// compressed at once, and comes back whole, in order, with the batch's ray queries counted once.
#include "pipeline/engine/journal.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test_support::ScratchDir;

// The file's header and its frames, walked by their sizes: a header (three words, the third the
// length of the input files' stamps after it), then per frame six
// words (marker, first record, records, ray queries, payload size, raw size), the payload and a
// checksum word.
struct JournalBytes {
  std::string header;
  std::vector<std::string> frames;
};

JournalBytes split_frames(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  JournalBytes bytes;
  std::array<std::uint64_t, 3> head{};
  in.read(reinterpret_cast<char*>(head.data()), sizeof head);
  bytes.header.assign(reinterpret_cast<const char*>(head.data()), sizeof head);
  bytes.header.resize(sizeof head + head[2]);
  in.read(bytes.header.data() + sizeof head, static_cast<std::streamsize>(head[2]));
  std::array<std::uint64_t, 6> words{};
  while (in.read(reinterpret_cast<char*>(words.data()), sizeof words)) {
    std::string frame(reinterpret_cast<const char*>(words.data()), sizeof words);
    frame.resize(sizeof words + words[4] + sizeof(std::uint64_t));
    in.read(frame.data() + sizeof words, static_cast<std::streamsize>(frame.size() - sizeof words));
    bytes.frames.push_back(std::move(frame));
  }
  return bytes;
}

int count_frames(const std::filesystem::path& file) {
  return static_cast<int>(split_frames(file).frames.size());
}

TEST(RunJournal, ABatchLargerThanAFrameComesBackWhole) {
  const ScratchDir dir;
  const auto path = dir.path() / RunJournal::kFileName;
  // Records of random waveforms (nothing to compress, no zeros to leave out), three frames' worth
  // in one batch, then a small batch.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> power_W(1e-9, 1e-6);
  const std::size_t bins = RunJournal::kFrameBytes / sizeof(double) / 2;  // two records a frame
  std::vector<ShotRecord> batch(5), small(1);
  for (std::size_t i = 0; i < batch.size(); ++i) {
    batch[i].shot_number = static_cast<std::int64_t>(i);
    batch[i].rx_waveform_W.assign(1, std::vector<double>(bins));
    for (double& value : batch[i].rx_waveform_W[0]) value = power_W(rng);
  }
  small[0].shot_number = 5;
  small[0].rx_waveform_W = {{1.0, 0.0, 2.0}};
  {
    RunJournal journal(path, "identity");
    journal.append(batch, 1000);
    journal.append(small, 7);
  }
  EXPECT_GE(count_frames(path), 4);  // the large batch split, the small one alone

  std::vector<ShotRecord> back;
  std::int64_t ray_queries = 0;
  RunJournal::resume(
      path, "identity", [&](const ShotRecord& record) { back.push_back(record); }, ray_queries);
  ASSERT_EQ(back.size(), 6u);
  EXPECT_EQ(ray_queries, 1007);  // each batch's queries once, not once a frame
  for (std::size_t i = 0; i < batch.size(); ++i) {
    EXPECT_EQ(back[i].shot_number, static_cast<std::int64_t>(i));
    EXPECT_EQ(back[i].rx_waveform_W, batch[i].rx_waveform_W) << i;
  }
  EXPECT_EQ(back[5].rx_waveform_W, small[0].rx_waveform_W);
}

// Found by tests/reliability/inputs_tried.py: a journal whose frames were each whole (their
// checksums right) but repeated, lost or swapped resumed "successfully", doubling some shots and
// losing others. Each frame says where its records begin in the run: such a journal is refused.
TEST(RunJournal, FramesRepeatedMissingOrSwappedAreRefused) {
  const ScratchDir dir;
  const auto path = dir.path() / RunJournal::kFileName;
  {
    RunJournal journal(path, "identity");
    for (std::int64_t batch = 0; batch < 3; ++batch) {
      std::vector<ShotRecord> records(2);
      for (std::size_t i = 0; i < records.size(); ++i) records[i].shot_number = 2 * batch + i;
      journal.append(records, 10);
    }
  }
  const JournalBytes bytes = split_frames(path);
  ASSERT_EQ(bytes.frames.size(), 3u);
  const auto& f = bytes.frames;
  const std::vector<std::pair<std::string, std::vector<std::string>>> broken = {
      {"repeated", {f[0], f[1], f[1], f[2]}},
      {"repeated in place of another", {f[0], f[1], f[1]}},
      {"missing", {f[0], f[2]}},
      {"swapped", {f[0], f[2], f[1]}},
  };
  for (const auto& [what, frames] : broken) {
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out << bytes.header;
      for (const std::string& frame : frames) out << frame;
    }
    std::int64_t ray_queries = 0;
    try {
      RunJournal::resume(
          path, "identity", [](const ShotRecord&) {}, ray_queries);
      ADD_FAILURE() << what << ": resumed";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::config) << what;
      EXPECT_NE(std::string(e.what()).find("(frames repeated, missing or out of order): the "
                                           "journal does not describe one run"),
                std::string::npos)
          << what << ": " << e.what();
    }
  }
  // The frames in their order still resume, each record once.
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes.header << f[0] << f[1] << f[2];
  }
  std::vector<std::int64_t> shots;
  std::int64_t ray_queries = 0;
  RunJournal::resume(
      path, "identity", [&](const ShotRecord& r) { shots.push_back(r.shot_number); }, ray_queries);
  EXPECT_EQ(shots, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(ray_queries, 30);
}

// Found by tests/reliability/inputs_tried.py: a journal replaced by a FIFO was waited on for
// ever by --resume; it is refused by the regular-file rule before it is opened.
TEST(RunJournal, AFifoIsRefusedNotWaitedOn) {
  const ScratchDir dir;
  const auto path = dir.path() / RunJournal::kFileName;
  ASSERT_EQ(mkfifo(path.c_str(), 0600), 0);
  std::int64_t ray_queries = 0;
  try {
    RunJournal::resume(
        path, "identity", [](const ShotRecord&) {}, ray_queries);
    ADD_FAILURE() << "resumed";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              path.string() +
                  ": cannot read the run journal: it is a FIFO (a pipe), not a "
                  "regular file");
  }
}

// Found by fuzz_journal: a frame whose payload-size word was damaged to near 2 GB (within what
// LZ4 takes) had its 2 GB allocated, and filled, before the read found the file ended; the
// fuzzer's 2 GB memory limit stopped it. A payload longer than what is left of the file is a
// torn end, found before anything is allocated: the frames before it resume, and it goes.
TEST(RunJournal, AFrameLongerThanTheFileIsTornAndNotAllocated) {
  const ScratchDir dir;
  const auto path = dir.path() / RunJournal::kFileName;
  {
    RunJournal journal(path, "identity");
    for (std::int64_t batch = 0; batch < 2; ++batch) {
      std::vector<ShotRecord> records(1);
      records[0].shot_number = batch;
      journal.append(records, 10);
    }
  }
  JournalBytes bytes = split_frames(path);
  ASSERT_EQ(bytes.frames.size(), 2u);
  const std::uint64_t damaged_size = 0x7e000000;  // within LZ4_COMPRESSBOUND(LZ4_MAX_INPUT_SIZE)
  std::memcpy(bytes.frames[1].data() + 4 * sizeof(std::uint64_t), &damaged_size,
              sizeof damaged_size);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes.header << bytes.frames[0] << bytes.frames[1];
  }
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  std::vector<std::int64_t> shots;
  std::int64_t ray_queries = 0;
  RunJournal::resume(
      path, "identity", [&](const ShotRecord& r) { shots.push_back(r.shot_number); }, ray_queries);
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_EQ(shots, (std::vector<std::int64_t>{0}));
  EXPECT_EQ(std::filesystem::file_size(path), bytes.header.size() + bytes.frames[0].size());
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256L * 1024);  // kB: nowhere near the 2 GB
}

// Issue 42: --resume checked the configuration, not its input files: a voxel grid or trees file
// changed between the killed run and its resume gave products half of each. The journal keeps
// each input's size, time and hash; a changed size or content is refused naming the file, a
// touched file of the same bits resumes.
TEST(RunJournal, AResumeOverAChangedInputIsRefusedNamingTheFile) {
  const ScratchDir dir;
  const auto path = dir.path() / RunJournal::kFileName;
  const auto grid = dir.path() / "grid.nc";
  const auto crowns = dir.path() / "crowns.csv";
  const std::string grid_bytes(3 << 20, 'g');  // three of the hash's 1 MiB reads
  std::ofstream(grid, std::ios::binary) << grid_bytes;
  std::ofstream(crowns, std::ios::binary) << "x,y\n1,2\n";
  const std::vector<std::string> files = {grid.string(), crowns.string()};
  {
    RunJournal journal(path, "identity", stamp_input_files(files));
    std::vector<ShotRecord> records(1);
    journal.append(records, 10);
  }
  const std::string saved = [&] {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }();
  auto resume = [&]() -> std::string {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << saved;
    std::int64_t ray_queries = 0, records = 0;
    try {
      RunJournal::resume(
          path, "identity", [&](const ShotRecord&) { ++records; }, ray_queries,
          stamp_input_files(files));
    } catch (const Error& e) {
      return e.what();
    }
    return "resumed " + std::to_string(records);
  };
  EXPECT_EQ(resume(), "resumed 1");
  // Touched: another time, the same bits.
  const auto when = std::filesystem::last_write_time(grid);
  std::filesystem::last_write_time(grid, when + std::chrono::hours(1));
  EXPECT_EQ(resume(), "resumed 1");
  // One byte of the last MiB changed, the size and time kept.
  {
    std::fstream out(grid, std::ios::binary | std::ios::in | std::ios::out);
    out.seekp(static_cast<std::streamoff>(grid_bytes.size() - 5));
    out.put('h');
  }
  std::filesystem::last_write_time(grid, when);
  EXPECT_EQ(
      resume().rfind(
          grid.string() + ": changed since the interrupted run began (its content: modified ", 0),
      0u)
      << resume();
  std::ofstream(grid, std::ios::binary | std::ios::trunc) << grid_bytes;
  EXPECT_EQ(resume(), "resumed 1");
  // A row added to the crowns.
  std::ofstream(crowns, std::ios::binary | std::ios::app) << "3,4\n";
  EXPECT_EQ(resume(), crowns.string() +
                          ": changed since the interrupted run began (12 bytes, were 8): --resume "
                          "would write products half from the old file and half from the new; "
                          "restore the file, or run again into a new output directory");
}

// The hash of a file read in pieces of any length is that of the file read at once (the
// reads' 1 MiB do not decide it), and differs with any one byte, or one byte more.
TEST(RunJournal, AnInputsHashIsThatOfItsBytesWhateverThePieces) {
  std::mt19937_64 rng(3);
  std::string bytes(100003, '\0');
  for (char& c : bytes) c = static_cast<char>(rng());
  ContentHash whole;
  whole.update(bytes.data(), bytes.size());
  for (std::size_t piece : {1, 7, 31, 32, 33, 4096}) {
    ContentHash pieces;
    for (std::size_t at = 0; at < bytes.size(); at += piece)
      pieces.update(bytes.data() + at, std::min(piece, bytes.size() - at));
    EXPECT_EQ(pieces.digest(), whole.digest()) << piece;
  }
  std::vector<std::uint64_t> digests = {whole.digest()};
  for (std::size_t at : {std::size_t{0}, std::size_t{40}, bytes.size() - 1}) {
    std::string changed = bytes;
    changed[at] ^= 1;
    ContentHash h;
    h.update(changed.data(), changed.size());
    digests.push_back(h.digest());
  }
  ContentHash longer;
  longer.update((bytes + '\0').data(), bytes.size() + 1);
  digests.push_back(longer.digest());
  std::sort(digests.begin(), digests.end());
  EXPECT_EQ(std::unique(digests.begin(), digests.end()), digests.end());
}

}  // namespace
}  // namespace glaswave
