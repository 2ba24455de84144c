// Private to models/: shapes a real robot cannot take, found from a Solution's disk frames (a
// tendon chord through the backbone, neighbouring disks interpenetrating). The solve driver
// calls it after every solve; findings go to Solution::geometry_warnings.
#pragma once

#include "tdcr/core/robot.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::physics {

/// Append to solution.geometry_warnings what its disk frames show that cannot be built.
void check_geometry(const TendonRouting& routing, Solution& solution);

}  // namespace tdcr::physics
