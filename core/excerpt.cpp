// The bounded excerpt every message quotes user input through.
#include "core/excerpt.hpp"

#include <cstdio>

namespace glaswave {
namespace {

bool continuation_byte(unsigned char byte) { return (byte & 0xC0) == 0x80; }

std::size_t characters(std::string_view text) {
  std::size_t n = 0;
  for (char c : text) n += continuation_byte(static_cast<unsigned char>(c)) ? 0 : 1;
  return n;
}

// The first `count` characters of `text`, control characters escaped.
std::string head(std::string_view text, std::size_t count) {
  std::size_t seen = 0, end = 0;
  for (; end < text.size(); ++end)
    if (!continuation_byte(static_cast<unsigned char>(text[end])) && seen++ == count) break;
  return escape_controls(text.substr(0, end));
}

}  // namespace

std::string escape_controls(std::string_view text) {
  std::string out;
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out;
}

std::string excerpt(std::string_view text) {
  const std::size_t length = characters(text);
  if (length <= excerpt_max_chars) return head(text, length);
  return head(text, excerpt_max_chars) + "... (" + std::to_string(length) + " characters)";
}

std::string quoted_excerpt(std::string_view text) {
  const std::size_t length = characters(text);
  std::string out(1, '"');  // not "\"" + std::string: GCC 12 warns of a false overlap there
  if (length <= excerpt_max_chars) return out.append(head(text, length)).append(1, '"');
  return out.append(head(text, excerpt_max_chars))
      .append("...\" (" + std::to_string(length) + " characters)");
}

}  // namespace glaswave
