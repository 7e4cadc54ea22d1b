// What the configuration tests share: documents from JSON text and the errors they raise.
#pragma once

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"

namespace glaswave::test_support {

// A configuration document from JSON text; a flat plane is added when the text has no terrain,
// since the terrain is the one section without a default.
inline nlohmann::json doc(const std::string& text) {
  nlohmann::json d = nlohmann::json::parse(text);
  if (!d.contains("terrain")) d["terrain"] = {{"plane", nlohmann::json::object()}};
  return d;
}

// The message of the configuration error parse_config throws, or "" when it throws none.
inline std::string error_of(const nlohmann::json& document) {
  try {
    parse_config(document);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::config);
    EXPECT_EQ(e.exit_status(), 2);
    return e.what();
  }
  return "";
}

}  // namespace glaswave::test_support
