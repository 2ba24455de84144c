// TEMPORARY, on the dyn-cosserat branch only: DELETE THIS FILE AT THE MERGE with the dynamics
// front end, which defines Timeline::at (and the rest of dynamics.hpp) for real. It sits here,
// not in models/dynamics/, because the layer check and the glob of models/CMakeLists.txt know no
// such folder yet.
//
// The Cosserat integrators' advance() calls Timeline::at; without a definition their objects
// would not link into the tests and benchmarks of this branch. A weak definition, so that the
// front end's strong one wins if both are ever linked from separate objects; the tests on this
// branch drive the integrators through advance_with_input and never call it.
#include "tdcr/models/dynamics.hpp"

namespace tdcr {

__attribute__((weak)) ModelInput Timeline::at(double t) const {
  // Piecewise constant (the front end interpolates linearly): the last entry at or before t.
  if (entries.empty()) return ModelInput{};
  const TimelineEntry* e = &entries.front();
  for (const TimelineEntry& x : entries)
    if (x.t <= t) e = &x;
  return e->input;
}

}  // namespace tdcr
