// The writers' registry (core/registry.hpp): a writer is one class and one registration in its own
// file, as the test double below is (nothing else in the tree names it), and make_writers makes
// every registered writer a run's settings ask for, in the registry's order.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/registry.hpp"
#include "pipeline/products/product_writer.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

// A writer that counts what it is given; it asks for itself when the run's command line says so.
struct CountingWriter final : ProductWriter {
  static inline int records = 0;
  void write(std::int64_t, const ShotRecord&) override { ++records; }
  void finish(const RunStats&) override {}
  void abort() noexcept override {}
};

const Registration<ProductWriter> counting_writer(
    "counting (a test double)", 99, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (c.info.command_line != "count") return nullptr;
      return std::make_unique<CountingWriter>();
    });

std::vector<std::string> names() {
  std::vector<std::string> out;
  for (const auto& entry : Registry<ProductWriter>::instance().entries()) out.push_back(entry.name);
  return out;
}

TEST(WriterRegistry, TheBuiltInWritersRegisterThemselvesInTheirOrder) {
  // Written out from docs/architecture.md's list: shots.nc first, the ICESat-2 granules last.
  const std::vector<std::string> expected = {
      "shots.nc",  "footprints", "gedi_l1b.h5",       "gedi_l2a.h5",
      "glah01.h5", "glah14.h5",  "atl03.h5 atl08.h5", "counting (a test double)"};
  EXPECT_EQ(names(), expected);
}

TEST(WriterRegistry, ATestDoubleNeedsNoEditOutsideItsOwnFile) {
  const test_support::ScratchDir dir("glaswave_writer_registry");
  ProductSettings settings;
  settings.netcdf = false;
  settings.footprints = false;
  RunInfo info;
  info.shots = 2;
  info.command_line = "count";
  auto writers = make_writers(dir.path(), settings, info);
  ASSERT_EQ(writers.size(), 1u);
  ShotRecord shot;
  writers[0]->write(0, shot);
  writers[0]->write(1, shot);
  EXPECT_EQ(CountingWriter::records, 2);
  info.command_line = "do not count";
  EXPECT_TRUE(make_writers(dir.path(), settings, info).empty());
}

TEST(WriterRegistry, TwoPartsOfOneNameIsABug) {
  EXPECT_THROW(
      Registration<ProductWriter>(
          "shots.nc", 0, [](const WriterContext&) { return std::unique_ptr<ProductWriter>(); }),
      std::logic_error);
}

}  // namespace
}  // namespace glaswave
