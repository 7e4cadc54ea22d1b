// The retrieval's two commands on the command line (PRODUCT.md section 11): `glaswave table`
// (the forward table) and `glaswave retrieve` (each method's estimates, retrieval.nc). cli.cpp
// adds them and hands them its progress bar.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace glaswave {

// Makes a progress reporter counting `unit` (a bar on a terminal, lines elsewhere); quiet: none.
using ProgressFactory =
    std::function<std::function<void(std::int64_t, std::int64_t)>(bool quiet, const char* unit)>;

class RetrievalCommands {
 public:
  explicit RetrievalCommands(CLI::App& app);
  // Whether the command line chose `table` or `retrieve`.
  bool chosen() const;
  int dispatch(const std::string& command_line, const ProgressFactory& progress);

 private:
  int table(const std::string& command_line, const ProgressFactory& progress);
  int retrieve(const std::string& command_line, const ProgressFactory& progress);

  CLI::App* table_ = nullptr;
  CLI::App* retrieve_ = nullptr;
  std::string config_file, out, table_file, methods, shots, threads_text, rt_search,
      counts_per_watt, photons_per_joule, beams, bbox;
  std::vector<std::string> overrides, inputs;
  bool quiet = false, json = false, plots = false;
};

}  // namespace glaswave
