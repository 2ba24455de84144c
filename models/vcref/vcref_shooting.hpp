// Private to models/vcref: what VcrefModel decides once (Data) and the multiple-shooting problem
// of one workspace (VcrefShooting: chart, residual blocks, scales; bound per input).
#pragma once

#include <memory>
#include <vector>

#include "physics/contact_law.hpp"
#include "physics/load_case.hpp"
#include "tdcr/bvp/shooting.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "tdcr/models/vcref.hpp"

namespace tdcr {

// Decided once from robot and effects.
struct VcrefModel::Data {
  int N = 0;                        // total disks (disk N = tip)
  int size = 0;                     // unknowns = residuals
  const Robot* robot = nullptr;     // the model's (outlives the data)
  const TendonRouting* routing = nullptr;
  std::vector<char> pass_through;   // some routed tendon passes (does not end at) disk j
  cosserat::Section section;        // stiffness and rod variant; weight per call
  bool remove_normal = true;        // Eq. 58
  bool friction = false;            // Effects::tendon_friction on: disk loads read all proximal poses
  TendonFriction tendon_friction;
  bool arc_guess = true;            // VcrefOptions::initial_guess
  int guess_passes = 3;             // VcrefOptions::guess_passes
  double length = 0.0;              // robot length L
  double l_min = 0.0;               // shortest interval
  // Layout and Jacobian pattern of every routed tendon: a workspace's fallback (its own patterns
  // follow the tensioned tendons, VcrefShooting::pass_through()).
  std::shared_ptr<const bvp::ShootingStructure> structure;
};

// The multiple-shooting problem (bvp/shooting.hpp) of VCref. Node 0: unknowns (n_0, m_0) at the
// fixed base pose; node j = 1..N-1: (p_j, w_j, n_j, m_j), R_j = Rbar_j exp(w_j). Block 0: tip
// equilibrium (6); block j: pose continuity and equilibrium of disk j (12). dependent_rows()
// follows pass_through(): every routed tendon until the first bind, then the tensioned ones.
class VcrefShooting final : public bvp::ShootingProblem {
 public:
  explicit VcrefShooting(const VcrefModel::Data& d);

  // Per call: loads, active tendons, scales, finite-difference steps; load factor 1.
  void bind(const ModelInput& input, const SolverOptions& options);
  // Scale every load (tensions, tip wrench, weights) by `lambda`.
  void set_load_factor(double lambda);
  // Displacement input: tendon index[i] pulls with T[i] (N) at every load factor until the next
  // bind (bound tensioned, so that it is active).
  void set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T);
  const VcrefModel::Data& data() const { return d_; }
  const physics::LoadCase& loads() const { return load_; }
  const std::vector<double>& tensions() const { return tension_; }
  const TendonRouting& active() const { return active_; }
  bool tendon_at(int j) const { return tendon_at_[j] != 0; }
  // Disk j has a tensioned tendon passing through it (its equilibrium reads disk j+1's pose).
  const std::vector<char>& pass_through() const { return passes_; }
  Vec3 rod_weight() const { return load_.backbone_weight(); }
  Mat3& reference(int j) {
    chart_node_ = -1;
    return rbar_[j];
  }
  // Viscous damping of the disk poses (bvp::ParameterizedSystem::set_damping): from now on the
  // equilibrium rows of disks 1..N-1 get rate (F_s / L) (p_j - p_j,ref) and rate F_s L R_j
  // log(R_j,ref^T R_j), the poses of `x` as reference; rate 0 removes them. The tip disk stays
  // undamped (its pose is no unknown): it follows quasi-statically.
  void set_damping(const double* x, double rate);
  // Component index 0..11 (p, w, n, m) of unknown j of node k.
  static int component(int k, int j) { return k == 0 ? j + 6 : j; }

  int state_dimension() const override { return cosserat::kStateSize; }
  int intervals() const override { return d_.N; }
  double node(int k) const override { return d_.routing->disk_s[k]; }
  const bvp::OdeSystem& ode(int) const override { return rod_; }
  // Friction: the tension at disk j follows the poses of disks 0..j+1, so every block reads every node.
  int coupling() const override { return d_.friction ? d_.N : 1; }
  int unknown_dimension(int k) const override { return k == 0 ? 6 : 12; }
  void start_state(int k, const double* x, double* y) const override;
  void rebase(int k, double* x) override;
  bool shifts_end(int k, int j) const override { return k > 0 && j < 3; }
  std::pair<int, int> dependent_rows(int block, int k, int j) const override;
  void boundary(const bvp::ShootingNodes& nodes, double* r) const override;
  void junction(int i, const bvp::ShootingNodes& nodes, double* r) const override;
  void unknown_scale(int k, double* s) const override;
  void block_scale(int block, double* s) const override;
  double increment(int k, int j, double value, double scale, double noise) const override;
  // The shot's derivative (vcref_tangent.cpp): forward differences in the start wrench (6
  // integrations), the start pose from the rod's symmetries (none). Without gravity (which breaks
  // the rotation symmetry) and for RK4 only (CVODE's error control is not rotation invariant).
  bool linearize_shot(int k, bvp::Integrator& integrator, const double* y0, const double* end) const override;
  void shot_tangent(int k, const double* dy, double* dend) const override;
  // The tendon wrenches on the disks through their exact linearisation in the poses of the disks
  // they read (vcref_tangent.cpp), while a Jacobian is taken: a tendon chord is L / N long, its
  // direction moves on that scale, and forward differences of the full wrench lost digits in
  // proportion to the disk count (from about 5000 disks per segment on, Newton stalled on the
  // paper robot). Not with tendon friction (the tensions read every proximal pose).
  void begin_linearization(const bvp::ShootingNodes& nominal) const override;
  void end_linearization() const override { linearized_ = false; }

  // --- Contact (vcref_shooting.cpp, vcref_model.cpp; docs/contact.md) ---
  // The bound input's obstacles; no candidates. The candidates' forces (b F_s along the normal
  // at the contact point of the disk's current pose) act on their disks in the tip and disk
  // equilibria like the tendon wrenches; they are reactions, not scaled by the load factor.
  void bind_contact(const ModelInput& input);
  bool contact_on() const { return !obstacles_.empty(); }
  std::vector<contact::Candidate>& candidates() { return candidates_; }
  const std::vector<contact::Candidate>& candidates() const { return candidates_; }
  const std::vector<Obstacle>& obstacles() const { return obstacles_; }
  const contact::Surfaces& surfaces() const { return surfaces_; }
  contact::Law& law() { return law_; }
  const contact::Law& law() const { return law_; }
  // The candidates' scaled force magnitudes b (one per candidate).
  void set_contact_forces(const double* b) {
    for (std::size_t i = 0; i < candidates_.size(); ++i) candidates_[i].lambda = b[i];
  }
  // The frame of disk k = 1..N of the trajectory `nodes` (node k's start, the tip the last end).
  Frame disk_frame(int k, const bvp::ShootingNodes& nodes) const {
    return cosserat::frame_of(k < d_.N ? nodes.start(k) : nodes.end(d_.N - 1));
  }
  // Candidate i's contact point with its disk at `frame`.
  ContactPoint contact_at(std::size_t i, const Frame& frame) const {
    const contact::Candidate& c = candidates_[i];
    return contact_point(obstacles_[c.obstacle], frame, c.body, surfaces_.radius(c.disk, c.body));
  }

  // The tendon wrench on disk j and its derivative in the poses (dp, body rotation dtheta) of the
  // disks j-1, j, j+1 (columns 0-5, 6-11, 12-17; the last six zero unless a tendon passes disk j)
  // at `frames` (disk frames, 0..N), for the tensions of the last set_load_factor(). Without
  // tendon friction.
  void disk_wrench_derivative(int j, const Frame* frames, tendon::DiskWrench& w,
                              Eigen::Matrix<double, 6, 18>& D) const;

 private:
  void subtract_disk_load(int j, Vec3& F, Vec3& M) const;
  // Subtracts the contact forces of the candidates at disk j (pose `frame`) from F, M (about its centre).
  void subtract_contact(int j, const Frame& frame, Vec3& F, Vec3& M) const;
  // The tendon wrench on disk j at frames_ j-1..j+1 through its linearisation about the nominal
  // frames (begin_linearization).
  tendon::DiskWrench linearized_wrench(int j) const;
  Frame nominal_frame(int k) const;
  // With friction: frames_ 0..j+1 (at most N) from the nodes and chord_ from them.
  void friction_frames(int j, const bvp::ShootingNodes& nodes) const;

  const VcrefModel::Data& d_;
  physics::LoadCase load_;
  std::vector<Obstacle> obstacles_;  // contact: the bound input's obstacles
  contact::Surfaces surfaces_;
  contact::Law law_;
  std::vector<contact::Candidate> candidates_;
  TendonRouting active_;            // tendons with nonzero tension
  std::vector<char> tendon_at_;     // disk j receives a tendon wrench
  std::vector<char> passes_;        // an active tendon passes disk j (all routed before bind)
  std::vector<double> tension_;     // at the load factor, by global index
  cosserat::Section section_;       // the rod's, with the weight at the load factor
  cosserat::FreeRod rod_;
  std::vector<Mat3> rbar_;          // chart references (0 unused)
  mutable std::vector<Frame> frames_;  // disk frames of one block evaluation
  mutable std::vector<double> chord_;  // friction: chord tensions (tendon::friction_tensions)
  // The last tendon wrench on each disk and the frames it was computed in (j-1, j and, if a
  // tendon passes, j+1), valid while tension_ is unchanged (version). A Jacobian's finite
  // differences in a node's wrench unknowns move no frame: those junctions reuse the wrench
  // instead of recomputing it (it was a fifth of a stiff direct solve's time).
  struct WrenchMemo {
    Frame frames[3];
    tendon::DiskWrench wrench;
    unsigned version = 0;
  };
  mutable std::vector<WrenchMemo> wrench_memo_;
  unsigned tension_version_ = 1;
  double damping_ = 0.0;               // set_damping's rate, and its reference poses per disk
  std::vector<Frame> damping_ref_;
  mutable int chart_node_ = -1;        // last chart evaluation: node, w, Rbar exp(w)
  mutable Vec3 chart_w_ = Vec3::Zero();
  mutable Mat3 chart_R_ = Mat3::Identity();
  double comp_scale_[4] = {1, 1, 1, 1};  // 1/L, 1, 1/F_s, 1/(F_s L)
  double fd_comp_[4] = {1, 1, 1, 1};     // finite-difference scale per component group
  double fd_rel_ = 1e-7;
  // Linearised tendon wrenches (begin_linearization): the nominal trajectory and, for the last
  // few disks asked for (a Jacobian visits the nodes in order), the wrench and its derivative.
  mutable bool linearized_ = false;
  mutable bvp::ShootingNodes nominal_{nullptr, nullptr, 0, 0};
  struct LinearWrench {
    int disk = -1;
    Frame frames[3];  // nominal frames of disks j-1, j, j+1
    tendon::DiskWrench wrench;
    Eigen::Matrix<double, 6, 18> D;
  };
  mutable LinearWrench linear_[4];
  mutable int linear_next_ = 0;
  // The last linearize_shot(): its start and end states and d(end) / d(n, m of the start).
  mutable cosserat::State shot_start_, shot_end_;
  mutable Eigen::Matrix<double, cosserat::kStateSize, 6> shot_d_;
};

}  // namespace tdcr
