// The common base of CCsub and PRB (lumped_model.hpp): workspace, binding, guesses, outputs, the
// recursive formulation (the banded one is in lumped_banded.cpp).
#include "tdcr/models/lumped_model.hpp"

#include "common/lumped_problem.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace detail {

LumpedWorkspace::LumpedWorkspace(const StaticModel& owner, const LumpedBody& body)
    : ModelWorkspace(owner), problem(body.make_problem()) {}
LumpedWorkspace::~LumpedWorkspace() = default;

LumpedBody::LumpedBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, int per_subsegment,
                       LumpedFormulation formulation, int banded_from)
    : statics(robot, routing, effects),
      length(robot.total_length()),
      per_subsegment(per_subsegment),
      N(statics.subsegments()),
      formulation(formulation),
      banded_from(banded_from) {
  // Friction couples each disk's tendon forces to the shape of every disk proximal to it: no band.
  if (formulation == LumpedFormulation::Banded && statics.friction())
    throw InputError("effects.tendon_friction", "on",
                     "the banded formulation needs disk loads that depend on the neighbouring disks only; "
                     "use the recursive (or automatic) formulation with tendon friction");
  const BackboneStiffness k = robot.backbone.effective_stiffness();
  EI = k.EI;
  GJ = k.GJ;
}

LumpedBody::~LumpedBody() = default;

bool LumpedBody::banded() const { return formulation == LumpedFormulation::Banded; }

bool LumpedBody::reduced(int J) const {
  return formulation == LumpedFormulation::Automatic && J >= banded_from && !statics.friction();
}

void LumpedBody::compute_frames(const double* x, int J, Frame* frames, SubsegmentPose* poses, Vec3* centroids,
                                int from) const {
  if (from <= 1) {
    frames[0] = Frame{};
    from = 1;
  }
  SubsegmentPose tmp;
  for (int j = from; j <= N; ++j) {
    const double l = statics.length(j);
    const Frame& prev = frames[j - 1];
    Frame& f = frames[j];
    if (j > J) {
      f.R = prev.R;
      f.p = prev.p + l * prev.R.col(2);
      if (centroids) centroids[j] = prev.p + 0.5 * l * prev.R.col(2);
      continue;
    }
    SubsegmentPose& g = poses ? poses[j] : tmp;
    local(j, x + per_subsegment * (j - 1), g);
    f.R = prev.R * g.R;
    f.p = prev.p + prev.R * g.p;
    if (centroids) centroids[j] = prev.p + prev.R * g.c;
  }
}

std::vector<Frame> LumpedBody::disk_frames(const Eigen::VectorXd& x) const {
  if (x.size() != per_subsegment * N)
    throw InputError("unknowns", std::to_string(x.size()),
                     "expected " + std::to_string(per_subsegment) + " unknowns per subsegment");
  std::vector<Frame> f(N + 1);
  compute_frames(x.data(), N, f.data());
  return f;
}

LumpedProblem::LumpedProblem(const LumpedBody& body) : body_(body) {
  frames_.resize(body.N + 1);
  poses_.resize(body.N + 1);
  centroids_.assign(body.N + 1, Vec3::Zero());
  F_.assign(body.N + 1, Vec3::Zero());
  M_.assign(body.N + 1, Vec3::Zero());
  disk_f_.assign(body.N + 1, Vec3::Zero());
  disk_m_.assign(body.N + 1, Vec3::Zero());
}

void LumpedProblem::bind(const ModelInput& input) {
  body_.statics.bind(input, loads_);
  convention_ = input.actuation.convention;
  banded_ = body_.banded();
  reduced_ = body_.reduced(active());
  if ((banded_ || reduced_) && pattern_J_ != active()) build_pattern();
}

void LumpedProblem::adjust(bvp::NewtonOptions& options) const {
  options.linear_solver = banded_ ? LinearSolverKind::SparseKLU : LinearSolverKind::Dense;
}

void LumpedProblem::adjust_warm(bvp::NewtonOptions& options, bool same_input) const {
  // Iterations one Jacobian serves (modified Newton), and the iterations of the previous solve
  // above which its Jacobian is too stale to start from.
  constexpr int kReuseSetupCalls = 10;
  constexpr int kStaleAfterIterations = 3;
  options.reuse_jacobian = same_input || last_iterations_ <= kStaleAfterIterations;
  options.max_setup_calls = kReuseSetupCalls;
}

void LumpedProblem::x_scale(double* s) const {
  for (int i = 0; i < body_.per_subsegment; ++i) s[i] = 1.0;
}

void LumpedProblem::unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  if (banded_) {
    banded_scale(s.data());
    return;
  }
  for (int j = 0; j < active(); ++j) x_scale(s.data() + body_.per_subsegment * j);
}

void LumpedProblem::cold_guess(Eigen::VectorXd& y) {
  straight_x(x_, false);
  lift(x_, y);
}

void LumpedProblem::rest_state(Eigen::VectorXd& y) {
  straight_x(x_, true);
  lift(x_, y);
}

bool LumpedProblem::warm_guess(const Solution& previous, Eigen::VectorXd& y) {
  if (previous.unknowns.size() != body_.per_subsegment * body_.N || !previous.unknowns.allFinite()) return false;
  x_ = previous.unknowns.head(body_.per_subsegment * active());
  on_warm(x_);
  lift(x_, y);
  return true;
}

void LumpedProblem::evaluate(const double* x) {
  body_.compute_frames(x, active(), frames_.data(), poses_.data(), backbone_weight_on() ? centroids_.data() : nullptr);
  if (body_.statics.friction()) body_.statics.update_friction(loads_, frames_.data());
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), F_.data(), M_.data());
}

bool LumpedProblem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
  const bool ok = banded_ ? banded_residual(y.data(), f.data()) : recursive_residual(y.data(), f.data());
  return ok && f.allFinite();
}

bool LumpedProblem::recursive_residual(const double* x, double* f) {
  evaluate(x);
  constitutive_all(x, f);
  return true;
}

void LumpedProblem::evaluate_from(const double* x, int k) {
  body_.compute_frames(x, active(), frames_.data(), poses_.data(), backbone_weight_on() ? centroids_.data() : nullptr, k);
  body_.statics.disk_loads(loads_, frames_.data(), disk_f_.data(), disk_m_.data(), k - 1);
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), disk_f_.data(), disk_m_.data(), F_.data(),
                                M_.data());
}

bool LumpedProblem::jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                             Eigen::Ref<Eigen::MatrixXd> Jm) {
  const int m = body_.per_subsegment, n = size();
  jac_x_ = x;
  jac_f_.resize(n);
  jac_uscale_.resize(n);
  unknown_scale(jac_uscale_);
  const double noise = relative_noise();
  evaluate_from(x.data(), 1);
  for (int k = active(); k >= 1; --k)
    for (int i = 0; i < m; ++i) {
      const int c = m * (k - 1) + i;
      const double h = bvp::finite_difference_step(x[c], jac_uscale_[c], noise);
      jac_x_[c] = x[c] + h;
      evaluate_from(jac_x_.data(), k);
      constitutive_all(jac_x_.data(), jac_f_.data());
      jac_x_[c] = x[c];
      if (!jac_f_.allFinite()) return false;
      Jm.col(c) = (jac_f_ - f) / h;
    }
  return true;
}

void LumpedProblem::constitutive_all(const double* x, double* f) {
  const int m = body_.per_subsegment;
  const bool bb = backbone_weight_on();
  for (int j = 1; j <= active(); ++j) {
    const Mat3 Rt = frames_[j - 1].R.transpose();
    const Vec3 W = bb ? Vec3(Rt * backbone_weight(j)) : Vec3::Zero();
    constitutive(j, x + m * (j - 1), poses_[j], Rt * F_[j], Rt * M_[j], W, f + m * (j - 1));
  }
}

void LumpedProblem::extract(const Eigen::VectorXd& y, bool evaluated, Solution& solution) {
  (void)evaluated;
  last_iterations_ = solution.summary.iterations;
  gather_x(y, x_);
  Eigen::VectorXd full = Eigen::VectorXd::Zero(body_.per_subsegment * body_.N);
  full.head(x_.size()) = x_;
  solution.disk_frames.resize(body_.N + 1);
  body_.compute_frames(full.data(), active(), solution.disk_frames.data());
  solution.tendon_displacements = tendon::chord_displacements(solution.disk_frames, body_.statics.routing(), convention_);
  if (body_.statics.friction()) {
    const TendonRouting& routing = body_.statics.routing();
    body_.statics.update_friction(loads_, solution.disk_frames.data());
    solution.tendon_end_tensions = tendon::end_tensions(routing, loads_.chord.data(), static_cast<int>(routing.tendons.size()));
  }
  solution.unknowns = std::move(full);
}

}  // namespace detail

LumpedModel::LumpedModel(const Robot& robot, const Effects& effects, LumpedFormulation formulation,
                         BodyFactory make_body)
    : StaticModel(robot, effects), body_(make_body(this->robot(), routing(), this->effects(), formulation)) {}

LumpedModel::~LumpedModel() = default;

std::unique_ptr<ModelWorkspace> LumpedModel::make_workspace() const {
  return std::make_unique<detail::LumpedWorkspace>(*this, *body_);
}

int LumpedModel::unknowns_per_subsegment() const { return body_->per_subsegment; }

std::vector<Frame> LumpedModel::frames(const Eigen::VectorXd& x) const { return body_->disk_frames(x); }

detail::ModelProblem& LumpedModel::bind(ModelWorkspace& workspace, const ModelInput& input,
                                        const SolverOptions&) const {
  detail::LumpedProblem& problem = *static_cast<detail::LumpedWorkspace&>(workspace).problem;
  problem.bind(input);
  return problem;
}

}  // namespace tdcr
