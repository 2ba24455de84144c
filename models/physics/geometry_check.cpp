#include "physics/geometry_check.hpp"

namespace tdcr::physics {

void check_geometry(const TendonRouting& routing, Solution& solution) {
  (void)routing;
  (void)solution;
}

}  // namespace tdcr::physics
