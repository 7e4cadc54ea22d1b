// Configuration text: a JSON file read with its faults placed (line, column and key path of a
// malformed token or a number nlohmann-json refuses), and the `--set KEY=VALUE` overrides applied
// to the document before it is parsed into settings.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace glaswave {

// Reads a JSON file; malformed JSON is an error naming the file, line and column.
nlohmann::json read_json_file(const std::filesystem::path& file);

// Applies one `--set KEY=VALUE` override: KEY is a dotted path ("canopy.pai"); VALUE is parsed
// as JSON when it parses, else taken as a string.
void apply_override(nlohmann::json& document, const std::string& assignment);

}  // namespace glaswave
