// VC by single shooting: unknowns n(0), m(0), residual the tip wrench (vc.hpp).
#include <cmath>

#include "tdcr/bvp/newton_solver.hpp"
#include "physics/tendon_path.hpp"
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
/// than kStaleAfterIterations iterations (a fresh one at the warm guess then).
constexpr int kReuseSetupCalls = 10;
constexpr int kStaleAfterIterations = 3;

/// The shooting residual as Newton sees it; its parameter is the load factor. Every shot records
/// the disk frames, backbone samples and tendon lengths (the final pass's rod, with length
/// states), and the last shot is memoised: the solver's check of its returned point and the
/// driver's final pass at the same unknowns and loads reuse it instead of shooting again.
class ShootingSystem final : public bvp::ParameterizedSystem {
 public:
  explicit ShootingSystem(VcWorkspace::Impl& W) : W_(W) {}
  int size() const override { return 6; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const Vec6 xx = x;
    if (!(valid_ && version_ == W_.loads_version && xx == x_)) {
      frames_.clear();
      samples_.clear();
      W_.degeneracy.reset();
      const Record rec{&frames_, &samples_, &W_.segment_lengths, &end_tensions_};
      x_ = xx;
      version_ = W_.loads_version;
      valid_ = shoot(W_, true, xx, f_, &rec);
    }
    if (!valid_) return false;
    f = f_;
    return true;
  }
  /// What the last shot recorded.
  const std::vector<Frame>& frames() const { return frames_; }
  const std::vector<BackboneSample>& samples() const { return samples_; }
  const std::vector<double>& end_tensions() const { return end_tensions_; }
  // With RK4 the exact Jacobian of the discrete shot (vc_jacobian.cpp, about one shot's cost);
  // with CVODE forward differences by the solver (6 extra shots), with increments
  // sqrt(max(eps, relative_noise)) = sqrt(rtol).
  bool has_jacobian() const override { return W_.model->options().exact_jacobian && has_exact_jacobian(W_); }
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
    s.tail<3>().setConstant(1.0 / W_.loads.moment_scale());
  }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { residual_scale(s); }
  void set_parameter(double lambda) override { set_load_factor(W_, lambda); }

 private:
  VcWorkspace::Impl& W_;
  // The last shot: unknowns, loads version, residual, success, records.
  Vec6 x_ = Vec6::Zero();
  unsigned long version_ = 0;
  Vec6 f_ = Vec6::Zero();
  bool valid_ = false;
  std::vector<Frame> frames_;
  std::vector<BackboneSample> samples_;
  std::vector<double> end_tensions_;  ///< Friction: each tendon's tension at its end.
};

class SingleShooting final : public detail::ModelProblem {
 public:
  explicit SingleShooting(VcWorkspace::Impl& W) : W_(W), system_(W) {}
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
  void cold_guess(Eigen::VectorXd& x) override { x = guess(W_.model->options().initial_guess); }
  bool alternative_guess(Eigen::VectorXd& x) override {
    // The equilibrium guess overestimates the lever of tip forces on strongly bent robots,
    // zeros ignore the tendons.
    x = guess(W_.model->options().initial_guess == VcInitialGuess::Equilibrium ? VcInitialGuess::Zero
                                                                               : VcInitialGuess::Equilibrium);
    return true;
  }
  // The unloaded robot is straight: n = m = 0 exactly.
  void rest_state(Eigen::VectorXd& x) override { x = Eigen::VectorXd::Zero(6); }
  bool warm_guess(const Solution& previous, Eigen::VectorXd& x) override {
    Vec6 r;
    if (warm_reaction(previous, r)) {
      x = r;
      return true;
    }
    if (previous.unknowns.size() == 6 && previous.unknowns.allFinite()) {
      x = previous.unknowns;
      return true;
    }
    return false;
  }
  bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) override {
    vc::set_driven_tensions(W_, index, T);
    return true;
  }
  // Every shot records the tendon lengths at the segment ends (memoised: after Newton's residual
  // at x this shoots nothing).
  bool tendon_pulls(const Eigen::VectorXd& x, Eigen::VectorXd& d) override {
    Vec6 f;
    if (!system_.residual(x, f)) return false;
    tendon_displacements(W_, W_.segment_lengths, pulls_);
    d = Eigen::Map<const Eigen::VectorXd>(pulls_.data(), static_cast<Eigen::Index>(pulls_.size()));
    return d.allFinite();
  }
  // The final pass records frames, samples and tendon lengths, and its end wrench is the residual
  // (usually the memoised last shot of Newton).
  bool final_residual(const Eigen::VectorXd& x, Eigen::Ref<Eigen::VectorXd> f) override {
    return system_.residual(x, f);
  }
  void extract(const Eigen::VectorXd&, bool evaluated, Solution& sol) override {
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
    tendon_displacements(W_, W_.segment_lengths, sol.tendon_displacements);
    if (W_.friction) sol.tendon_end_tensions = system_.end_tensions();
  }
  // The conjugate-point test on its coarse mesh (solve/stability_mesh.hpp) still adds about 75 %
  // to the median loaded solve of bench_loaded (its 6 perturbed shots per disk interval): over the
  // automatic rule's budget, so direct answers under loads are not tested without asking.
  bool automatic_stability_under_loads() const override { return false; }
  Stability stability(const Eigen::VectorXd& x, double load_factor) override {
    if (W_.friction)
      return Stability{StabilityStatus::Undetermined, NAN,
                       "tendon friction: the conjugate-point test assumes tensions independent of the shape"};
    return conjugate_point_test(W_, Vec6(x), load_factor);
  }
  bool infeasibility(const Eigen::VectorXd&, double threshold, std::string& why) override {
    return tendon_limit(W_, threshold, why);
  }
  // Single shooting cannot damp a snap; multiple shooting damps the inner disks' poses. Its node
  // 0 holds the base wrench, this formulation's unknowns. Not with friction (single shooting only).
  detail::ModelProblem* damping_formulation() override {
    if (W_.friction) return nullptr;
    if (!W_.multiple) W_.multiple = make_multiple_shooting(W_);
    return W_.multiple.get();
  }
  void from_damping_formulation(const Eigen::VectorXd& y, Eigen::VectorXd& x) override { x = y.segment<6>(12); }
  std::string integrator_name() const override { return W_.shot_integrator->name(); }

 private:
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
};

}  // namespace

std::unique_ptr<detail::ModelProblem> make_single_shooting(VcWorkspace::Impl& W) {
  return std::make_unique<SingleShooting>(W);
}

}  // namespace tdcr::vc
