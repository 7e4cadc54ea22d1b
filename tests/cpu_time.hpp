// CPU time for tests that bound how long something takes: a loaded machine (ctest -j, a
// sanitizer's build beside it) stretches wall time many times over (a check of 3.3 s of CPU took
// 259 s of wall under AddressSanitizer at a load of 20), CPU time little.
#pragma once

#include <sys/resource.h>

#include "core/spawned_reader.hpp"

namespace glaswave::test_support {

// This process's CPU and that of its children already waited for (the programs it ran, the
// reader programs its library spawned), seconds.
inline double cpu_used_s() {
  rusage self{}, children{};
  ::getrusage(RUSAGE_SELF, &self);
  ::getrusage(RUSAGE_CHILDREN, &children);
  return cpu_seconds(self) + cpu_seconds(children);
}

}  // namespace glaswave::test_support
