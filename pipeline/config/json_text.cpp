// Configuration text: JSON files read with their faults placed, and `--set` overrides applied.
#include "pipeline/config/json_text.hpp"

#include <algorithm>
#include <cerrno>
#include <fstream>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "pipeline/config/json_reader.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

// A configuration of a million `points` takes about 50 MB; nlohmann-json holds about ten times
// the text's size.
constexpr std::uintmax_t max_config_bytes = std::uintmax_t{256} << 20;

// ---- numbers nlohmann-json refuses ---------------------------------------------------------

// Where a number token sits in JSON text: line, column and the JSON pointer of its value.
struct TokenPlace {
  bool found = false;
  std::size_t line = 0;
  std::size_t column = 0;
  std::string pointer;
};

// Where a scan of JSON text stands in the nesting of objects and arrays, and on which line.
struct JsonScan {
  struct Frame {
    bool object;
    std::string key;
    std::size_t index;
  };
  std::vector<Frame> stack;
  bool expect_key = false;
  std::size_t line = 1, line_start = 0;

  // The JSON pointer of the value being scanned.
  std::string pointer() const {
    std::string p;
    for (const Frame& f : stack)
      p = f.object ? json_pointer_child(p, f.key) : p + "/" + std::to_string(f.index);
    return p;
  }

  // Skips the string that opens at text[i], taking it as the key of its object when a key is
  // expected; returns where the scan goes on.
  std::size_t skip_string(const std::string& text, std::size_t i) {
    std::size_t j = i + 1;
    while (j < text.size() && text[j] != '"') j += text[j] == '\\' ? 2 : 1;
    if (!stack.empty() && stack.back().object && expect_key) {
      try {
        stack.back().key = json::parse(text.substr(i, j - i + 1)).get<std::string>();
      } catch (const json::exception&) {
        stack.back().key = text.substr(i + 1, j - i - 1);
      }
    }
    return j + 1;
  }

  // Follows one byte of structure at text[i]: brackets, separators and newlines.
  void structure(char c, std::size_t i) {
    switch (c) {
      case '{':
        stack.push_back({true, "", 0});
        expect_key = true;
        break;
      case '[':
        stack.push_back({false, "", 0});
        break;
      case '}':
      case ']':
        if (!stack.empty()) stack.pop_back();
        break;
      case ',':
        if (!stack.empty()) {
          if (stack.back().object)
            expect_key = true;
          else
            ++stack.back().index;
        }
        break;
      case ':':
        expect_key = false;
        break;
      case '\n':
        ++line;
        line_start = i + 1;
        break;
      default:
        break;
    }
  }
};

// The end of the number token that begins at text[i].
std::size_t number_end(const std::string& text, std::size_t i) {
  while (i < text.size() &&
         std::string_view("0123456789+-.eE").find(text[i]) != std::string_view::npos)
    ++i;
  return i;
}

// nlohmann-json stops at a number that overflows a double (1e999) with an error that names the
// token but not where it is. The text before that token is valid JSON, so a small scan that
// follows objects and arrays finds the token's line, column and key path.
TokenPlace locate_number(const std::string& text, const std::string& token) {
  JsonScan scan;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '"') {
      i = scan.skip_string(text, i);
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      const std::size_t end = number_end(text, i);
      if (text.compare(i, end - i, token) == 0)
        return {true, scan.line, i - scan.line_start + 1, scan.pointer()};
      i = end;
    } else {
      scan.structure(c, i);
      ++i;
    }
  }
  return {};
}

// The token of nlohmann-json's "number overflow parsing '1e999'" message.
std::string overflow_token(const std::string& what) {
  const std::string marker = "number overflow parsing '";
  const auto begin = what.find(marker);
  if (begin == std::string::npos) return "";
  const auto end = what.find('\'', begin + marker.size());
  return what.substr(begin + marker.size(), end - begin - marker.size());
}

// The dotted key of an override as a JSON pointer ("canopy.pai" -> "/canopy/pai").
std::string dotted_to_pointer(const std::vector<std::string>& parts) {
  std::string p;
  for (const std::string& part : parts) p = json_pointer_child(p, part);
  return p;
}
}  // namespace

json read_json_file(const std::filesystem::path& file) {
  std::error_code ec;
  // A device or a pipe (/dev/zero) would be read for ever, and opening a pipe nobody writes
  // waits for ever: a configuration is a file, and a small one, which is seen before opening.
  require_input_file(file.native(), "the configuration", ErrorKind::config);
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw config_error(file.string(),
                       "cannot read: " + std::generic_category().message(errno ? errno : ENOENT));
  }
  if (std::filesystem::file_size(file, ec) > max_config_bytes)
    throw config_error(file.string(), "is larger than the limit of " +
                                          std::to_string(max_config_bytes >> 20) +
                                          " MiB for a configuration");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw config_error(file.string(), "cannot read: input/output error");
  const std::string text = buffer.str();
  try {
    return parse_json_checked(text);
  } catch (const Error& e) {
    throw config_error(e.place(), e.message() + " (" + file.string() + ")");
  } catch (const json::parse_error& e) {
    // nlohmann-json's own "line 3, column 0" goes astray when the bad token ends a line, so the
    // place is counted here from the byte offset, which is exact: the last byte it read.
    const std::size_t offset = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    const std::size_t newline = offset == 0 ? std::string::npos : text.rfind('\n', offset - 1);
    const std::size_t line_start = newline == std::string::npos ? 0 : newline + 1;
    const auto line = 1 + std::count(text.begin(), text.begin() + offset, '\n');
    const std::size_t column = offset - line_start + 1;
    // The cause, without "[json.exception.parse_error.101] parse error at line 3, column 0: ".
    std::string cause = e.what();
    const auto at = cause.find("parse error");
    const auto colon = cause.find(": ", at == std::string::npos ? 0 : at);
    if (colon != std::string::npos) cause = cause.substr(colon + 2);
    // nlohmann-json quotes what it last read, which may be a whole line of a file of another
    // kind: a few characters are enough to find the place.
    const auto last_read = cause.find("; last read: '");
    if (last_read != std::string::npos) {
      const std::size_t begin = last_read + 14;
      const std::size_t end = cause.rfind('\'');
      std::string excerpt = cause.substr(begin, end > begin ? end - begin : 0);
      if (excerpt.size() > 12) excerpt = "..." + excerpt.substr(excerpt.size() - 12);
      cause = cause.substr(0, begin) + excerpt + "'";
    }
    for (char& c : cause)
      if (c == '\n' || c == '\r') c = ' ';
    throw config_error(file.string(), "malformed JSON at line " + std::to_string(line) +
                                          ", column " + std::to_string(column) + ": " + cause);
  } catch (const json::out_of_range& e) {
    const std::string token = overflow_token(e.what());
    const TokenPlace place = locate_number(text, token);
    if (token.empty() || !place.found) throw config_error(file.string(), e.what());
    throw config_error(place.pointer.empty() ? file.string() : place.pointer,
                       "must be a finite number, got " + token + " (" + file.string() + ", line " +
                           std::to_string(place.line) + ", column " + std::to_string(place.column) +
                           ")");
  }
}

void apply_override(json& document, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos)
    throw config_error("--set", "expected KEY=VALUE, got " + quoted_excerpt(assignment));
  const std::string key = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  if (key.empty()) throw config_error("--set", "empty key in " + quoted_excerpt(assignment));
  std::vector<std::string> parts;
  for (std::size_t begin = 0;;) {
    const auto dot = key.find('.', begin);
    parts.push_back(key.substr(begin, dot - begin));
    if (parts.back().empty())
      throw config_error("--set", "empty part in the key " + quoted_excerpt(key) + " of " +
                                      quoted_excerpt(assignment));
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }

  json value;
  try {
    value = parse_json_checked(text, dotted_to_pointer(parts));
  } catch (const Error& e) {
    throw config_error(e.place(), e.message() + " (from --set " + excerpt(key) + ")");
  } catch (const json::parse_error&) {
    value = text;  // not JSON: a bare string such as a path or a name
  } catch (const json::out_of_range&) {
    throw config_error(dotted_to_pointer(parts), "must be a finite number, got " + excerpt(text) +
                                                     " (from --set " + excerpt(key) + ")");
  }

  if (document.is_null()) document = json::object();
  json* node = &document;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    const bool last = i + 1 == parts.size();
    if (node->is_array()) {
      // Array elements by index, as in "sensor.bands.1.pulse_energy_mJ".
      std::size_t index = 0;
      bool numeric = !part.empty();
      for (char c : part) numeric = numeric && c >= '0' && c <= '9';
      if (numeric) index = std::stoul(part);
      if (!numeric || index >= node->size()) {
        throw config_error("--set", "cannot set " + quoted_excerpt(key) + ": " +
                                        quoted_excerpt(part) + " is not an index of an array of " +
                                        std::to_string(node->size()));
      }
      node = &(*node)[index];
    } else if (node->is_object()) {
      node = &(*node)[part];
    } else {
      throw config_error("--set", "cannot set " + quoted_excerpt(key) + ": the value above " +
                                      quoted_excerpt(part) + " is " + describe(*node) +
                                      ", not an object");
    }
    if (last) {
      *node = value;
    } else if (node->is_null()) {
      *node = json::object();  // create intermediate objects, also in place of a null
    }
  }
}

}  // namespace glaswave
