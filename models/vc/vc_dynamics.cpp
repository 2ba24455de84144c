// VC's Cosserat rod dynamics (vc_dynamics.hpp): the time stepping, the history update of each
// scheme, and Newton on the step's shooting residual.
//
// Time schemes (Till, Aloi and Rucker 2019, Eq. 5-7): every time derivative of v, u, q, w (and of
// v_s, u_s, for the damping) is y_t = c0 y + y_h, y_h from the history at the same point:
// - BDF-alpha, step h: c0 = (1.5 + a) / (h (1 + a)), y_h = c1 y(i-1) + c2 y(i-2) + d1 y_t(i-1),
//   c1 = -2 / h, c2 = (0.5 + a) / (h (1 + a)), d1 = a / (1 + a); a = 0 is BDF2. The start is
//   consistent: at rest, y(-1) = y(0) and y_t(0) = 0 (then c0 + c1 + c2 = 0 makes y_t = 0 a
//   solution of a constant input).
// - Implicit midpoint: the step's BVP is solved for the fields at t + h/2 with
//   y_t = (2 / h) (y_mid - y(i)), i.e. c0 = 2 / h, y_h = -c0 y(i); then y(i+1) = 2 y_mid - y(i).
#include "vc/vc_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>

#include "solve/displacement_input.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_dynamics_mesh.hpp"

namespace tdcr {

namespace vc {

void CosseratDynamicsOptions::validate() const {
  if (rk4_steps < 1) throw InputError("rk4_steps", std::to_string(rk4_steps), "must be >= 1");
  if (!(rk4_max_step > 0.0)) throw InputError("rk4_max_step", format_value(rk4_max_step), "must be > 0");
  if (!(function_tolerance > 0.0) || !std::isfinite(function_tolerance))
    throw InputError("function_tolerance", format_value(function_tolerance), "must be a number > 0");
  if (max_iterations < 1) throw InputError("max_iterations", std::to_string(max_iterations), "must be >= 1");
  if (!(automatic_threshold > 0.0))
    throw InputError("automatic_threshold", format_value(automatic_threshold), "must be > 0");
}

void check_settings(const DynamicsSettings& settings, double dt) {
  settings.validate();
  if (!(dt > 0.0) || !std::isfinite(dt)) throw InputError("dt", format_value(dt), "must be a finite number > 0");
}

namespace {

using dyn::Values;

/// CosseratDynamicsOptions::Shooting for VC.
bool shoots_multiply(const VcModel& model, const DynamicsSettings& settings, double dt,
                     const CosseratDynamicsOptions& o) {
  if (o.shooting != CosseratDynamicsOptions::Shooting::Automatic)
    return o.shooting == CosseratDynamicsOptions::Shooting::Multiple;
  const Robot& robot = model.robot();
  const double a = settings.alpha;
  const double c0 = settings.scheme == TimeScheme::ImplicitMidpoint ? 2.0 / dt : (1.5 + a) / (dt * (1.0 + a));
  const double exponent =
      robot.total_length() *
      std::pow(robot.backbone.linear_mass() * c0 * c0 / robot.backbone.effective_stiffness().EI, 0.25);
  return exponent > o.automatic_threshold;
}
using dyn::ValuesList;

/// Two inputs the same (skip a re-bind).
bool same_input(const ModelInput& a, const ModelInput& b) {
  return a.actuation.kind == b.actuation.kind && a.actuation.values == b.actuation.values &&
         a.actuation.kinds == b.actuation.kinds && a.loads.tip_force == b.loads.tip_force &&
         a.loads.tip_moment == b.loads.tip_moment && a.loads.gravity == b.loads.gravity;
}

/// The step's shooting residual as KINSOL sees it: n(0), m(0) -> tip wrench residual.
class StepSystem final : public bvp::ResidualSystem {
 public:
  StepSystem(VcWorkspace::Impl& W, const dyn::ShotData& d) : W_(W), d_(d) {}
  int size() const override { return 6; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    ++shots;
    last_x = x;
    last_ok = dyn::shoot(W_, d_, last_x, res_);
    if (!last_ok) return false;
    f = res_;
    return true;
  }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    s.head<3>().setConstant(1.0 / force_scale);
    s.tail<3>().setConstant(1.0 / moment_scale);
  }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { residual_scale(s); }
  long shots = 0;
  // The statics' scales of the input's loads, or the largest base wrench met so far if larger:
  // a robot swinging after its load is removed has wrenches far above the (then tiny) load
  // scales, and a tolerance relative to those would ask for digits below rounding.
  double force_scale = 1.0, moment_scale = 1.0;
  dyn::Vec6 last_x = dyn::Vec6::Constant(NAN);  ///< The last shot's unknowns (its values are in d_.values).
  bool last_ok = false;

 private:
  VcWorkspace::Impl& W_;
  const dyn::ShotData& d_;
  dyn::Vec6 res_;
};

/// A time step as the model problem that displacement input borders (detail::DisplacementProblem,
/// the statics' own): its residual system is the step's shooting (single or multiple), its
/// tendon pulls those of the step's shape, its driven tensions set on the workspace's loads as
/// the statics set them. Only what the bordered Newton solve and complementarity read.
class StepProblem final : public ModelProblem, public bvp::ParameterizedSystem {
 public:
  /// `pulls(d)`: every tendon's pull of the last residual's shape into d.
  StepProblem(VcWorkspace::Impl& W, bvp::ResidualSystem& system, std::function<void(Eigen::VectorXd&)> pulls)
      : W_(W), sys_(system), pulls_(std::move(pulls)) {}
  /// The unknowns the guesses return (the step's current ones).
  Eigen::VectorXd current;

  // --- bvp::ParameterizedSystem: the step's shooting at fixed input ---
  int size() const override { return sys_.size(); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    last_x_ = x;
    last_version_ = version_;
    last_ok_ = sys_.residual(x, f);
    return last_ok_;
  }
  const bvp::SparsityPattern* sparsity() const override { return sys_.sparsity(); }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override { sys_.residual_scale(s); }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { sys_.unknown_scale(s); }
  void set_parameter(double) override {}

  // --- ModelProblem ---
  bvp::ParameterizedSystem* system() override { return this; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void cold_guess(Eigen::VectorXd& x) override { x = current; }
  void rest_state(Eigen::VectorXd& x) override { x = current; }
  bool warm_guess(const Solution&, Eigen::VectorXd& x) override {
    x = current;
    return true;
  }
  void extract(const Eigen::VectorXd&, bool, Solution&) override {}
  bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) override {
    vc::set_driven_tensions(W_, index, T);
    ++version_;
    return true;
  }
  bool tendon_pulls(const Eigen::VectorXd& x, Eigen::VectorXd& d) override {
    if (!(last_ok_ && last_version_ == version_ && last_x_.size() == x.size() && last_x_ == x)) {
      scratch_.resize(x.size());
      if (!residual(x, scratch_)) return false;
    }
    pulls_(d);
    return d.allFinite();
  }

 private:
  VcWorkspace::Impl& W_;
  bvp::ResidualSystem& sys_;
  std::function<void(Eigen::VectorXd&)> pulls_;
  bvp::NewtonSolver newton_;
  Eigen::VectorXd last_x_, scratch_;
  bool last_ok_ = false;
  unsigned long version_ = 0, last_version_ = ~0ul;
};

class VcDynamics final : public CosseratDynamics {
 public:
  /// `model` the VC rod of `original` (VC itself, or VCref's robot and effects as a VcModel, then
  /// owned: `owned`); `chords`: VCref's tendons.
  VcDynamics(const StaticModel& original, const VcModel& model, std::unique_ptr<VcModel> owned,
             const DynamicsSettings& settings, double dt, const CosseratDynamicsOptions& o, bool chords)
      : original_(original),
        owned_(std::move(owned)),
        model_(model),
        settings_(settings),
        options_(o),
        chords_(chords),
        multiple_(chords || shoots_multiply(model, settings, dt, o)),
        workspace_(model.make_workspace()),
        W_(static_cast<VcWorkspace&>(*workspace_).impl()),
        system_(W_, shot_) {
    check_settings(settings, dt);
    options_.validate();
    const Robot& robot = model.robot();
    if (!(robot.backbone.linear_mass() > 0.0))
      throw InputError("robot.backbone.density", format_value(robot.backbone.density),
                       "dynamics needs the backbone's mass: give a density > 0 (or mass_per_length)");
    if (model.effects().tendon_friction.on())
      throw InputError("effects.tendon_friction", "on", "the Cosserat dynamics have no tendon friction");
    shot_ = dyn::ShotData{&mesh_, &X_, &history_, &values_, !chords};
  }

  void initialize(const Solution& at_rest, const ModelInput& input) override {
    if (!at_rest.converged())
      throw InputError("at_rest", to_string(at_rest.summary.termination),
                       "the start must be a converged static answer");
    // Displacement input: the driven tendons' tensions join each step's unknowns.
    driven_index_.clear();
    for (std::size_t k = 0; k < input.actuation.values.size(); ++k)
      if (input.actuation.kind_of(k) == Actuation::Kind::Displacements) driven_index_.push_back(static_cast<int>(k));
    driven_ = static_cast<int>(driven_index_.size());
    displacement_.reset();
    step_problem_.reset();
    bound_ = false;
    if (driven_ > 0) placeholders_ = detail::DisplacementProblem::placeholders(original_, input);
    bind(input);
    mesh_.build(W_, options_.rk4_steps, options_.rk4_max_step);
    const Values zero = Values::Zero();
    history_.assign(mesh_.points, zero);
    values_.assign(mesh_.points, zero);
    set_c0(0.0);  // the statics on this mesh: no history, no inertia
    dyn::Vec6 x = dyn::Vec6::Zero();
    if (at_rest.unknowns.size() == 6)
      x = at_rest.unknowns;
    else if (!at_rest.backbone.empty())
      x << at_rest.backbone.front().n, at_rest.backbone.front().m;
    x_ = x;
    peak_force_ = peak_moment_ = 0.0;
    if (driven_ > 0) {
      // The start's driven tensions, so that the static start of multiple shooting is its shape.
      Eigen::VectorXd T(driven_);
      for (int i = 0; i < driven_; ++i) {
        const auto k = static_cast<std::size_t>(driven_index_[i]);
        T[i] = k < at_rest.tensions.size() ? at_rest.tensions[k] : 0.0;
      }
      vc::set_driven_tensions(W_, driven_index_, T);
    }
    if (multiple_) start_multiple(at_rest);
    if (driven_ > 0) start_displacement(at_rest, input);
    bvp::NewtonResult r = solve(false);
    if (!r.converged())
      throw std::runtime_error("Cosserat dynamics: the static start on the dynamics' mesh did not converge: " +
                               r.message);
    y1_ = values_;
    y2_ = values_;
    yt1_.assign(mesh_.points, zero);
    t_ = 0.0;
    steps_ = 0;
    publish(y1_);
  }

  SimulationStep advance(double t_next, const Timeline& timeline) override {
    const bool midpoint = settings_.scheme == TimeScheme::ImplicitMidpoint;
    return advance_with_input(t_next, timeline.at(midpoint ? 0.5 * (t_ + t_next) : t_next));
  }

  SimulationStep advance_with_input(double t_next, const ModelInput& input) override {
    if (y1_.empty()) throw std::logic_error("VC dynamics: advance before initialize");
    const double h = t_next - t_;
    if (!(h > 0.0) || !std::isfinite(h))
      throw InputError("t_next", format_value(t_next), "must be after the current time " + format_value(t_));
    bind(input);
    const bool midpoint = settings_.scheme == TimeScheme::ImplicitMidpoint;
    if (midpoint) {
      const double c0 = 2.0 / h;
      set_c0(c0);
      for (int i = 0; i < mesh_.points; ++i) history_[i] = -c0 * y1_[i];
    } else {
      const double a = settings_.alpha;
      const double c0 = (1.5 + a) / (h * (1.0 + a));
      const double c1 = -2.0 / h, c2 = (0.5 + a) / (h * (1.0 + a)), d1 = a / (1.0 + a);
      set_c0(c0);
      for (int i = 0; i < mesh_.points; ++i) history_[i] = c1 * y1_[i] + c2 * y2_[i] + d1 * yt1_[i];
    }
    const dyn::Vec6 x_start = x_;
    // Predictor: the unknowns extrapolated linearly from the last two steps. A single shot
    // amplifies an error of the guess by up to exp(L (rho A c0^2 / EI)^(1/4)), so a guess of
    // second order keeps the short steps' Newton in its linear range.
    if (steps_ > 1) x_ = 2.0 * x_ - x_previous_;
    const Eigen::VectorXd xm_start = xm_;
    if (multiple_ && steps_ > 1) xm_ = 2.0 * xm_ - xm_previous_;
    tau_start_ = tau_;
    if (driven_ > 0 && steps_ > 1) tau_ = 2.0 * tau_ - tau_previous_;
    const bvp::NewtonResult r = solve(steps_ > 0);
    SimulationStep step;
    step.t = t_next;
    step.status = r.termination;
    step.iterations = r.iterations;
    if (!r.converged()) {
      x_ = x_start;  // the state stays at t_, so that a caller may retry with another step
      xm_ = xm_start;
      tau_ = tau_start_;
      step.tip = frames_.back();  // the last converged shape's
      step.tensions = tensions_;
      step.tendon_displacements = pulls_report_;
      return step;
    }
    for (int i = 0; i < mesh_.points; ++i) {
      if (midpoint) {
        const Values end = 2.0 * values_[i] - y1_[i];
        yt1_[i] = (end - y1_[i]) / h;
        y2_[i] = y1_[i];
        y1_[i] = end;
      } else {
        yt1_[i] = X_.c0 * values_[i] + history_[i];
        y2_[i] = y1_[i];
        y1_[i] = values_[i];
      }
    }
    x_previous_ = x_start;
    xm_previous_ = xm_start;
    tau_previous_ = tau_start_;
    t_ = t_next;
    ++steps_;
    publish(y1_);
    step.tip = frames_.back();
    step.kinetic_energy = kinetic_;
    step.potential_energy = potential_;
    step.tensions = tensions_;
    step.tendon_displacements = pulls_report_;
    return step;
  }

  Solution shape() const override {
    Solution s;
    s.model = to_string(original_.kind());
    s.model_fingerprint = original_.fingerprint();
    s.summary.termination = TerminationType::Converged;
    s.disk_frames = frames_;
    s.backbone = samples_;
    s.tensions = tensions_;
    s.tendon_displacements = pulls_report_;
    s.tendon_slack = slack_;
    s.unknowns = x_;
    return s;
  }
  double potential_energy() override { return potential_; }
  bool takes_displacement_input() const override { return true; }
  double time() const override { return t_; }
  long shots() const override { return system_.shots + (multiple_system_ ? multiple_system_->shots : 0); }
  int mesh_points() const override { return mesh_.points; }
  const std::string& last_message() const override { return message_; }

 private:
  void bind(const ModelInput& input) {
    input.validate(model_.robot());
    const bool displaced = input.actuation.kind != Actuation::Kind::Tensions || input.actuation.mixed();
    if (displaced != (driven_ > 0))
      throw InputError("actuation.kind", displaced ? "displacements" : "tensions",
                       "the simulation started with the other kind of input: tendons given by displacement stay so");
    if (bound_ && same_input(input, input_)) return;
    const ModelInput* bound = &input;
    if (driven_ > 0) {
      // The tension form (the statics' rule): the driven tendons bound at their tension scales,
      // their tensions set per evaluation by the displacement problem.
      tension_form_.actuation.kind = Actuation::Kind::Tensions;
      tension_form_.actuation.convention = input.actuation.convention;
      tension_form_.actuation.kinds.clear();
      tension_form_.actuation.values.assign(input.actuation.values.begin(), input.actuation.values.end());
      for (const int k : driven_index_) tension_form_.actuation.values[static_cast<std::size_t>(k)] = placeholders_[k];
      tension_form_.loads = input.loads;
      bound = &tension_form_;
    }
    if (!(bound_ && same_input(*bound, bound_input_))) {
      SolverOptions o;
      o.integrator = IntegratorKind::FixedStepRK4;  // the workspace's own integrators stay unused
      bind_input(W_, model_, *bound, o);
      bound_input_ = *bound;
      set_c0(X_.c0);  // the section's weight follows the input
    }
    input_ = input;
    bound_ = true;
    if (displacement_) displacement_->set_commanded(input);
  }

  // Displacement input: the statics' DisplacementProblem on the step's shooting, its tendons taut
  // or slack as the start's.
  void start_displacement(const Solution& at_rest, const ModelInput& input) {
    if (chords_) {
      // VCref's pulls: each tendon's chords from its first disk (the base, or with the
      // per-segment convention its segment's start) and their length on the straight robot,
      // read off chord_displacements (pull + chords' length) once.
      const TendonRouting& rt = model_.routing();
      const std::vector<double> p = tendon::chord_displacements(at_rest.disk_frames, rt, input.actuation.convention);
      chord_first_.assign(rt.tendons.size(), 0);
      chord_rest_.assign(rt.tendons.size(), 0.0);
      for (std::size_t k = 0; k < rt.tendons.size(); ++k) {
        const RoutedTendon& t = rt.tendons[k];
        if (input.actuation.convention == Actuation::DisplacementConvention::PerSegment && t.segment > 0)
          chord_first_[k] = rt.segment_end_disk[static_cast<std::size_t>(t.segment - 1)];
        chord_rest_[k] =
            p[k] + tendon::chord_length(at_rest.disk_frames.data(), rt, static_cast<int>(k), chord_first_[k]);
      }
    }
    bvp::ResidualSystem& sys = multiple_ ? static_cast<bvp::ResidualSystem&>(*multiple_system_) : system_;
    step_problem_ = std::make_unique<StepProblem>(W_, sys, [this](Eigen::VectorXd& d) { step_pulls(d); });
    step_problem_->current = multiple_ ? xm_ : Eigen::VectorXd(x_);
    displacement_ = std::make_unique<detail::DisplacementProblem>();
    SolverOptions so;
    so.function_tolerance = options_.function_tolerance;
    displacement_->bind(original_, *step_problem_, input, so, &at_rest);
    Eigen::VectorXd y;
    if (!displacement_->warm_guess(at_rest, y))
      throw InputError("at_rest", "", "the start has no tensions of the displacement-driven tendons");
    tau_ = y.tail(driven_);
    tau_previous_ = tau_;
  }

  // Every tendon's pull of the last residual's shape (the displacement problem's rows).
  void step_pulls(Eigen::VectorXd& d) {
    if (chords_) {  // pull = the straight chords' length minus the chords' (allocation-free)
      const TendonRouting& rt = model_.routing();
      d.resize(static_cast<Eigen::Index>(rt.tendons.size()));
      for (std::size_t k = 0; k < rt.tendons.size(); ++k)
        d[static_cast<Eigen::Index>(k)] = chord_rest_[k] - tendon::chord_length(multiple_system_->frames().data(), rt,
                                                                                static_cast<int>(k), chord_first_[k]);
      return;
    }
    dyn::path_pulls(W_, mesh_, values_, lengths_, pulls_);
    d = Eigen::Map<const Eigen::VectorXd>(pulls_.data(), static_cast<Eigen::Index>(pulls_.size()));
  }

  // Newton on the step with the driven tensions as unknowns (the displacement problem's bordered
  // system), then complementarity: a tendon that would push goes slack, a slack one pulled past
  // its path goes taut, and the step is solved again (at most kMaxSlackChanges times). The
  // re-solves are exact Newton with full steps: KINSOL's line search stalled on the bordered
  // multiple-shooting system (paper robot, tendon 1 pulled 2 mm within 10 ms from slack, VCref:
  // 50 iterations at a scaled residual of 0.13; full steps: 4 iterations).
  bvp::NewtonResult bordered_solve(bvp::NewtonOptions o, int& iterations) {
    constexpr int kMaxSlackChanges = 8;
    detail::DisplacementProblem& D = *displacement_;
    bvp::NewtonResult r = D.newton().solve(D, y_, o);
    iterations += r.iterations;
    o.reuse_jacobian = false;  // other equations: exact Newton from the last answer
    o.max_setup_calls = 1;
    o.line_search = false;
    int changes = 0;
    while (r.converged() && D.update_slack(y_)) {
      if (++changes > kMaxSlackChanges) {
        r.termination = TerminationType::NoConvergence;
        r.message += "; slack and taut tendons changed more than " + std::to_string(kMaxSlackChanges) + " times";
        break;
      }
      y_flip_ = y_;
      r = D.newton().solve(D, y_, o);
      iterations += r.iterations;
      if (!r.converged()) {  // full steps failed: with the line search from the same start
        y_ = y_flip_;
        o.line_search = true;
        r = D.newton().solve(D, y_, o);
        iterations += r.iterations;
        o.line_search = false;
      }
    }
    return r;
  }

  // The step with displacement input: bordered_solve from the predicted unknowns; where that
  // fails, from the step's start by exact Newton with full steps; where that fails too and a taut
  // tendon is commanded below the last state's pull (released faster than the robot follows:
  // its taut equations ask for a pushing tendon), from the start with those tendons slack.
  bvp::NewtonResult solve_driven(bool reuse) {
    detail::DisplacementProblem& D = *displacement_;
    const int n = multiple_ ? static_cast<int>(xm_.size()) : 6;
    y_.resize(n + driven_);
    if (multiple_)
      y_.head(n) = xm_;
    else
      y_.head(n) = x_;
    y_.tail(driven_) = tau_;
    y_start_ = y_;
    int iterations = 0;
    bvp::NewtonResult r = bordered_solve(newton_options(reuse), iterations);
    bvp::NewtonOptions exact = newton_options(false);
    exact.max_setup_calls = 1;
    exact.line_search = false;
    if (!r.converged()) {
      y_ = y_start_;
      r = bordered_solve(exact, iterations);
    }
    if (!r.converged()) {
      y_ = y_start_;
      bool released = false;
      for (int i = 0; i < driven_; ++i) {
        const auto k = static_cast<std::size_t>(driven_index_[i]);
        if (D.taut()[static_cast<std::size_t>(i)] && k < pulls_report_.size() &&
            input_.actuation.values[k] < pulls_report_[k]) {
          y_[n + i] = -1.0;  // marks it for update_slack
          released = true;
        }
      }
      if (released) {
        D.update_slack(y_);
        for (int i = 0; i < driven_; ++i) y_[n + i] = std::max(0.0, y_[n + i]);
        r = bordered_solve(exact, iterations);
      }
    }
    r.iterations = iterations;
    message_ = r.message;
    if (!r.converged()) return r;
    // The state of the answer (values_, the workspace's tensions): one evaluation at it.
    fy_.resize(y_.size());
    if (!D.residual(y_, fy_)) {
      r.termination = TerminationType::IntegrationFailed;
      r.message += "; the shot at the solution failed";
      return r;
    }
    tau_ = y_.tail(driven_);
    if (multiple_) {
      Eigen::VectorXd x = y_.head(n);
      multiple_system_->rebase(x);
      xm_ = x;
      x_ = x.head<6>();
    } else {
      x_ = y_.head<6>();
    }
    return r;
  }

  // The step's section: K + c0 B inverted once per step length.
  void set_c0(double c0) {
    const Robot& robot = model_.robot();
    X_.S = W_.section;
    X_.c0 = c0;
    X_.bse = settings_.shear_damping_time * X_.S.kse;
    X_.bbt = settings_.bending_damping_time * X_.S.kbt;
    X_.Seff = X_.S;
    X_.Seff.kse = X_.S.kse + c0 * X_.bse;
    X_.Seff.kbt = X_.S.kbt + c0 * X_.bbt;
    X_.Seff.inv_kse = X_.Seff.kse.cwiseInverse();
    X_.Seff.inv_kbt = X_.Seff.kbt.cwiseInverse();
    const Backbone& b = robot.backbone;
    const double ro2 = b.outer_radius * b.outer_radius, ri2 = b.inner_radius * b.inner_radius;
    const double area = M_PI * (ro2 - ri2), I = 0.25 * M_PI * (ro2 * ro2 - ri2 * ri2);
    X_.rho_a = b.linear_mass();
    const double rho = X_.rho_a / area;
    X_.rho_j = Vec3(rho * I, rho * I, 2.0 * rho * I);
    X_.drag = settings_.air_drag;
  }

  // The unknowns of multiple shooting from the static answer `at_rest`: VC's from a shot of the
  // single-shooting start; VCref's from its disk poses and wrenches (n(s_j-), m(s_j-) there,
  // made distal by the chords' disk wrench; Newton corrects the rest on this mesh).
  void start_multiple(const Solution& at_rest) {
    const TendonRouting& rt = model_.routing();
    const int N = rt.disk_count() - 1;
    const double L = model_.robot().total_length();
    const double rate = std::sqrt(X_.S.kbt.x() / (X_.rho_a * std::pow(L, 4)));  // first-mode scale
    multiple_system_ = std::make_unique<dyn::MultipleShooting>(
        W_, shot_, chords_, model_.effects().disk_normal_force == DiskNormalForce::Removed, L * rate, rate);
    dyn::StateList nodes(std::max(N - 1, 0), dyn::State::Zero());
    if (!chords_) {
      const bvp::NewtonResult r = solve_single(false);
      if (!r.converged())
        throw std::runtime_error("Cosserat dynamics: the static start did not converge: " + r.message);
      shot_.nodes = &nodes;
      dyn::Vec6 f;
      const bool ok = dyn::shoot(W_, shot_, x_, f);
      shot_.nodes = nullptr;
      if (!ok) throw std::runtime_error("Cosserat dynamics: the static start failed to integrate");
    } else {
      if (static_cast<int>(at_rest.disk_frames.size()) != N + 1 || static_cast<int>(at_rest.backbone.size()) != N + 1)
        throw InputError("at_rest", "", "needs the disk frames and backbone samples of a VCref answer");
      std::vector<double> T(W_.loads.full_tensions().size());
      for (std::size_t k = 0; k < T.size(); ++k) T[k] = W_.loads.tension(static_cast<int>(k));
      for (int j = 1; j < N; ++j) {
        const tendon::DiskWrench w =
            tendon::disk_wrench(j, at_rest.disk_frames.data(), rt, T.data(),
                                model_.effects().disk_normal_force == DiskNormalForce::Removed);
        dyn::State& y = nodes[j - 1];
        y.head<3>() = at_rest.disk_frames[j].p;
        Eigen::Map<Mat3>(y.data() + 3) = at_rest.disk_frames[j].R;
        y.segment<3>(12) = at_rest.backbone[j].n - w.force;
        y.segment<3>(15) = at_rest.backbone[j].m - w.moment;
      }
    }
    multiple_system_->from_nodes(x_, nodes, xm_);
  }

  // Newton on the step from x_ (single shooting) or xm_ (multiple); on success x_ (and xm_) are
  // the solution and values_ hold its fields.
  bvp::NewtonResult solve(bool reuse) {
    peak_force_ = std::max(peak_force_, x_.head<3>().norm());
    peak_moment_ = std::max(peak_moment_, x_.tail<3>().norm());
    const double fs = std::max(W_.loads.force_scale(), peak_force_);
    const double ms = std::max(W_.loads.moment_scale(), peak_moment_);
    system_.force_scale = fs;
    system_.moment_scale = ms;
    if (multiple_) multiple_system_->set_scales(fs, ms);
    if (displacement_) return solve_driven(reuse);
    if (!multiple_) return solve_single(reuse);
    dyn::MultipleShooting& sys = *multiple_system_;
    Eigen::VectorXd x = xm_;
    bvp::NewtonResult r = newton_.solve(sys, x, newton_options(reuse));
    message_ = r.message;
    if (!r.converged()) return r;
    if (!(sys.last_ok && sys.last_x == x)) {
      Eigen::VectorXd f(x.size());
      if (!sys.residual(x, f)) {
        r.termination = TerminationType::IntegrationFailed;
        r.message += "; the shot at the solution failed";
        return r;
      }
    }
    sys.rebase(x);
    xm_ = x;
    x_ = x.head<6>();
    return r;
  }

  bvp::NewtonOptions newton_options(bool reuse) const {
    bvp::NewtonOptions o;
    o.function_tolerance = options_.function_tolerance;
    o.max_iterations = options_.max_iterations;
    // No bound on the step (unlike the statics' cold solves): a warm start is close, and the
    // base wrench of a swinging robot changes by more than the load scales in one step.
    o.max_newton_step = 0.0;
    o.max_setup_calls = 10;  // modified Newton: the step's Jacobian changes little from step to step
    o.reuse_jacobian = reuse;
    return o;
  }

  bvp::NewtonResult solve_single(bool reuse) {
    Eigen::VectorXd x = x_;
    bvp::NewtonResult r = newton_.solve(system_, x, newton_options(reuse));
    message_ = r.message;
    if (!r.converged()) return r;
    const dyn::Vec6 xs = x;
    if (!(system_.last_ok && system_.last_x == xs)) {
      dyn::Vec6 f;
      if (!dyn::shoot(W_, shot_, xs, f)) {
        r.termination = TerminationType::IntegrationFailed;
        r.message += "; the shot at the solution failed";
        return r;
      }
    }
    x_ = xs;
    return r;
  }

  // Frames, disk samples and energies of the shape `values` (at the current time), with the time
  // derivatives yt1_ for the damping's share of the wrench.
  void publish(const ValuesList& values) {
    dyn::reconstruct(mesh_, values, frames_, point_positions_);
    const TendonRouting& rt = model_.routing();
    samples_.assign(frames_.size(), BackboneSample{});
    for (std::size_t j = 0; j < frames_.size(); ++j) {
      // The wrench just distal of disk j (the base: at the first point), as VC's statics record.
      const int point = j == 0 ? 0 : mesh_.post[j];
      const Values& y = values[point];
      const Values& yt = yt1_.empty() ? Values::Zero().eval() : yt1_[point];
      Vec3 nb = X_.bse.cwiseProduct(yt.segment<3>(dyn::kV));
      if (X_.S.shear_extension) nb += X_.S.kse.cwiseProduct(y.segment<3>(dyn::kV) - Vec3::UnitZ());
      const Vec3 mb = X_.S.kbt.cwiseProduct(y.segment<3>(dyn::kU)) + X_.bbt.cwiseProduct(yt.segment<3>(dyn::kU));
      samples_[j] = BackboneSample{rt.disk_s[j], frames_[j], frames_[j].R * nb, frames_[j].R * mb};
    }
    dyn::energies(W_, chords_, X_, mesh_, values, frames_, point_positions_, kinetic_, potential_);
    // The reported tensions (a slack tendon's exactly 0) and the pulls a motor sets (an elastic
    // tendon's stretch added, as the statics report them).
    const std::size_t K = W_.loads.full_tensions().size();
    tensions_.resize(K);
    slack_.assign(K, false);
    for (std::size_t k = 0; k < K; ++k) tensions_[k] = std::max(0.0, W_.loads.tension(static_cast<int>(k)));
    if (displacement_)
      for (int i = 0; i < driven_; ++i)
        slack_[static_cast<std::size_t>(driven_index_[i])] = !displacement_->taut()[static_cast<std::size_t>(i)];
    if (chords_)
      pulls_report_ = tendon::chord_displacements(frames_, model_.routing(), input_.actuation.convention);
    else
      dyn::path_pulls(W_, mesh_, values, lengths_, pulls_report_);
    tendon::add_elastic_stretch(model_.robot(), model_.routing(), tensions_, pulls_report_);
  }

  const StaticModel& original_;
  std::unique_ptr<VcModel> owned_;
  const VcModel& model_;
  DynamicsSettings settings_;
  CosseratDynamicsOptions options_;
  bool chords_, multiple_;
  std::unique_ptr<ModelWorkspace> workspace_;
  VcWorkspace::Impl& W_;
  ModelInput input_;        ///< The input of the step (displacements as given).
  ModelInput bound_input_;  ///< What the workspace is bound to (displacement input: its tension form).
  bool bound_ = false;
  // Displacement input: the driven tendons (global indices), their tension scales' placeholders,
  // the statics' bordered problem on the step, and the driven tensions (scaled) now, at the step's
  // start and a step before.
  int driven_ = 0;
  std::vector<int> driven_index_;
  std::vector<double> placeholders_;
  ModelInput tension_form_;
  std::unique_ptr<StepProblem> step_problem_;
  std::unique_ptr<detail::DisplacementProblem> displacement_;
  Eigen::VectorXd tau_, tau_start_, tau_previous_, y_, y_start_, y_flip_, fy_;
  std::vector<double> lengths_, pulls_;                   ///< path_pulls' scratch and result.
  std::vector<int> chord_first_;                           ///< VCref: each tendon's first disk of its pull.
  std::vector<double> chord_rest_;                         ///< VCref: its chords' length on the straight robot.
  std::vector<double> tensions_, pulls_report_;            ///< Reported with the published shape.
  std::vector<bool> slack_;
  dyn::Mesh mesh_;
  dyn::StepSection X_;
  ValuesList history_, values_;  ///< Per point: the step's history, the last shot's values.
  ValuesList y1_, y2_, yt1_;     ///< Per point: y(i), y(i-1), y_t(i).
  dyn::ShotData shot_;
  StepSystem system_;
  std::unique_ptr<dyn::MultipleShooting> multiple_system_;
  bvp::NewtonSolver newton_;
  Eigen::VectorXd xm_, xm_previous_;  ///< Multiple shooting's unknowns, now and a step before.
  dyn::Vec6 x_ = dyn::Vec6::Zero();
  dyn::Vec6 x_previous_ = dyn::Vec6::Zero();  ///< The unknowns of the step before.
  double t_ = 0.0;
  long steps_ = 0;
  std::vector<Frame> frames_;
  std::vector<BackboneSample> samples_;
  std::vector<Vec3> point_positions_;
  double kinetic_ = 0.0, potential_ = 0.0;
  double peak_force_ = 0.0, peak_moment_ = 0.0;  ///< Largest |n(0)|, |m(0)| so far.
  std::string message_;
};

}  // namespace

std::unique_ptr<CosseratDynamics> make_vc_dynamics(const VcModel& model, const DynamicsSettings& settings, double dt,
                                                   const CosseratDynamicsOptions& options) {
  return std::make_unique<VcDynamics>(model, model, nullptr, settings, dt, options, false);
}

std::unique_ptr<CosseratDynamics> make_vcref_dynamics(const StaticModel& model, const DynamicsSettings& settings,
                                                      double dt, const CosseratDynamicsOptions& options) {
  if (model.kind() != ModelKind::VCref) throw InputError("model", to_string(model.kind()), "is not VCref");
  // VCref's free rods between the disks are VC's rod without its distributed tendon loads: a
  // VcModel of the same robot and effects carries the section, loads and mesh.
  auto rod = std::make_unique<VcModel>(model.robot(), model.effects());
  const VcModel& ref = *rod;
  return std::make_unique<VcDynamics>(model, ref, std::move(rod), settings, dt, options, true);
}

}  // namespace vc

std::unique_ptr<DynamicsIntegrator> make_cosserat_dynamics_integrator(const StaticModel& model,
                                                                      const DynamicsSettings& settings, double dt) {
  if (const auto* vc = dynamic_cast<const VcModel*>(&model)) return vc::make_vc_dynamics(*vc, settings, dt);
  if (model.kind() == ModelKind::VCref) return vc::make_vcref_dynamics(model, settings, dt);
  throw InputError("model", to_string(model.kind()), "has no Cosserat dynamics (VC and VCref have)");
}

}  // namespace tdcr
