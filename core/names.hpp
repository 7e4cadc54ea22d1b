// "Did you mean": the nearest known name to a mistyped key, preset or choice, for error messages.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace glaswave {

// Levenshtein edit distance between two strings.
std::size_t edit_distance(const std::string& a, const std::string& b);

// The known name that `name` is most likely a typo of, if any is close enough to say so.
std::optional<std::string> nearest_name(const std::string& name,
                                        const std::vector<std::string>& known);

// The one wording of the suggestion, to append to an error message: `; did you mean "NAME"?`, or
// nothing when no known name is close enough.
std::string did_you_mean(const std::string& name, const std::vector<std::string>& known);

}  // namespace glaswave
