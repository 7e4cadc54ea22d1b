// "Did you mean": the nearest known name to a mistyped one.
#include "core/names.hpp"

#include <algorithm>
#include <cctype>
#include <limits>

namespace glaswave {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::optional<std::string> nearest_name(const std::string& name,
                                        const std::vector<std::string>& known) {
  auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string name_lower = lower(name);
  // A key without its unit ("slope" for "slope_deg") is a typo of the one key it begins.
  std::optional<std::string> completion;
  int completions = 0;
  for (const std::string& candidate : known) {
    if (lower(candidate).rfind(name_lower + "_", 0) == 0) {
      completion = candidate;
      ++completions;
    }
  }
  if (completions == 1) return completion;
  const std::string* best = nullptr;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const std::string& candidate : known) {
    const std::size_t d = edit_distance(name_lower, lower(candidate));
    if (d < best_distance) {
      best_distance = d;
      best = &candidate;
    }
  }
  if (!best) return std::nullopt;
  // Two edits catch swapped letters ("pia" for "pai"); a third of the length allows for longer
  // misspellings. Beyond that a suggestion is a guess.
  const std::size_t longest = std::max(name.size(), best->size());
  if (best_distance <= std::max<std::size_t>(2, longest / 3) && best_distance < longest)
    return *best;
  return std::nullopt;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& known) {
  const auto nearest = nearest_name(name, known);
  return nearest ? "; did you mean \"" + *nearest + "\"?" : std::string();
}

}  // namespace glaswave
