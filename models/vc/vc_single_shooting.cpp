// VC by single shooting: unknowns n(0), m(0), residual the tip wrench (vc.hpp).
#include <cmath>

#include "tdcr/bvp/newton_solver.hpp"
#include "physics/tendon_path.hpp"
#include "solve/contact_completion.hpp"
#include "vc/vc_shooting.hpp"
#include "vc/vc_stability.hpp"

namespace tdcr::vc {

namespace {

/// Bound on the scaled Newton step (KINSOL mxnewtstep): by global equilibrium |n(0)| <= F_s and
/// |m(0)| <~ M_s, so the solution lies within a scaled distance of about sqrt(6) of the origin;
/// longer steps only overshoot into strongly coiled shapes (where RK4 fails or a wrong
/// equilibrium waits).
constexpr double kMaxNewtonStep = 1.0;

/// The Newton iterations a Jacobian serves (modified Newton: KINSOL takes a fresh one earlier when
/// the residual stops falling fast enough): a cold solve converges in about 4 shots after its one
/// Jacobian (6 shots) instead of 2 iterations with a Jacobian each. Warm-started solves
/// (VcOptions::reuse_jacobian) start from the previous solve's Jacobian unless that solve took more
/// than kStaleAfterIterations iterations (a fresh one at the warm guess then). 7, not 10: on the
/// hardest of the 60 loaded side-by-side cases (case 56, n = 3, 6.6 N and a 0.45 N tip force) the
/// cold guess's Jacobian converged linearly in 17 iterations, where a fresh one after 7 takes 10 (its
/// instructions -18 %); over the 60 cases' cold default solves -3 % (callgrind; 10, 8, 7, 6, 5, 4:
/// 770, 755, 748, 756, 775, 814 M instructions for 3 solves of each).
constexpr int kReuseSetupCalls = 7;
constexpr int kStaleAfterIterations = 3;

/// The shooting residual as Newton sees it; its parameter is the load factor. Every shot records
/// the disk frames, backbone samples and tendon lengths (the final pass's rod, with length
/// states), and the last shot is memoised: the solver's check of its returned point and the
/// driver's final pass at the same unknowns and loads reuse it instead of shooting again.
class ShootingSystem final : public bvp::ParameterizedSystem {
 public:
  explicit ShootingSystem(VcWorkspace::Impl& W) : W_(W) {}
  // With contact candidates (W.contacts, docs/contact.md) their scaled force magnitudes follow
  // n(0), m(0) and their complementarity residuals the tip wrench; the forces act at their disks
  // among the disk point loads.
  int contacts() const { return static_cast<int>(W_.contacts.size()); }
  int size() const override { return 6 + contacts(); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const Vec6 xx = x.head<6>();
    const int nc = contacts();
    bool same = valid_ && version_ == W_.loads_version && xx == x_ && xc_.size() == nc;
    for (int i = 0; same && i < nc; ++i) same = xc_[i] == x[6 + i];
    if (!same) {
      frames_.clear();
      samples_.clear();
      W_.degeneracy.reset();
      for (int i = 0; i < nc; ++i) W_.contacts[static_cast<std::size_t>(i)].lambda = x[6 + i];
      const Record rec{&frames_, &samples_, &W_.segment_lengths, &end_tensions_};
      x_ = xx;
      if (xc_.size() != nc) xc_.resize(nc);  // allocates only when the candidates change
      xc_ = x.tail(nc);
      version_ = W_.loads_version;
      valid_ = shoot(W_, true, xx, f_, &rec);
    }
    if (!valid_) return false;
    f.head<6>() = f_;
    for (int i = 0; i < nc; ++i) {
      contact::Candidate& c = W_.contacts[static_cast<std::size_t>(i)];
      c.at = contact_point(W_.obstacles[c.obstacle], frames_[static_cast<std::size_t>(c.disk)], c.body,
                           W_.surfaces.radius(c.disk, c.body));
      f[6 + i] = W_.law.residual(c.at.gap, x[6 + i]);
    }
    return f.allFinite();
  }
  /// What the last shot recorded.
  const std::vector<Frame>& frames() const { return frames_; }
  const std::vector<BackboneSample>& samples() const { return samples_; }
  const std::vector<double>& end_tensions() const { return end_tensions_; }
  // With RK4 the exact Jacobian of the discrete shot (vc_jacobian.cpp, about one shot's cost);
  // with CVODE forward differences by the solver (6 extra shots), with increments
  // sqrt(max(eps, relative_noise)) = sqrt(rtol). With contact candidates: forward differences
  // by the solver (6 + candidates shots).
  bool has_jacobian() const override {
    return contacts() == 0 && W_.model->options().exact_jacobian && has_exact_jacobian(W_);
  }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>&,
                Eigen::Ref<Eigen::MatrixXd> J) override {
    Vec6 r;
    Mat6 Jx;
    if (!shoot_jacobian(W_, Vec6(x), r, Jx)) return false;
    J = Jx;
    return true;
  }
  double relative_noise() const override { return W_.shot_integrator->relative_noise(); }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    s.head<3>().setConstant(1.0 / W_.loads.force_scale());
    s.segment<3>(3).setConstant(1.0 / W_.loads.moment_scale());
    s.tail(s.size() - 6).setOnes();  // phi: the gap in units of r_o, the force in units of F_s
  }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { residual_scale(s); }
  void set_parameter(double lambda) override { set_load_factor(W_, lambda); }

 private:
  VcWorkspace::Impl& W_;
  // The last shot: unknowns, loads version, residual, success, records.
  Vec6 x_ = Vec6::Zero();
  Eigen::VectorXd xc_;  // and its contact forces
  unsigned long version_ = 0;
  Vec6 f_ = Vec6::Zero();
  bool valid_ = false;
  std::vector<Frame> frames_;
  std::vector<BackboneSample> samples_;
  std::vector<double> end_tensions_;  ///< Friction: each tendon's tension at its end.
};

class SingleShooting final : public detail::ModelProblem, public detail::ContactHost {
 public:
  explicit SingleShooting(VcWorkspace::Impl& W) : W_(W), system_(W) {}

  // Contact (solve/contact_completion.hpp, docs/contact.md).
  Completion complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) override {
    return detail::complete_contacts(*this, y, options, summary);
  }
  const std::vector<Obstacle>& contact_obstacles() const override { return W_.obstacles; }
  const contact::Surfaces& contact_surfaces() const override { return W_.surfaces; }
  contact::Law& contact_law() override { return W_.law; }
  std::vector<contact::Candidate>& contact_candidates() override { return W_.contacts; }
  void contact_candidates_changed() override {}
  bvp::ParameterizedSystem& contact_system() override { return system_; }
  bvp::NewtonSolver& contact_newton() override { return newton_; }
  bool contact_frames(const Eigen::VectorXd& y, std::vector<Frame>& frames) override {
    scratch_f_.resize(system_.size());
    if (!system_.residual(y, scratch_f_)) return false;
    frames = system_.frames();
    return static_cast<int>(frames.size()) == W_.model->routing().disk_count();
  }
  void contact_rest(Eigen::VectorXd& y) override { rest_state(y); }
  const std::vector<double>& contact_disk_s() const override { return W_.model->routing().disk_s; }
  int contact_disks() const override { return W_.model->routing().disk_count() - 1; }
  double contact_length() const override { return W_.model->robot().total_length(); }
  bvp::ParameterizedSystem* system() override { return &system_; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void adjust(bvp::NewtonOptions& options) const override {
    options.max_newton_step = kMaxNewtonStep;
    options.max_setup_calls = kReuseSetupCalls;
  }
  void adjust_warm(bvp::NewtonOptions& options, bool same_input) const override {
    if (!W_.model->options().reuse_jacobian) return;
    options.reuse_jacobian = same_input || last_iterations_ <= kStaleAfterIterations;
    options.max_setup_calls = kReuseSetupCalls;
  }
  // Without external loads (no tip wrench, weights or obstacles) the base reaction is the
  // tendons' pull at the clamped base. Where every tendon leaves the base along the backbone
  // (r_k'(0) = 0: straight routing), its direction there, v + u x r_k, is the backbone's tangent
  // whatever the strains (u x r_k is along it for r_k in the cross-section, and no shear force
  // arises), so the equilibrium guess is the exact answer. Curved routing tilts it by the strains.
  detail::ColdStart cold_start() const override {
    detail::ColdStart c;
    const physics::LoadCase& L = W_.loads;
    bool along_backbone = true;
    for (const RoutedTendon& t : W_.model->routing().tendons) {
      const Vec3 d = physics::rest_tangent(t, 0.0);
      along_backbone = along_backbone && d.x() == 0.0 && d.y() == 0.0;
    }
    c.guess_is_answer = along_backbone && W_.model->options().initial_guess == VcInitialGuess::Equilibrium &&
                        !L.has_tip_wrench() && !L.has_gravity() && W_.obstacles.empty();
    return c;
  }
  void cold_guess(Eigen::VectorXd& x) override {
    x = guess(W_.model->options().initial_guess);
    append_forces(x, true);
  }
  bool alternative_guess(Eigen::VectorXd& x) override {
    // The equilibrium guess overestimates the lever of tip forces on strongly bent robots,
    // zeros ignore the tendons.
    x = guess(W_.model->options().initial_guess == VcInitialGuess::Equilibrium ? VcInitialGuess::Zero
                                                                               : VcInitialGuess::Equilibrium);
    append_forces(x, true);
    return true;
  }
  // The unloaded robot is straight: n = m = 0 exactly (and every candidate's force 0).
  void rest_state(Eigen::VectorXd& x) override {
    x = Eigen::VectorXd::Zero(6);
    append_forces(x, true);
  }
  // A previous answer's contacts become the candidates, their forces the guess; its base wrench
  // (with contacts: its own unknowns, which balance its contact forces too) or the reaction of its
  // shape under the bound loads.
  bool warm_guess(const Solution& previous, Eigen::VectorXd& x) override {
    W_.contacts.clear();
    if (!W_.obstacles.empty())
      detail::warm_contacts(previous, contact_disks(), static_cast<int>(W_.obstacles.size()), W_.law.force_scale,
                            W_.contacts);
    Vec6 r;
    if (W_.contacts.empty() && warm_reaction(previous, r)) {
      x = r;
      return true;
    }
    if (previous.unknowns.size() >= 6 && previous.unknowns.allFinite()) {
      x = previous.unknowns.head(6);
      append_forces(x, false);
      return true;
    }
    W_.contacts.clear();
    return false;
  }
  bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) override {
    vc::set_driven_tensions(W_, index, T);
    return true;
  }
  // Every shot records the tendon lengths at the segment ends (memoised: after Newton's residual
  // at x this shoots nothing).
  bool tendon_pulls(const Eigen::VectorXd& x, Eigen::VectorXd& d) override {
    scratch_f_.resize(system_.size());  // allocates only when the candidates change
    if (!system_.residual(x, scratch_f_)) return false;
    tendon_displacements(W_, W_.segment_lengths, pulls_);
    d = Eigen::Map<const Eigen::VectorXd>(pulls_.data(), static_cast<Eigen::Index>(pulls_.size()));
    return d.allFinite();
  }
  // The final pass records frames, samples and tendon lengths, and its end wrench is the residual
  // (usually the memoised last shot of Newton).
  bool final_residual(const Eigen::VectorXd& x, Eigen::Ref<Eigen::VectorXd> f) override {
    return system_.residual(x, f);
  }
  void extract(const Eigen::VectorXd& x, bool evaluated, Solution& sol) override {
    last_iterations_ = sol.summary.iterations;
    sol.tensions = W_.loads.full_tensions();
    if (!evaluated) {
      if (sol.summary.converged()) {
        sol.summary.termination = TerminationType::IntegrationFailed;
        sol.summary.message += "; the final pass at the solution failed to integrate";
      }
      return;
    }
    sol.disk_frames = system_.frames();
    sol.backbone = system_.samples();
    sol.contacts.clear();
    if (!W_.contacts.empty()) {
      scratch_f_.resize(system_.size());
      if (system_.residual(x, scratch_f_))  // memoised: sets the candidates' contact points
        contact::report(W_.contacts, W_.model->routing().disk_s, W_.law.force_scale, 1e-9, sol.contacts);
    }
    tendon_displacements(W_, W_.segment_lengths, sol.tendon_displacements);
    if (W_.friction) sol.tendon_end_tensions = system_.end_tensions();
  }
  // The conjugate-point test on its coarse mesh (solve/stability_mesh.hpp) still adds 80-100 % to
  // the median loaded solve of bench_loaded (65 % of the instructions; its 6 perturbed shots per
  // disk interval, docs/models.md "Stability"): over the automatic rule's budget, so direct
  // answers under loads are not tested without asking.
  bool automatic_stability_under_loads() const override { return false; }
  Stability stability(const Eigen::VectorXd& x, double load_factor) override {
    if (W_.friction)
      return Stability{StabilityStatus::Undetermined, NAN,
                       "tendon friction: the conjugate-point test assumes tensions independent of the shape"};
    // The contact forces of x act at their disks in the test's shots (constraints or penalties
    // there: vc_stability.cpp).
    const int nc = static_cast<int>(W_.contacts.size());
    for (int i = 0; i < nc; ++i) W_.contacts[static_cast<std::size_t>(i)].lambda = x[6 + i];
    return conjugate_point_test(W_, Vec6(x.head<6>()), load_factor);
  }
  bool infeasibility(const Eigen::VectorXd&, double threshold, std::string& why) override {
    return tendon_limit(W_, threshold, why);
  }
  // Single shooting cannot damp a snap; multiple shooting damps the inner disks' poses. Its node
  // 0 holds the base wrench, this formulation's unknowns. Not with friction (single shooting only).
  detail::ModelProblem* damping_formulation() override {
    if (W_.friction || !W_.obstacles.empty()) return nullptr;  // multiple shooting has no contact
    if (!W_.multiple) W_.multiple = make_multiple_shooting(W_);
    return W_.multiple.get();
  }
  void from_damping_formulation(const Eigen::VectorXd& y, Eigen::VectorXd& x) override { x = y.segment<6>(12); }
  std::string integrator_name() const override { return W_.shot_integrator->name(); }

 private:
  // x (n(0), m(0)) extended by the candidates' scaled forces (`zero`: 0).
  void append_forces(Eigen::VectorXd& x, bool zero) const {
    const int nc = static_cast<int>(W_.contacts.size());
    if (nc == 0) return;
    x.conservativeResize(6 + nc);
    for (int i = 0; i < nc; ++i) x[6 + i] = zero ? 0.0 : W_.contacts[static_cast<std::size_t>(i)].lambda;
  }
  // The cold-start guess at load factor 1 (VcInitialGuess).
  Vec6 guess(VcInitialGuess which) const {
    Vec6 x = Vec6::Zero();
    if (which == VcInitialGuess::Zero) return x;
    const physics::LoadCase& L = W_.loads;
    const TendonRouting& rt = W_.model->routing();
    const double length = W_.model->robot().total_length();
    // The tendons' pull on the straight robot at the base, T_k t_k(0) at r_k(0).
    Vec3 pull = Vec3::Zero(), tm = Vec3::Zero();
    for (const RoutedTendon& t : rt.tendons) {
      const Vec3 p = L.tension(t.index) * physics::rest_tangent(t, 0.0);
      pull += p;
      tm -= physics::tendon_offset(t, 0.0).cross(p);
    }
    // Weights of the straight robot and their moments about the base.
    Vec3 weight = Vec3::Zero(), weight_moment = Vec3::Zero();
    if (L.has_disk_weight())
      for (int j = 1; j < rt.disk_count(); ++j) {
        weight += L.disk_weight(j);
        weight_moment += (rt.disk_s[j] * Vec3::UnitZ()).cross(L.disk_weight(j));
      }
    if (L.has_backbone_weight()) {
      weight += length * L.backbone_weight();
      weight_moment += (0.5 * length * length * Vec3::UnitZ()).cross(L.backbone_weight());
    }
    x.head<3>() = L.tip_force() + weight - pull;
    x.tail<3>() = L.tip_moment() + (length * Vec3::UnitZ()).cross(L.tip_force()) + weight_moment + tm;
    return x;
  }

  // The base reaction of the previous shape under the bound loads (VcModel's warm start).
  bool warm_reaction(const Solution& previous, Vec6& x) const {
    const physics::LoadCase& L = W_.loads;
    const TendonRouting& rt = W_.model->routing();
    const cosserat::Section& S = W_.section;
    const int nd = rt.disk_count();
    if (static_cast<int>(previous.disk_frames.size()) != nd || static_cast<int>(previous.backbone.size()) != nd)
      return false;
    // Tendon directions at the base from the previous strains (R(0) = I).
    const Vec3 u0 = S.curvature(Mat3::Identity(), previous.backbone[0].m);
    const Vec3 v0 = S.strain(Mat3::Identity(), previous.backbone[0].n);
    Vec3 n = L.tip_force(), m = L.tip_moment() + previous.disk_frames.back().p.cross(L.tip_force());
    for (const RoutedTendon& t : rt.tendons) {
      const double T = L.tension(t.index);
      if (T <= 0.0) continue;
      const Vec3 r0 = physics::tendon_offset(t, 0.0);
      // The tendon's pull on the robot at the base.
      const Vec3 pull = T * physics::tendon_tangent(v0, u0, r0, physics::tendon_offset_rate(t, 0.0)).normalized();
      n -= pull;
      m -= r0.cross(pull);
    }
    if (L.has_disk_weight())
      for (int j = 1; j < nd; ++j) {
        n += L.disk_weight(j);
        m += previous.disk_frames[j].p.cross(L.disk_weight(j));
      }
    if (L.has_backbone_weight()) {
      // Integral of p over the backbone: trapezoid between disks with the end correction
      // h^2/12 (p'(a) - p'(b)), p' ~ R e_z (fourth order, Euler-Maclaurin).
      Vec3 integral = Vec3::Zero();
      for (int j = 1; j < nd; ++j) {
        const Frame& a = previous.disk_frames[j - 1];
        const Frame& b = previous.disk_frames[j];
        const double h = rt.disk_s[j] - rt.disk_s[j - 1];
        integral += 0.5 * h * (a.p + b.p) + (h * h / 12.0) * (a.R.col(2) - b.R.col(2));
      }
      n += W_.model->robot().total_length() * L.backbone_weight();
      m += integral.cross(L.backbone_weight());
    }
    x.head<3>() = n;
    x.tail<3>() = m;
    return x.allFinite();
  }

  VcWorkspace::Impl& W_;
  ShootingSystem system_;
  bvp::NewtonSolver newton_;
  int last_iterations_ = 0;  ///< Newton iterations of the last solve (Jacobian reuse).
  std::vector<double> pulls_;  ///< tendon_pulls()
  Eigen::VectorXd scratch_f_;  ///< residuals of tendon_pulls(), extract(), contact_frames()
};

}  // namespace

std::unique_ptr<detail::ModelProblem> make_single_shooting(VcWorkspace::Impl& W) {
  return std::make_unique<SingleShooting>(W);
}

}  // namespace tdcr::vc
