// The switches a part declares beside its code (PDAL's Stage::addArgs): a part the configuration
// cannot name (it sits on a floor above it) registers the boolean keys that turn it on, from its
// own .cpp, into Registry<PartSwitch>; the configuration declares them among its own keys (in the
// JSON Schema and the table of keys too), reads them into its section's `switches` and hands them
// to the part's kind unchanged. A new product writer is then one pair of files:
//
//   const Registration<PartSwitch> my_key("my_product", 0, {"output", false, "write my.h5"});
//   const Registration<ProductWriter> my_writer("my.h5", 60, [](const WriterContext& c) ...
//     if (!switched_on(c.settings.switches, "my_product")) return nullptr; ...
//
// A library whose parts declare switches is linked whole into whatever reads the configuration.
#pragma once

#include <map>
#include <string>

#include "core/registry.hpp"

namespace glaswave {

struct PartSwitch {
  // What a registration holds, under the key's name: the section the key is in ("output"), its
  // default, and what it does (the table of keys prints it).
  struct Declaration {
    std::string section;
    bool fallback = false;
    std::string description;
  };
  using Factory = Declaration;
};

// The switches of one section as the configuration read them, by the key's name: each declared
// one is there, at its default when not given.
using PartSwitches = std::map<std::string, bool>;

// Whether switch `name` is on; off when absent (settings made without a configuration).
inline bool switched_on(const PartSwitches& switches, const std::string& name) {
  const auto found = switches.find(name);
  return found != switches.end() && found->second;
}

}  // namespace glaswave
