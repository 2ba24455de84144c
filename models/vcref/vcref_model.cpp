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
#include "vcref/vcref_shooting.hpp"
#include "vcref/vcref_stability.hpp"

namespace tdcr {

namespace {

// The shooting system with the load factor as its parameter; accepted steps rebase the charts.
class VcrefSystem final : public bvp::ParameterizedSystem {
 public:
  VcrefSystem(VcrefShooting& problem, bvp::ShootingSystem& shooting) : problem_(problem), shooting_(shooting) {}
  int size() const override { return shooting_.size(); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    return shooting_.residual(x, f) && f.allFinite();
  }
  const bvp::SparsityPattern* sparsity() const override { return shooting_.sparsity(); }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                       double* values) override {
    return shooting_.sparse_jacobian(x, f, values);
  }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override { shooting_.residual_scale(s); }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { shooting_.unknown_scale(s); }
  void set_parameter(double lambda) override {
    problem_.set_load_factor(lambda);
    shooting_.invalidate();
  }
  void accept_step(Eigen::VectorXd& x) override { shooting_.rebase(x); }
  // Along a loading path a disk can turn by more than pi from its reference (the rest state's):
  // its rotation vector w then nears |w| = 2 pi, where the chart degenerates and the path's
  // steps are spent on w (VCref s1011 of the loaded-scene suite, docs/hard-cases.md). Re-centred
  // once some |w| exceeds kRecenterAngle.
  bool recenter(Eigen::Ref<Eigen::VectorXd> x) override {
    constexpr double kRecenterAngle = 1.0;  // rad
    const int nodes = (static_cast<int>(x.size()) - 6) / 12;
    bool far = false;
    for (int k = 1; k <= nodes && !far; ++k) far = x.segment<3>(6 + 12 * (k - 1) + 3).norm() > kRecenterAngle;
    if (far) shooting_.rebase(x);
    return far;
  }
  bool set_damping(const Eigen::Ref<const Eigen::VectorXd>& x, double rate) override {
    problem_.set_damping(x.data(), rate);
    shooting_.invalidate();
    return true;
  }

 private:
  VcrefShooting& problem_;
  bvp::ShootingSystem& shooting_;
};

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
class VcrefWorkspace final : public ModelWorkspace, public detail::ModelProblem {
 public:
  VcrefWorkspace(const VcrefModel& owner, const VcrefModel::Data& d)
      : ModelWorkspace(owner),
        d_(d),
        problem_(d),
        integrator_(bvp::make_integrator(detail::integrator_options(integrator_options_))),
        shooting_(problem_, *integrator_, d.structure),
        system_(problem_, shooting_) {}

  void bind(const ModelInput& input, const SolverOptions& options, const VcrefOptions& vo) {
    if (!same_integrator(options, integrator_options_)) {
      integrator_ = bvp::make_integrator(detail::integrator_options(options));
      integrator_options_ = options;
      shooting_.set_integrator(*integrator_);
    }
    detail::update_stability_integrator(options, stability_integrator_);
    problem_.bind(input, options);
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
  void cold_guess(Eigen::VectorXd& x) override { shape_guess(x, d_.arc_guess); }
  // The other shape: under antagonistic tensions with a tip force the arcs can start Newton in a
  // basin it does not leave (tests/data/antagonistic_tip_force.json), the straight robot not.
  bool alternative_guess(Eigen::VectorXd& x) override {
    shape_guess(x, !d_.arc_guess);
    return true;
  }
  void rest_state(Eigen::VectorXd& x) override { shape_guess(x, false); }
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
    if (!shooting_.evaluate(x)) return Stability{StabilityStatus::Undetermined, NAN, "the shots at the answer failed"};
    // The rods' transfer matrices on the stability test's coarse RK4 mesh (the solve's CVODE).
    return disk_pose_stability(problem_, stability_integrator_ ? *stability_integrator_ : *integrator_,
                               shooting_.nodes());
  }

  // The previous unknowns, its disk rotations as the chart references (w = 0).
  bool warm_guess(const Solution& prev, Eigen::VectorXd& x) override {
    const int N = d_.N;
    if (prev.unknowns.size() != d_.size || static_cast<int>(prev.disk_frames.size()) != N + 1 ||
        !prev.unknowns.allFinite())
      return false;
    x = prev.unknowns;
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
    sol.backbone.resize(N + 1);
    sol.backbone[0] = BackboneSample{0.0, Frame{}, x.segment<3>(0), x.segment<3>(3)};
    for (int j = 1; j <= N; ++j) {
      const double* e = nodes.end(j - 1);
      sol.backbone[j] = BackboneSample{routing.disk_s[j], sol.disk_frames[j], cosserat::force(e), cosserat::moment(e)};
    }
  }

 private:
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
  Eigen::VectorXd x, scale(sys.size());
  if (!(at && ws.warm_guess(*at, x))) ws.cold_guess(x);
  sys.unknown_scale(scale);
  for (int i = 0; i < x.size(); ++i) x[i] += perturbation * std::sin(1.0 + i) / scale[i];
  return bvp::check_jacobian(sys, x);
}


}  // namespace tdcr
