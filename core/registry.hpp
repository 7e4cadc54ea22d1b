// The one registry of glaswave's parts (PDAL's static stages are the model): each part of a kind
// (a product writer, and with the next steps a vegetation source, a receiver, a granule reader, a
// retrieval method, an atmosphere model) registers itself from its own .cpp with a
// Registration, by name; the code that uses the kind looks parts up, or goes through them all in
// their order, and never names one. `T` is the kind's interface; `T::Factory` makes a part.
//
// A library whose parts register themselves is linked whole (CMake's WHOLE_ARCHIVE), so that a
// part no other code names still registers.
#pragma once

#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace glaswave {

template <typename T>
class Registry {
 public:
  using Factory = typename T::Factory;

  struct Entry {
    std::string name;
    int order = 0;  // the parts go in this order, then by name
    Factory make;
  };

  static Registry& instance() {
    static Registry registry;
    return registry;
  }

  // Throws std::logic_error when `name` is registered already (two parts of one name is a bug).
  void add(std::string name, int order, Factory make) {
    const std::lock_guard lock(mutex_);
    for (const Entry& e : entries_)
      if (e.name == name) throw std::logic_error("two parts registered as \"" + name + "\"");
    Entry entry{std::move(name), order, std::move(make)};
    auto at = entries_.begin();
    while (at != entries_.end() &&
           (at->order < entry.order || (at->order == entry.order && at->name < entry.name)))
      ++at;
    entries_.insert(at, std::move(entry));
  }

  // The parts, in their order (a copy: parts may register while it is read).
  std::vector<Entry> entries() const {
    const std::lock_guard lock(mutex_);
    return entries_;
  }

  // The part named `name`; nullopt when none is.
  std::optional<Factory> find(const std::string& name) const {
    const std::lock_guard lock(mutex_);
    for (const Entry& e : entries_)
      if (e.name == name) return e.make;
    return std::nullopt;
  }

 private:
  Registry() = default;
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
};

// One part's registration: a namespace-scope object in the part's own .cpp.
template <typename T>
struct Registration {
  Registration(std::string name, int order, typename T::Factory make) {
    Registry<T>::instance().add(std::move(name), order, std::move(make));
  }
};

}  // namespace glaswave
