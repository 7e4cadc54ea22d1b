// The kinds the configuration names (sensor.receiver, the canopy's kind), declared by the parts
// themselves: a part on a floor above the configuration (a receiver, a vegetation source) registers
// its name, what the table of keys says of it and its traits (what it is, as the rules across keys
// and the engine ask: "it counts photons", not "it is photon_counting") from its own .cpp into
// Registry<PartKind<Traits>>. The configuration takes its allowed names from there and asks the
// traits, so that a new kind needs no edit in the configuration (core/part_switch.hpp does the
// same for the writers' switches). `Traits` is a struct a floor below both can see:
//
//   const Registration<PartKind<ReceiverTraits>> mine("my_receiver", 2, {"what it records",
//   {...}});
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/registry.hpp"

namespace glaswave {

template <typename Traits>
struct PartKind {
  struct Declaration {
    std::string description;  // what the kind is, for the table of keys
    Traits traits;
  };
  using Factory = Declaration;
};

// The traits the kind `name` declared; nullopt when no kind of that name registered.
template <typename Traits>
std::optional<Traits> declared_traits(const std::string& name) {
  if (const auto declared = Registry<PartKind<Traits>>::instance().find(name))
    return declared->traits;
  return std::nullopt;
}

// The kinds registered, in their order, whose traits satisfy `keep` (all without one).
template <typename Traits, typename Keep>
std::vector<std::string> declared_kinds(Keep keep) {
  std::vector<std::string> names;
  for (const auto& entry : Registry<PartKind<Traits>>::instance().entries())
    if (keep(entry.make.traits)) names.push_back(entry.name);
  return names;
}
template <typename Traits>
std::vector<std::string> declared_kinds() {
  return declared_kinds<Traits>([](const Traits&) { return true; });
}

// Items as a sentence lists them: "a", "a or b", "a, b or c".
inline std::string alternatives(const std::vector<std::string>& items) {
  std::string text;
  for (std::size_t i = 0; i < items.size(); ++i)
    text += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
  return text;
}

// Names as a message lists them: "\"a\" or \"b\"".
inline std::string quoted_alternatives(std::vector<std::string> names) {
  for (std::string& name : names) name = "\"" + name + "\"";
  return alternatives(names);
}

}  // namespace glaswave
