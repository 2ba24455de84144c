// VCref: Cosserat rod per subsegment with discrete tendon disk forces, solved by multiple
// shooting (see tdcr/models/vcref.hpp). The model, its workspace and the solve problem.
#include "tdcr/models/vcref.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tdcr/models/model_problem.hpp"
#include "solve/stability_mesh.hpp"
#include "solve/bvp_options.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "physics/tendon_path.hpp"
#include "solve/contact_completion.hpp"
#include "vcref/vcref_shooting.hpp"
#include "vcref/vcref_stability.hpp"

namespace tdcr {

namespace {

// The shooting system with the load factor as its parameter; accepted steps rebase the charts.
// With contact candidates (VcrefShooting::candidates(), docs/contact.md) their scaled force
// magnitudes b_i follow the shooting unknowns and their complementarity residuals the shooting
// residuals: the forces act in the disk equilibria (VcrefShooting::subtract_contact).
class VcrefSystem final : public bvp::ParameterizedSystem {
 public:
  VcrefSystem(VcrefShooting& problem, bvp::ShootingSystem& shooting, std::unique_ptr<bvp::Integrator>& integrator)
      : problem_(problem), shooting_(shooting), integrator_(integrator) {}
  int free_size() const { return shooting_.size(); }
  int contacts() const { return static_cast<int>(problem_.candidates().size()); }
  int size() const override { return free_size() + contacts(); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const int n = free_size(), nc = contacts();
    if (nc == 0) return shooting_.residual(x, f) && f.allFinite();
    problem_.set_contact_forces(x.data() + n);
    if (!shooting_.residual(x.head(n), f.head(n))) return false;
    const bvp::ShootingNodes nodes = shooting_.nodes();
    std::vector<contact::Candidate>& cands = problem_.candidates();
    for (int i = 0; i < nc; ++i) {
      contact::Candidate& c = cands[static_cast<std::size_t>(i)];
      c.at = problem_.contact_at(static_cast<std::size_t>(i), problem_.disk_frame(c.disk, nodes));
      f[n + i] = problem_.law().residual(c.at.gap, x[n + i]);
    }
    return f.allFinite();
  }
  const bvp::SparsityPattern* sparsity() const override {
    return contacts() == 0 ? shooting_.sparsity() : &pattern_;
  }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                       double* values) override {
    if (contacts() == 0) return shooting_.sparse_jacobian(x, f, values);
    return contact_jacobian(x, f, values);
  }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    const int n = free_size();
    shooting_.residual_scale(s.head(n));
    s.tail(s.size() - n).setOnes();  // phi: the gap in units of r_o, the force in units of F_s
  }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    const int n = free_size();
    shooting_.unknown_scale(s.head(n));
    s.tail(s.size() - n).setOnes();
  }
  void set_parameter(double lambda) override {
    problem_.set_load_factor(lambda);
    shooting_.invalidate();
  }
  void accept_step(Eigen::VectorXd& x) override {
    Eigen::Ref<Eigen::VectorXd> head = x.head(free_size());
    shooting_.rebase(head);
  }
  // Along a loading path a disk can turn by more than pi from its reference (the rest state's):
  // its rotation vector w then nears |w| = 2 pi, where the chart degenerates and the path's
  // steps are spent on w (VCref s1011 of the loaded-scene suite, docs/hard-cases.md). Re-centred
  // once some |w| exceeds kRecenterAngle.
  bool recenter(Eigen::Ref<Eigen::VectorXd> x) override {
    constexpr double kRecenterAngle = 1.0;  // rad
    const int nodes = (free_size() - 6) / 12;
    bool far = false;
    for (int k = 1; k <= nodes && !far; ++k) far = x.segment<3>(6 + 12 * (k - 1) + 3).norm() > kRecenterAngle;
    if (far) {
      Eigen::Ref<Eigen::VectorXd> head = x.head(free_size());
      shooting_.rebase(head);
    }
    return far;
  }
  bool set_damping(const Eigen::Ref<const Eigen::VectorXd>& x, double rate) override {
    problem_.set_damping(x.data(), rate);
    shooting_.invalidate();
    return true;
  }
  // The candidates or the shooting structure changed: the pattern of the contact system.
  void contacts_changed();

 private:
  // Rows of the equilibrium of disk j (6: force, moment) and the first column and count of the
  // unknowns its pose depends on.
  int equilibrium_row(int j) const { return j == problem_.data().N ? shooting_.offset(0) : shooting_.offset(j) + 6; }
  void pose_columns(int j, int& first, int& count) const {
    const int N = problem_.data().N;
    const int k = j == N ? N - 1 : j;
    first = shooting_.offset(k);
    count = j == N ? problem_.unknown_dimension(k) : 6;
  }
  bool contact_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                        double* values);
  // The gap of candidate i with its disk's pose from node unknowns `node` (of node k; the tip:
  // one shot of the last interval); false if the shot failed.
  bool gap_of(std::size_t i, int k, const double* node, double& gap) const;

  VcrefShooting& problem_;
  bvp::ShootingSystem& shooting_;
  std::unique_ptr<bvp::Integrator>& integrator_;
  bvp::SparsityPattern pattern_;
  std::vector<int> shoot_pos_;              // position of each shooting entry in pattern_
  std::vector<int> gap_pos_, force_pos_, diag_pos_;  // per candidate: 12, 6, 1 positions
  std::vector<double> shoot_values_;
};

void VcrefSystem::contacts_changed() {
  const int n = free_size(), nc = contacts();
  if (nc == 0) return;
  const bvp::SparsityPattern& sp = *shooting_.sparsity();
  std::vector<std::pair<int, int>> e;
  e.reserve(static_cast<std::size_t>(sp.nnz() + 20 * nc));
  for (int c = 0; c < n; ++c)
    for (int k = sp.col_ptr[c]; k < sp.col_ptr[c + 1]; ++k) e.emplace_back(sp.row_idx[k], c);
  const std::vector<contact::Candidate>& cands = problem_.candidates();
  for (int i = 0; i < nc; ++i) {
    const int j = cands[static_cast<std::size_t>(i)].disk;
    int first = 0, count = 0;
    pose_columns(j, first, count);
    for (int q = 0; q < count; ++q) e.emplace_back(n + i, first + q);
    for (int r = 0; r < 6; ++r) e.emplace_back(equilibrium_row(j) + r, n + i);
    e.emplace_back(n + i, n + i);
  }
  pattern_ = bvp::SparsityPattern::from_triplets(n + nc, n + nc, e);
  shoot_pos_.resize(static_cast<std::size_t>(sp.nnz()));
  for (int c = 0; c < n; ++c)
    for (int k = sp.col_ptr[c]; k < sp.col_ptr[c + 1]; ++k) shoot_pos_[static_cast<std::size_t>(k)] = pattern_.index_of(sp.row_idx[k], c);
  gap_pos_.assign(static_cast<std::size_t>(12 * nc), -1);
  force_pos_.assign(static_cast<std::size_t>(6 * nc), -1);
  diag_pos_.assign(static_cast<std::size_t>(nc), -1);
  for (int i = 0; i < nc; ++i) {
    const int j = cands[static_cast<std::size_t>(i)].disk;
    int first = 0, count = 0;
    pose_columns(j, first, count);
    for (int q = 0; q < count; ++q) gap_pos_[static_cast<std::size_t>(12 * i + q)] = pattern_.index_of(n + i, first + q);
    for (int r = 0; r < 6; ++r) force_pos_[static_cast<std::size_t>(6 * i + r)] = pattern_.index_of(equilibrium_row(j) + r, n + i);
    diag_pos_[static_cast<std::size_t>(i)] = pattern_.index_of(n + i, n + i);
  }
}

bool VcrefSystem::gap_of(std::size_t i, int k, const double* node, double& gap) const {
  const int N = problem_.data().N;
  const int j = problem_.candidates()[i].disk;
  double y[cosserat::kStateSize];
  problem_.start_state(k, node, y);
  if (j == N && !integrator_->integrate(problem_.ode(k), problem_.node(k), problem_.node(k + 1), y)) return false;
  gap = problem_.contact_at(i, cosserat::frame_of(y)).gap;
  return std::isfinite(gap);
}

// The shooting's Jacobian (its differences see the contact forces at the perturbed poses), the
// force columns exactly (a unit b_i adds -F_s n_i and -(c_i - p_j) x F_s n_i to the equilibrium
// of its disk j) and the complementarity rows as phi's derivatives in closed form times the
// gap's gradient in the unknowns of the disk's pose (central differences: of the pose chart at
// a node, of one shot of the last interval at the tip).
bool VcrefSystem::contact_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                                   double* values) {
  const int n = free_size(), nc = contacts();
  std::fill(values, values + pattern_.nnz(), 0.0);
  problem_.set_contact_forces(x.data() + n);
  shoot_values_.resize(shoot_pos_.size());
  if (!shooting_.sparse_jacobian(x.head(n), f.head(n), shoot_values_.data())) return false;
  for (std::size_t k = 0; k < shoot_pos_.size(); ++k) values[shoot_pos_[k]] = shoot_values_[k];
  if (!shooting_.evaluate(x.head(n))) return false;
  const bvp::ShootingNodes nodes = shooting_.nodes();
  const double Fs = problem_.law().force_scale;
  const double rel = std::max(1e-6, std::cbrt(integrator_->relative_noise()));
  std::vector<contact::Candidate>& cands = problem_.candidates();
  for (int i = 0; i < nc; ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    contact::Candidate& c = cands[ui];
    const Frame frame = problem_.disk_frame(c.disk, nodes);
    c.at = problem_.contact_at(ui, frame);
    const Vec3 fn = Fs * c.at.normal;
    const Vec3 mn = (c.at.point - frame.p).cross(fn);
    for (int r = 0; r < 3; ++r) {
      values[force_pos_[6 * ui + static_cast<std::size_t>(r)]] = -fn[r];
      values[force_pos_[6 * ui + 3 + static_cast<std::size_t>(r)]] = -mn[r];
    }
    double dgap = 0.0, db = 0.0;
    problem_.law().derivatives(c.at.gap, x[n + i], dgap, db);
    values[diag_pos_[ui]] = db;
    if (dgap == 0.0) continue;
    int first = 0, count = 0;
    pose_columns(c.disk, first, count);
    const int N = problem_.data().N;
    const int k = c.disk == N ? N - 1 : c.disk;
    double node[12], scale[12];
    problem_.unknown_scale(k, scale);
    std::copy(x.data() + first, x.data() + first + problem_.unknown_dimension(k), node);
    for (int q = 0; q < count; ++q) {
      const double h = rel * std::max(std::abs(node[q]) * (q >= 6 || k == 0 ? 1.0 : 0.0), 1.0 / scale[q]);
      const double keep = node[q];
      double gp = 0.0, gm = 0.0;
      node[q] = keep + h;
      const bool okp = gap_of(ui, k, node, gp);
      node[q] = keep - h;
      const bool okm = gap_of(ui, k, node, gm);
      node[q] = keep;
      if (!okp || !okm) return false;
      values[gap_pos_[12 * ui + static_cast<std::size_t>(q)]] = dgap * (gp - gm) / (2.0 * h);
    }
  }
  return true;
}

// Largest system factored densely: two disk intervals (18 unknowns).
constexpr int kDenseSizeLimit = 18;
// Warm starts: the Newton iterations one Jacobian serves, and the iterations of the previous
// solve above which its Jacobian is too stale to start from.
constexpr int kReuseSetupCalls = 10;
constexpr int kStaleAfterIterations = 3;

bool same_integrator(const SolverOptions& a, const SolverOptions& b) {
  return a.integrator == b.integrator && a.rk4_steps == b.rk4_steps && a.rk4_max_step == b.rk4_max_step &&
         a.cvode_rtol == b.cvode_rtol && a.cvode_atol == b.cvode_atol;
}

// The mutable memory of VCref's solves and the problem of the bound input.
class VcrefWorkspace final : public ModelWorkspace, public detail::ModelProblem, public detail::ContactHost {
 public:
  VcrefWorkspace(const VcrefModel& owner, const VcrefModel::Data& d)
      : ModelWorkspace(owner),
        d_(d),
        problem_(d),
        integrator_(bvp::make_integrator(detail::integrator_options(integrator_options_))),
        shooting_(problem_, *integrator_, d.structure),
        system_(problem_, shooting_, integrator_) {}

  void bind(const ModelInput& input, const SolverOptions& options, const VcrefOptions& vo) {
    if (!same_integrator(options, integrator_options_)) {
      integrator_ = bvp::make_integrator(detail::integrator_options(options));
      integrator_options_ = options;
      shooting_.set_integrator(*integrator_);
    }
    detail::update_stability_integrator(options, stability_integrator_);
    problem_.bind(input, options);  // no contact candidates
    select_structure();
    shooting_.invalidate();
    convention_ = input.actuation.convention;
    reuse_ = vo.reuse_jacobian;
    // Cold-start rule: external loads only (the tendon chords follow the disks).
    const physics::LoadCase& l = problem_.loads();
    const double worst = std::max(l.load_parameter() / vo.load_threshold,
                                  l.compression_parameter() / vo.compression_threshold);
    cold_ = detail::ColdStart{};
    if (worst > 1.0) {
      char why[160];
      std::snprintf(why, sizeof why,
                    "loaded from rest: L^2 (|W| + |F_tip|) / EI = %.3g, compression parameter %.3g (thresholds %g, %g)",
                    l.load_parameter(), l.compression_parameter(), vo.load_threshold, vo.compression_threshold);
      cold_ = detail::ColdStart{true, 1.0 / worst, why};
    }
  }

  bvp::ParameterizedSystem* system() override { return &system_; }
  bvp::NewtonSolver& newton() override {
    // Kept alive so that a later structure cannot take the address of the pattern NewtonSolver
    // last saw (a pattern change then always changes the pointer, too).
    solved_ = shooting_.structure();
    return newton_;
  }
  // KLU above two intervals: the Jacobian is block tridiagonal, and a dense LU of even 66
  // unknowns (paper robot, n = 3) costs more than the shots of a Newton iteration.
  void adjust(bvp::NewtonOptions& options) const override { options.dense_size_limit = kDenseSizeLimit; }
  // VcrefOptions::reuse_jacobian: a warm start begins with the previous solve's Jacobian
  // (modified Newton, a fresh one when the residual stops falling fast): along a trajectory an
  // iteration then costs one shot per interval instead of seven. Not after a slow solve (its
  // Jacobian may be far from here) or a change of the Jacobian's pattern.
  void adjust_warm(bvp::NewtonOptions& options, bool same_input) const override {
    if (!reuse_) return;
    options.reuse_jacobian =
        (same_input || last_iterations_ <= kStaleAfterIterations) && solved_ == shooting_.structure();
    options.max_setup_calls = kReuseSetupCalls;
  }
  detail::ColdStart cold_start() const override { return cold_; }
  void cold_guess(Eigen::VectorXd& x) override {
    shape_guess(x, d_.arc_guess);
    append_forces(x, true);
  }
  // The other shape: under antagonistic tensions with a tip force the arcs can start Newton in a
  // basin it does not leave (tests/data/antagonistic_tip_force.json), the straight robot not.
  bool alternative_guess(Eigen::VectorXd& x) override {
    shape_guess(x, !d_.arc_guess);
    append_forces(x, true);
    return true;
  }
  void rest_state(Eigen::VectorXd& x) override {
    shape_guess(x, false);
    append_forces(x, true);
  }
  std::string integrator_name() const override { return integrator_->name(); }
  // The test on a coarse mesh costs a fraction of a cold loaded solve (solve/stability_mesh.hpp):
  // +17 % on the median loaded case of bench_loaded, so the automatic rule tests direct answers
  // under loads too.
  bool automatic_stability_under_loads() const override { return true; }
  // The reduced stiffness in the disk poses (vcref_stability.cpp).
  Stability stability(const Eigen::VectorXd& x, double load_factor) override {
    if (d_.friction)
      return Stability{StabilityStatus::Undetermined, NAN,
                       "tendon friction: the disk-pose stiffness test assumes tensions independent of the shape"};
    if (problem_.loads().load_factor() != load_factor) system_.set_parameter(load_factor);
    // With contact the candidates' forces follow the shooting unknowns (constraints or penalties
    // in the test: vcref_stability.cpp).
    const int n = shooting_.size();
    if (!problem_.candidates().empty()) problem_.set_contact_forces(x.data() + n);
    if (!shooting_.evaluate(x.head(n)))
      return Stability{StabilityStatus::Undetermined, NAN, "the shots at the answer failed"};
    // The rods' transfer matrices on the stability test's coarse RK4 mesh (the solve's CVODE).
    return disk_pose_stability(problem_, stability_integrator_ ? *stability_integrator_ : *integrator_,
                               shooting_.nodes());
  }

  // The previous unknowns, its disk rotations as the chart references (w = 0).
  bool warm_guess(const Solution& prev, Eigen::VectorXd& x) override {
    const int N = d_.N;
    if (prev.unknowns.size() < d_.size || static_cast<int>(prev.disk_frames.size()) != N + 1 ||
        !prev.unknowns.allFinite())
      return false;
    x = prev.unknowns.head(d_.size);
    warm_contacts(prev);
    append_forces(x, false);
    for (int j = 1; j < N; ++j) {
      problem_.reference(j) = lie::nearest_rotation(prev.disk_frames[j].R);
      x.segment<3>(6 + 12 * (j - 1) + 3).setZero();
    }
    shooting_.invalidate();
    return true;
  }

  bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) override {
    problem_.set_driven_tensions(index, T);
    shooting_.invalidate();
    return true;
  }
  // The disk frames from the nodes' poses (unknowns, no integration) and the tip from one shot
  // of the last interval: a finite difference of the pulls in one unknown costs one interval.
  bool tendon_pulls(const Eigen::VectorXd& x, Eigen::VectorXd& d) override {
    const int N = d_.N;
    pull_frames_.assign(N + 1, Frame{});
    double y[cosserat::kStateSize];
    auto node = [&](int k) { return x.data() + (k == 0 ? 0 : 6 + 12 * (k - 1)); };
    for (int j = 1; j < N; ++j) {
      problem_.start_state(j, node(j), y);
      pull_frames_[j] = cosserat::frame_of(y);
    }
    problem_.start_state(N - 1, node(N - 1), y);
    if (!integrator_->integrate(problem_.ode(N - 1), problem_.node(N - 1), problem_.node(N), y)) return false;
    pull_frames_[N] = cosserat::frame_of(y);
    const std::vector<double> pulls = tendon::chord_displacements(pull_frames_, *d_.routing, convention_);
    d = Eigen::Map<const Eigen::VectorXd>(pulls.data(), static_cast<Eigen::Index>(pulls.size()));
    return d.allFinite();
  }

  void extract(const Eigen::VectorXd& x, bool evaluated, Solution& sol) override {
    const int N = d_.N;
    sol.contacts.clear();
    const TendonRouting& routing = *d_.routing;
    last_iterations_ = sol.summary.iterations;
    sol.tensions = problem_.loads().full_tensions();
    if (!evaluated) {
      sol.disk_frames.assign(N + 1, Frame{});
      return;
    }
    const bvp::ShootingNodes nodes = shooting_.nodes();
    sol.disk_frames.assign(N + 1, Frame{});
    for (int j = 1; j < N; ++j) sol.disk_frames[j] = cosserat::frame_of(nodes.start(j));
    sol.disk_frames[N] = cosserat::frame_of(nodes.end(N - 1));
    sol.tendon_displacements = tendon::chord_displacements(sol.disk_frames, routing, convention_);
    if (d_.friction) {
      std::vector<double> chord(problem_.tensions().size() * routing.disk_count(), 0.0);
      tendon::friction_tensions(sol.disk_frames.data(), problem_.active(), problem_.tensions().data(), d_.tendon_friction,
                                chord.data());
      sol.tendon_end_tensions = tendon::end_tensions(routing, chord.data(), static_cast<int>(routing.tendons.size()));
    }
    sol.disk_frames[N].R = lie::nearest_rotation(sol.disk_frames[N].R);
    if (problem_.contact_on()) report_contacts(nodes, sol);
    sol.backbone.resize(N + 1);
    sol.backbone[0] = BackboneSample{0.0, Frame{}, x.segment<3>(0), x.segment<3>(3)};
    for (int j = 1; j <= N; ++j) {
      const double* e = nodes.end(j - 1);
      sol.backbone[j] = BackboneSample{routing.disk_s[j], sol.disk_frames[j], cosserat::force(e), cosserat::moment(e)};
    }
  }

  // Contact (solve/contact_completion.hpp, docs/contact.md).
  Completion complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) override {
    return detail::complete_contacts(*this, y, options, summary);
  }
  const std::vector<Obstacle>& contact_obstacles() const override { return problem_.obstacles(); }
  const contact::Surfaces& contact_surfaces() const override { return problem_.surfaces(); }
  contact::Law& contact_law() override { return problem_.law(); }
  std::vector<contact::Candidate>& contact_candidates() override { return problem_.candidates(); }
  void contact_candidates_changed() override { system_.contacts_changed(); }
  bvp::ParameterizedSystem& contact_system() override { return system_; }
  bvp::NewtonSolver& contact_newton() override { return newton(); }
  // The disk frames 1..N of the shooting unknowns (one shot per interval).
  bool contact_frames(const Eigen::VectorXd& y, std::vector<Frame>& frames) override {
    if (!shooting_.evaluate(y.head(d_.size))) return false;
    const bvp::ShootingNodes nodes = shooting_.nodes();
    frames.resize(static_cast<std::size_t>(d_.N + 1));
    frames[0] = Frame{};
    for (int j = 1; j <= d_.N; ++j) frames[static_cast<std::size_t>(j)] = problem_.disk_frame(j, nodes);
    return true;
  }
  void contact_rest(Eigen::VectorXd& y) override { rest_state(y); }
  const std::vector<double>& contact_disk_s() const override { return d_.routing->disk_s; }
  int contact_disks() const override { return d_.N; }
  double contact_length() const override { return d_.length; }

 private:
  // --- Contact (docs/contact.md) ---
  // x (the shooting unknowns) extended by the candidates' scaled forces (`zero`: 0).
  void append_forces(Eigen::VectorXd& x, bool zero) const {
    const std::vector<contact::Candidate>& c = problem_.candidates();
    if (c.empty()) return;
    const Eigen::Index n = x.size();
    x.conservativeResize(n + static_cast<Eigen::Index>(c.size()));
    for (std::size_t i = 0; i < c.size(); ++i) x[n + static_cast<Eigen::Index>(i)] = zero ? 0.0 : c[i].lambda;
  }
  // The contacts of a previous answer as the candidates, their forces as the guess.
  void warm_contacts(const Solution& prev) {
    problem_.candidates().clear();
    if (problem_.contact_on())
      detail::warm_contacts(prev, d_.N, static_cast<int>(problem_.obstacles().size()), problem_.law().force_scale,
                            problem_.candidates());
    system_.contacts_changed();
  }
  void report_contacts(const bvp::ShootingNodes& nodes, Solution& sol) {
    std::vector<contact::Candidate>& cands = problem_.candidates();
    for (std::size_t i = 0; i < cands.size(); ++i) cands[i].at = problem_.contact_at(i, problem_.disk_frame(cands[i].disk, nodes));
    contact::report(cands, d_.routing->disk_s, problem_.law().force_scale, kReportedForce, sol.contacts);
  }
  static constexpr double kReportedForce = 1e-9;  // scaled forces below: no contact

  std::vector<Frame> pull_frames_;  // tendon_pulls()
  // The Jacobian structure of the bound input's pass-through mask: the model's (every routed
  // tendon) when they agree, else the last or second-last one built here (a trajectory rebuilds
  // it only when its mask changes).
  void select_structure() {
    const std::vector<char>& mask = problem_.pass_through();
    std::shared_ptr<const bvp::ShootingStructure> s = d_.structure;
    if (mask != d_.pass_through) {
      if (cache_[1].mask == mask) std::swap(cache_[0], cache_[1]);
      if (cache_[0].mask != mask) {
        cache_[1] = std::move(cache_[0]);
        cache_[0] = Structure{mask, bvp::ShootingStructure::of(problem_)};
      }
      s = cache_[0].structure;
    }
    if (s != shooting_.structure()) shooting_.set_structure(std::move(s));
  }

  // Disk poses on the constant-curvature arcs of the tendon moments (paper Eq. 8 with u = sum T_k
  // (e_z x r_k) / EI per segment) or, with `arcs` false, the straight robot; wrenches from the
  // statics of that shape (backward pass of the disk equilibria at the current load factor).
  // Rbar_j = R_j, w_j = 0. With arcs, then fixed-point passes as CCsub's cold guess: each
  // interval bent into the arc of the moment at its proximal disk (u = K^-1 R^T m), the statics
  // redone on that shape, while the passes contract (the largest change of u l halves); they add
  // the external loads' bending to the tendons' arcs.
  void shape_guess(Eigen::VectorXd& x, bool arcs) {
    const int N = d_.N;
    const TendonRouting& routing = *d_.routing;
    const std::vector<double>& T = problem_.tensions();
    frames_.assign(N + 1, Frame{});
    u_.assign(N + 1, Vec3::Zero());
    m_.assign(N + 1, Vec3::Zero());
    for (int j = 1; j <= N; ++j) {
      const int seg = routing.disk_segment[j];
      Vec3 u = Vec3::Zero();
      if (arcs)
        for (const RoutedTendon& t : problem_.active().tendons)
          if (t.segment >= seg) u += T[t.index] * Vec3::UnitZ().cross(physics::tendon_offset(t, routing.disk_s[j]));
      u_[j] = d_.section.inv_kbt.cwiseProduct(u);
    }
    shape_statics(x);
    double last = INFINITY;
    for (int pass = 0; arcs && pass < d_.guess_passes; ++pass) {
      double change = 0.0;
      for (int j = 1; j <= N; ++j) {
        const double l = routing.disk_s[j] - routing.disk_s[j - 1];
        const Vec3 u = d_.section.inv_kbt.cwiseProduct(frames_[j - 1].R.transpose() * m_[j - 1]);
        const double d = u.allFinite() ? l * (u - u_[j]).cwiseAbs().maxCoeff() : NAN;
        if (!(d <= change)) change = d;  // NaN ends the passes with the last finite shape
        next_u_[j] = u;
      }
      if (!(change <= 0.5 * last)) break;
      last = change;
      std::swap(u_, next_u_);
      shape_statics(x);
    }
    shooting_.invalidate();
  }

  // The unknowns of the shape with curvature u_[j] on interval j: disk poses, reference
  // rotations, and the wrenches of the backward pass (m_[j]: the moment just distal of disk j,
  // about its centre, base frame).
  void shape_statics(Eigen::VectorXd& x) {
    const int N = d_.N;
    const TendonRouting& routing = *d_.routing;
    const std::vector<double>& T = problem_.tensions();
    x.setZero(d_.size);
    next_u_.resize(N + 1);
    for (int j = 1; j <= N; ++j) {
      const double l = routing.disk_s[j] - routing.disk_s[j - 1];
      frames_[j] = frames_[j - 1] * lie::exp_se3(u_[j] * l, Vec3::UnitZ() * l);
      if (j < N) problem_.reference(j) = frames_[j].R;
    }
    const physics::LoadCase& load = problem_.loads();
    Vec3 n = Vec3::Zero(), m = Vec3::Zero();  // wrench just distal of disk j
    const Vec3 w = problem_.rod_weight();
    for (int j = N; j >= 1; --j) {
      if (problem_.tendon_at(j)) {
        const tendon::DiskWrench dw = tendon::disk_wrench(j, frames_.data(), problem_.active(), T.data(), d_.remove_normal);
        n += dw.force;
        m += dw.moment;
      }
      if (load.has_disk_weight()) n += load.disk_weight(j);
      if (j == N && load.has_tip_wrench()) {
        n += load.tip_force();
        m += load.tip_moment();
      }
      // Interval j, chord approximation: n' = -w, m' = -p' x n.
      const double l = routing.disk_s[j] - routing.disk_s[j - 1];
      const Vec3 dp = frames_[j].p - frames_[j - 1].p;
      m += dp.cross(n + 0.5 * w * l);
      n += w * l;
      m_[j - 1] = m;
      const int c = j - 1 == 0 ? 0 : 6 + 12 * (j - 2);  // first unknown of node j-1
      if (j - 1 >= 1) x.segment<3>(c) = frames_[j - 1].p;
      x.segment<3>(j - 1 == 0 ? 0 : c + 6) = n;
      x.segment<3>(j - 1 == 0 ? 3 : c + 9) = m;
    }
  }

  const VcrefModel::Data& d_;
  VcrefShooting problem_;
  SolverOptions integrator_options_;
  std::unique_ptr<bvp::Integrator> integrator_;
  std::unique_ptr<bvp::Rk4Integrator> stability_integrator_;  // solve/stability_mesh.hpp; null with CVODE
  bvp::ShootingSystem shooting_;
  VcrefSystem system_;
  bvp::NewtonSolver newton_;
  detail::ColdStart cold_;
  Actuation::DisplacementConvention convention_ = Actuation::DisplacementConvention::AtBase;
  std::vector<Frame> frames_;  // guess scratch
  std::vector<Vec3> u_, next_u_, m_;  // guess scratch: interval curvatures, moments
  struct Structure {
    std::vector<char> mask;  // VcrefShooting::pass_through() it was built for
    std::shared_ptr<const bvp::ShootingStructure> structure;
  };
  Structure cache_[2];  // most recently used first
  std::shared_ptr<const bvp::ShootingStructure> solved_;  // structure of the last newton() call
  int last_iterations_ = 0;  // Newton iterations of the last solve (Jacobian reuse)
  bool reuse_ = false;       // VcrefOptions::reuse_jacobian
};

}  // namespace

VcrefModel::VcrefModel(const Robot& robot, const Effects& effects, const VcrefOptions& options)
    : StaticModel(robot, effects), options_(options) {
  if (!(options_.load_threshold > 0.0))
    throw InputError("vcref.load_threshold", format_value(options_.load_threshold), "must be positive");
  if (!(options_.compression_threshold > 0.0))
    throw InputError("vcref.compression_threshold", format_value(options_.compression_threshold), "must be positive");
  if (options_.guess_passes < 0 || options_.guess_passes > 20)
    throw InputError("vcref.guess_passes", std::to_string(options_.guess_passes), "must be in 0..20");
  auto d = std::make_shared<Data>();
  d->robot = &this->robot();
  d->routing = &routing();
  d->N = this->robot().total_disks();
  const int N = d->N;
  d->size = 6 + 12 * (N - 1);
  d->pass_through.assign(N + 1, 0);
  for (const RoutedTendon& t : routing().tendons)
    for (int j = 1; j < t.end_disk; ++j) d->pass_through[j] = 1;
  d->section = cosserat::Section::from(this->robot(), effects, Vec3::Zero());
  d->remove_normal = effects.disk_normal_force == DiskNormalForce::Removed;
  d->friction = effects.tendon_friction.on();
  d->tendon_friction = effects.tendon_friction;
  d->arc_guess = options_.initial_guess == VcrefOptions::InitialGuess::ConstantCurvature;
  d->guess_passes = options_.guess_passes;
  d->length = this->robot().total_length();
  d->l_min = d->length;
  for (int j = 1; j <= N; ++j) d->l_min = std::min(d->l_min, routing().disk_s[j] - routing().disk_s[j - 1]);
  // The Jacobian pattern of every routed tendon; workspaces drop the untensioned ones.
  d->structure = bvp::ShootingStructure::of(VcrefShooting(*d));
  data_ = d;
}

VcrefModel::~VcrefModel() = default;

std::unique_ptr<ModelWorkspace> VcrefModel::make_workspace() const {
  return std::make_unique<VcrefWorkspace>(*this, *data_);
}

detail::ModelProblem& VcrefModel::bind(ModelWorkspace& workspace, const ModelInput& input,
                                       const SolverOptions& options) const {
  auto& ws = static_cast<VcrefWorkspace&>(workspace);
  ws.bind(input, options, options_);
  return ws;
}

namespace {
physics::LoadCase load_case(const StaticModel& model, const ModelInput& input) {
  input.validate(model.robot());
  physics::LoadCase l;
  l.bind(model.robot(), model.routing(), input);
  return l;
}
}  // namespace

double VcrefModel::load_parameter(const ModelInput& input) const { return load_case(*this, input).load_parameter(); }

double VcrefModel::compression_parameter(const ModelInput& input) const {
  return load_case(*this, input).compression_parameter();
}

bool VcrefModel::loads_from_rest(const ModelInput& input) const {
  return load_parameter(input) > options_.load_threshold ||
         compression_parameter(input) > options_.compression_threshold;
}

int VcrefModel::unknowns() const { return data_->size; }

int VcrefModel::jacobian_nonzeros() const { return data_->structure->pattern.nnz(); }

int VcrefModel::jacobian_nonzeros(const ModelInput& input) const {
  input.validate(robot());
  check_input(input);
  VcrefShooting problem(*data_);
  problem.bind(input, SolverOptions());
  return problem.pass_through() == data_->pass_through ? jacobian_nonzeros()
                                                       : bvp::ShootingStructure::of(problem)->pattern.nnz();
}

bvp::JacobianCheck VcrefModel::check_jacobian(ModelWorkspace& workspace, const ModelInput& input,
                                              const SolverOptions& options, const Solution* at,
                                              double perturbation) const {
  if (!workspace.belongs_to(*this))
    throw InputError("workspace", "a workspace of another model", "use VcrefModel::make_workspace()");
  input.validate(robot());
  check_input(input);
  auto& ws = static_cast<VcrefWorkspace&>(workspace);
  ws.bind(input, options, options_);
  bvp::ParameterizedSystem& sys = *ws.system();
  sys.set_parameter(1.0);
  Eigen::VectorXd x;
  if (!(at && ws.warm_guess(*at, x))) ws.cold_guess(x);
  Eigen::VectorXd scale(sys.size());  // the contact forces of `at` join the unknowns
  sys.unknown_scale(scale);
  for (int i = 0; i < x.size(); ++i) x[i] += perturbation * std::sin(1.0 + i) / scale[i];
  return bvp::check_jacobian(sys, x);
}


}  // namespace tdcr
