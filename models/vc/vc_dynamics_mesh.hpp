// Private to models/vc: the fixed mesh of VC's dynamics, the history stored on it, and one shot
// of a time step's boundary value problem (vc_dynamics_mesh.cpp).
//
// The mesh: every disk interval takes max(rk4_steps, ceil(length / rk4_max_step)) equal RK4
// steps; each step evaluates the rod at 4 points (its RK4 stages, the two midpoint stages apart),
// and every disk adds a point just proximal (the strains before its point loads) and one just
// distal (after them). Each point holds the history of v, u, q, w, v_s, u_s (dyn::Values):
// the scheme's combination of the values of past steps at that very point, so that a shot of
// the step differs from a static shot only by distributed and point loads known per point.
#pragma once

#include <vector>

#include <Eigen/StdVector>

#include "vc/vc_dynamics_rod.hpp"
#include "vc/vc_shooting.hpp"

namespace tdcr::vc::dyn {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using State = Eigen::Matrix<double, kStateSize, 1>;
using ValuesList = std::vector<Values, Eigen::aligned_allocator<Values>>;

/// One disk interval of the mesh.
struct Interval {
  int segment = 0;
  int disk = 0;       ///< The disk at its end (1-based disk index).
  double s0 = 0.0;    ///< Arc length of its start (m).
  double h = 0.0;     ///< RK4 step (m).
  int steps = 0;      ///< RK4 steps.
  int first = 0;      ///< Its first evaluation point (4 per step).
};

/// The mesh and the per-point data of one simulation.
struct Mesh {
  std::vector<Interval> intervals;
  std::vector<int> pre, post;  ///< Per disk (index 0 unused): its proximal and distal points.
  int points = 0;
  std::vector<double> weight;  ///< Quadrature weight per point (RK4's h/6 (1, 2, 2, 1); 0 at disks).
  std::vector<double> disk_mass;  ///< kg, per disk (index 0 unused).

  /// Build for `W`'s model with the RK4 settings.
  void build(const VcWorkspace::Impl& W, int rk4_steps, double rk4_max_step);
};

/// What one shot needs besides the workspace's bound loads.
struct ShotData {
  const Mesh* mesh = nullptr;
  const StepSection* X = nullptr;
  const ValuesList* history = nullptr;  ///< Per point.
  ValuesList* values = nullptr;          ///< Per point: written by the shot.
};

/// One shot from the clamped base (p = 0, R = I, q = w = 0) with x = (n(0), m(0)): false if it
/// failed (non-finite state, a kink without a fixed point), else res = the tip wrench residual.
/// Allocation-free.
bool shoot(VcWorkspace::Impl& W, const ShotData& d, const Vec6& x, Vec6& res);

/// The disk frames of the shape whose strains are `values` (p' = R v, R' = R [u]x by the shot's
/// RK4 on the same points), and the position at every point (for the weights' potential).
void reconstruct(const Mesh& mesh, const ValuesList& values, std::vector<Frame>& frames, std::vector<Vec3>& points);

/// Kinetic and potential energy (J) of the shape `values` (frames, points from reconstruct):
/// kinetic of the backbone (translation and rotation) and of the disks' masses; potential:
/// elastic, weights, the tendon tensions times their path lengths, the tip force (the tip
/// moment has no potential here).
void energies(const VcWorkspace::Impl& W, const StepSection& X, const Mesh& mesh, const ValuesList& values,
              const std::vector<Frame>& frames, const std::vector<Vec3>& points, double& kinetic,
              double& potential);

}  // namespace tdcr::vc::dyn
