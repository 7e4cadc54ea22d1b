// The run journal on its own: a batch larger than a frame goes into several frames, each
// compressed at once, and comes back whole, in order, with the batch's ray queries counted once.
#include "pipeline/engine/journal.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <fstream>
#include <random>
#include <vector>

#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test_support::ScratchDir;

// Frames in the file, walked by their sizes: a 16-byte header, then per frame five words
// (marker, records, ray queries, payload size, raw size), the payload and a checksum word.
int count_frames(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(16);
  int frames = 0;
  std::array<std::uint64_t, 5> words{};
  while (in.read(reinterpret_cast<char*>(words.data()), sizeof words)) {
    ++frames;
    in.seekg(static_cast<std::streamoff>(words[3] + sizeof(std::uint64_t)), std::ios::cur);
  }
  return frames;
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

}  // namespace
}  // namespace glaswave
