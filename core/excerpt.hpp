// The one way a message quotes what a user or a file gave (a key, a value, a name, a path): a
// bounded excerpt, so that a 200,000-character key or a 1 MB string is never echoed whole and a
// message stays one short line whatever the input.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace glaswave {

// The most characters of the input a message quotes.
inline constexpr std::size_t excerpt_max_chars = 60;

// `text` for a message: whole when it has at most excerpt_max_chars characters (UTF-8 code
// points), else its first excerpt_max_chars followed by "... (N characters)". Control characters
// (escape codes, newlines) are written \xNN, so that nothing reaches a terminal raw.
std::string excerpt(std::string_view text);

// `text` whole, its control characters (escape codes, newlines) written \xNN: a one-line message
// on a terminal.
std::string escape_controls(std::string_view text);

// The excerpt in double quotes: `"pai"`, `"aaaa..." (200000 characters)`.
std::string quoted_excerpt(std::string_view text);

}  // namespace glaswave
