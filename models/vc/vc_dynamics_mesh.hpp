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

#include "tdcr/bvp/residual_system.hpp"
#include "vc/vc_dynamics_rod.hpp"
#include "vc/vc_shooting.hpp"

namespace tdcr::vc::dyn {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using State = Eigen::Matrix<double, kStateSize, 1>;
using ValuesList = std::vector<Values, Eigen::aligned_allocator<Values>>;

/// One disk interval of the mesh.
struct Interval {
  int segment = 0;
  int disk = 0;     ///< The disk at its end (1-based disk index).
  double s0 = 0.0;  ///< Arc length of its start (m).
  double h = 0.0;   ///< RK4 step (m).
  int steps = 0;    ///< RK4 steps.
  int first = 0;    ///< Its first evaluation point (4 per step).
};

/// The mesh and the per-point data of one simulation.
struct Mesh {
  std::vector<Interval> intervals;
  std::vector<int> pre, post;  ///< Per disk (index 0 unused): its proximal and distal points.
  int points = 0;
  std::vector<double> weight;     ///< Quadrature weight per point (RK4's h/6 (1, 2, 2, 1); 0 at disks).
  std::vector<double> disk_mass;  ///< kg, per disk (index 0 unused).
  /// kg m^2, per disk (index 0 unused): its rotary inertia about its centre in the disk frame,
  /// a thin disk of the segment's disk_radius (0: out to the farthest tendon hole, as the lumped
  /// models take it), m r^2 (1/4, 1/4, 1/2).
  std::vector<Vec3> disk_inertia;

  /// Build for `W`'s model with the RK4 settings.
  void build(const VcWorkspace::Impl& W, int rk4_steps, double rk4_max_step);
};

/// What one shot needs besides the workspace's bound loads.
struct ShotData {
  const Mesh* mesh = nullptr;
  const StepSection* X = nullptr;
  const ValuesList* history = nullptr;  ///< Per point.
  ValuesList* values = nullptr;         ///< Per point: written by the shot.
  /// VC: the tendons load the rod continuously (and at their terminations, with kinks). False:
  /// VCref's free rods, the tendons act at the disks only (as chords, added by the caller).
  bool distributed = true;
  /// If set, shoot() records the state just distal of every inner disk (index j - 1 for disk j).
  std::vector<State, Eigen::aligned_allocator<State>>* nodes = nullptr;
};

/// Integrate interval I (RK4 on its points) from y, in place; false on a non-finite state.
bool integrate_interval(VcWorkspace::Impl& W, const ShotData& d, const Interval& I, State& y);

/// The point loads at disk j (the end of an interval of segment i) on y with the step's strains
/// on both sides: VC's tendon terminations and kinks (ShotData::distributed), the disk's weight
/// and inertia. Writes the values of the disk's two points. False if a kink has no fixed point.
bool disk_loads(VcWorkspace::Impl& W, const ShotData& d, int i, int j, double* y);

/// One shot from the clamped base (p = 0, R = I, q = w = 0) with x = (n(0), m(0)): false if it
/// failed (non-finite state, a kink without a fixed point), else res = the tip wrench residual.
/// Allocation-free.
bool shoot(VcWorkspace::Impl& W, const ShotData& d, const Vec6& x, Vec6& res);

using StateList = std::vector<State, Eigen::aligned_allocator<State>>;

/// Multiple shooting of a step: one interval per disk interval. Unknowns: n(0), m(0), then per
/// inner disk j = 1..N-1 the state just distal of it, (p_j, theta_j, n_j, m_j, q_j, w_j) with
/// R_j = Rbar_j exp(theta_j) (Rbar_j rebased after every solve, so theta stays small). Residuals
/// per inner disk: the end of interval j-1 (after the disk's point loads) minus node j, the
/// rotation as vee(skew(R_j^T R^-)); at the tip the tip wrench. With `chords` (VCref) the tendons
/// act at the disks only, by tendon::disk_wrench on the disk poses (Eq. 30-33, Eq. 58 with
/// `remove_normal`): disk j's residual then also reads node j+1's pose. Single shooting's tip
/// depends on n(0), m(0) like exp(L (rho A c0^2 / EI)^(1/4)) within a step, which short steps
/// make ill-conditioned; an interval of one disk spacing keeps that factor near 1.
class MultipleShooting final : public bvp::ResidualSystem {
 public:
  /// `W`, `d` outlive it; `velocity` and `rate` scale q and w (m/s, rad/s).
  MultipleShooting(VcWorkspace::Impl& W, const ShotData& d, bool chords, bool remove_normal, double velocity,
                   double rate);
  int size() const override { return n_; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override;
  const bvp::SparsityPattern* sparsity() const override { return &pattern_; }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { residual_scale(s); }
  /// Unknowns from the states distal of the inner disks and the base wrench (rotations rebased).
  void from_nodes(const Vec6& base, const StateList& nodes, Eigen::VectorXd& x);
  /// Fold theta_j into Rbar_j (x's thetas become 0).
  void rebase(Eigen::VectorXd& x);
  /// Force and moment scales of the wrench rows and unknowns.
  void set_scales(double force, double moment) {
    force_ = force;
    moment_ = moment;
  }
  /// The disk poses 0..N of the last residual (the nodes' and the tip's).
  const std::vector<Frame>& frames() const { return frames_; }
  long shots = 0;          ///< Residual evaluations.
  Eigen::VectorXd last_x;  ///< The last residual's unknowns (its values are in d.values).
  bool last_ok = false;

 private:
  void node_state(const Eigen::Ref<const Eigen::VectorXd>& x, int j, State& y) const;
  VcWorkspace::Impl& W_;
  const ShotData& d_;
  bool chords_, remove_normal_;
  double velocity_, rate_, length_, force_ = 1.0, moment_ = 1.0;
  int disks_ = 0, n_ = 0;
  std::vector<Mat3> rbar_;     ///< Per inner disk (index j - 1).
  StateList ends_;             ///< Per interval: the state at its end, before the disk's loads.
  std::vector<Frame> frames_;  ///< Disk poses 0..N for the chords.
  std::vector<double> tensions_;  ///< The tensions of the last residual (global order).
  bvp::SparsityPattern pattern_;
};

/// The disk frames of the shape whose strains are `values` (p' = R v, R' = R [u]x by the shot's
/// RK4 on the same points), and the position at every point (for the weights' potential).
void reconstruct(const Mesh& mesh, const ValuesList& values, std::vector<Frame>& frames, std::vector<Vec3>& points);

/// The pull of every tendon (Solution::tendon_displacements in the bound convention, without an
/// elastic tendon's stretch) of the shape whose strains are `values`: VC's fully constrained
/// paths, |v + u x r_k + r_k'| integrated with RK4's weights on the points (the statics' length
/// states on the same steps). `lengths`: scratch. Allocation-free once sized.
void path_pulls(const VcWorkspace::Impl& W, const Mesh& mesh, const ValuesList& values, std::vector<double>& lengths,
                std::vector<double>& pulls);

/// Kinetic and potential energy (J) of the shape `values` (frames, points from reconstruct):
/// kinetic of the backbone (translation and rotation) and of the disks' masses; potential:
/// elastic, weights, the tendon tensions times their path lengths (fully constrained paths, or
/// with `chords` VCref's chords between the disks), the tip force (the tip moment has no
/// potential here).
void energies(const VcWorkspace::Impl& W, bool chords, const StepSection& X, const Mesh& mesh, const ValuesList& values,
              const std::vector<Frame>& frames, const std::vector<Vec3>& points, double& kinetic, double& potential);

}  // namespace tdcr::vc::dyn
