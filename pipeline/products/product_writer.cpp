// The record ledger every writer keeps, and a run's writers made from the registered ones (each
// writer registers itself in its own .cpp).
#include "pipeline/products/product_writer.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "core/registry.hpp"

namespace glaswave {

RecordLedger::RecordLedger(std::filesystem::path product, std::int64_t shots)
    : product_(std::move(product)),
      written_(static_cast<std::size_t>(std::max<std::int64_t>(0, shots))) {}

void RecordLedger::fail(const std::string& message) const {
  throw run_error(product_.string(), message);
}

void RecordLedger::check_write(std::int64_t index) const {
  if (finished_) fail("write after finish");
  if (index < 0 || index >= shots())
    fail("record index " + std::to_string(index) + " outside [0, " + std::to_string(shots()) + ")");
  if (written_[static_cast<std::size_t>(index)])
    fail("record " + std::to_string(index) + " written twice");
}

void RecordLedger::check_finish() const {
  if (finished_) fail("finished twice");
  for (std::size_t i = 0; i < written_.size(); ++i)
    if (!written_[i]) fail("record " + std::to_string(i) + " was never written");
}

std::vector<std::unique_ptr<ProductWriter>> make_writers(const std::filesystem::path& out_dir,
                                                         const ProductSettings& settings,
                                                         const RunInfo& info,
                                                         const Icesat2ProductSettings& icesat2) {
  const WriterContext context{out_dir, settings, info, icesat2};
  std::vector<std::unique_ptr<ProductWriter>> writers;
  for (const auto& entry : Registry<ProductWriter>::instance().entries())
    if (auto writer = entry.make(context)) writers.push_back(std::move(writer));
  return writers;
}

}  // namespace glaswave
