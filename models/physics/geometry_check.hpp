// Private to models/: shapes a real robot cannot take, found from a Solution's disk frames (a
// tendon running backwards along the backbone, a tendon chord through the backbone, neighbouring
// disks interpenetrating), and the tendon at its geometric limit when a loading path stalls.
//
// The measure of a tendon's limit is curvature x offset: between disks j-1 and j (centres p,
// holes h of tendon k),  c_kj = 1 - (dh . dp) / |dp|^2,  the fraction of the backbone's advance
// the tendon loses on the inside of the bend (exactly kappa |r_k| for a planar arc with the
// tendon towards the centre of curvature; the discrete form of VC's 1 - q_k . v / |v|^2). At 1
// the tendon sits on the centre of curvature; beyond, it would have to cross the backbone.
#pragma once

#include <string>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::physics {

/// A stalled loading path whose last equilibrium has a tensioned tendon at curvature x offset
/// of at least this is stopped by the tendon geometry, not by the numerics.
constexpr double kTendonLimitNear = 0.9;

/// A converged answer with a tendon at curvature x offset of at least this is flagged as at its
/// geometric limit even below 1: that close to it the models disagree whether the actuation is
/// feasible (docs/hard-cases.md, loaded scene s1015).
constexpr double kTendonLimitWarn = 0.99;

/// The reason text for a tendon at its geometric limit: "infeasible actuation: tendon T1 (index
/// 0) ... curvature x offset 0.99 at <where>". `tendon` is the global 0-based index.
std::string tendon_limit_message(int tendon, double value, const std::string& where);

/// Append to solution.geometry_warnings what its disk frames show that cannot be built: a tendon
/// with curvature x offset >= 1 (or at its limit, >= kTendonLimitWarn), a tendon chord closer to
/// the backbone chord than the backbone's outer radius, neighbouring disks (radius: the largest
/// tendon offset) interpenetrating.
/// `max_curvature`: an upper bound of the backbone's curvature that the model knows (CC: its
/// arcs), or negative if unknown; at most 1 / (2 r_max) no pair of disks can show a finding
/// (see quiet() in the source), so the frames are not examined.
void check_geometry(const Robot& robot, const TendonRouting& routing, Solution& solution,
                    double max_curvature = -1.0);

/// For the equilibrium where a loading path stopped (solution's disk frames): true and the reason
/// in `why` if a tensioned tendon (solution.tensions) has curvature x offset >= threshold
/// (kTendonLimitNear where a path stopped; kTendonLimitWarn at a fold, where a path would snap).
bool tendon_limit(const TendonRouting& routing, const Solution& solution, double threshold, std::string& why);

}  // namespace tdcr::physics
