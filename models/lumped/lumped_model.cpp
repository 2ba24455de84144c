// The common base of CCsub and PRB (lumped_model.hpp): workspace, binding, guesses, outputs, the
// recursive formulation (the banded one is in lumped_banded.cpp, the analytic Jacobian in
// lumped_jacobian.cpp).
#include "tdcr/models/lumped_model.hpp"

#include <cmath>

#include "lumped/lumped_problem.hpp"
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
  backbone_radius = robot.backbone.outer_radius;
  disk_radius.assign(N + 1, 0.0);
  for (int j = 0; j <= N; ++j) disk_radius[j] = robot.segments[routing.disk_segment[j]].disk_radius;
}

LumpedBody::~LumpedBody() = default;

bool LumpedBody::banded() const { return formulation == LumpedFormulation::Banded; }

bool LumpedBody::reduced(int J) const {
  return formulation == LumpedFormulation::Automatic && J >= banded_from && !statics.friction();
}

void LumpedBody::pose(int j, const double* xj, double stretch, SubsegmentPose& g) const {
  local(j, xj, g);
  if (stretch == 1.0) return;
  g.p *= stretch;
  g.c *= stretch;
  for (Vec3& a : g.aux) a *= stretch;
}

bool LumpedBody::pose_rates(int j, const double* xj, double stretch, SubsegmentPose& g, SubsegmentRates& d) const {
  if (!local_rates(j, xj, g, d)) return false;
  if (stretch == 1.0) return true;
  g.p *= stretch;
  g.c *= stretch;
  for (Vec3& a : g.aux) a *= stretch;
  for (int i = 0; i < per_subsegment; ++i) {
    d.dp[i] *= stretch;
    for (Vec3* mid : {d.dmid[0], d.dmid[1], d.dmid[2], d.dmid[3]}) mid[i] *= stretch;
  }
  return true;
}

void LumpedBody::compute_frames(const double* x, int J, const double* stretch, Frame* frames, SubsegmentPose* poses,
                                Vec3* centroids, int from) const {
  if (from <= 1) {
    frames[0] = Frame{};
    from = 1;
  }
  SubsegmentPose tmp;
  for (int j = from; j <= N; ++j) {
    const double l = stretch ? stretch[j] * statics.length(j) : statics.length(j);
    const Frame& prev = frames[j - 1];
    Frame& f = frames[j];
    if (j > J) {
      f.R = prev.R;
      f.p = prev.p + l * prev.R.col(2);
      if (centroids) centroids[j] = prev.p + 0.5 * l * prev.R.col(2);
      continue;
    }
    SubsegmentPose& g = poses ? poses[j] : tmp;
    pose(j, x + per_subsegment * (j - 1), stretch ? stretch[j] : 1.0, g);
    f.R = prev.R * g.R;
    f.p = prev.p + prev.R * g.p;
    if (centroids) centroids[j] = prev.p + prev.R * g.c;
  }
}

std::vector<Frame> LumpedBody::disk_frames(const Eigen::VectorXd& x, const double* stretch) const {
  if (x.size() != per_subsegment * N)
    throw InputError("unknowns", std::to_string(x.size()),
                     "expected " + std::to_string(per_subsegment) + " unknowns per subsegment");
  std::vector<Frame> f(N + 1);
  compute_frames(x.data(), N, stretch, f.data());
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
  residual_changed();
  body_.statics.bind(input, loads_);
  convention_ = input.actuation.convention;
  banded_ = body_.banded();
  reduced_ = body_.reduced(active());
  damping_ = 0.0;  // a snap switches it off again; a new input never starts damped
  bind_contact(input);
  if (banded_ && pattern_J_ != active()) build_pattern();
}

void LumpedProblem::bind_all(const ModelInput& input) {
  bind(input);
  loads_.active = body_.N;
  banded_ = false;
  reduced_ = body_.reduced(active());
}

void LumpedProblem::adjust(bvp::NewtonOptions& options) const {
  options.linear_solver = banded_ ? bvp::LinearSolverKind::SparseKLU : bvp::LinearSolverKind::Dense;
}

void LumpedProblem::adjust_warm(bvp::NewtonOptions& options, bool same_input) const {
  // Iterations one Jacobian serves (modified Newton), and the iterations of the previous solve
  // above which its Jacobian is too stale to start from. bench_loaded's trajectory (n = 10,
  // 1000 steps): with 3, PRB kept the first step's Jacobian for most of the trajectory (42
  // Jacobians, 2.35 iterations per step); with 2, 101 Jacobians and 1.82 iterations per step,
  // 5 % less time; with 1, 317 Jacobians, 1.31 iterations, 35 % more time. CCsub: 0.99
  // iterations per step with each.
  constexpr int kReuseSetupCalls = 10;
  constexpr int kStaleAfterIterations = 2;
  options.reuse_jacobian = same_input || last_iterations_ <= kStaleAfterIterations;
  options.max_setup_calls = kReuseSetupCalls;
  // With contact candidates (a warm start's contacts) the Jacobian is dense differences, a
  // residual per unknown: modified Newton from the last one pays (docs/contact.md, bench_contact).
  if (!contacts_.empty()) options.reuse_jacobian = true;
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
  s.tail(static_cast<Eigen::Index>(contacts_.size())).setOnes();  // the scaled contact forces
}

void LumpedProblem::cold_guess(Eigen::VectorXd& y) {
  residual_changed();
  for (ContactCandidate& c : contacts_) c.lambda = 0.0;
  guess_x(x_, false);
  lift(x_, y);
  append_contact_unknowns(y);
}

void LumpedProblem::rest_state(Eigen::VectorXd& y) {
  residual_changed();
  for (ContactCandidate& c : contacts_) c.lambda = 0.0;
  guess_x(x_, true);
  lift(x_, y);
  append_contact_unknowns(y);
}

void LumpedProblem::fixed_point_passes(Eigen::VectorXd& x, int passes) {
  const int m = body_.per_subsegment;
  const double lambda = loads_.loads.load_factor();
  set_parameter(1.0);
  const bool bb = backbone_weight_on();
  double last_change = INFINITY;
  next_x_.resize(x.size());
  for (int pass = 0; pass < passes; ++pass) {
    evaluate(x.data());
    double change = 0.0;
    for (int j = 1; j <= active(); ++j) {
      const Mat3 Rt = frames_[j - 1].R.transpose();
      const Vec3 W = bb ? Vec3(Rt * backbone_weight(j)) : Vec3::Zero();
      const double* xj = x.data() + m * (j - 1);
      double* next = next_x_.data() + m * (j - 1);
      double weight[8];  // m <= 8
      for (int i = 0; i < m; ++i) weight[i] = 1.0;
      if (!fixed_point(j, xj, poses_[j], Rt * F_[j], Rt * M_[j], W, next, weight)) {
        set_parameter(lambda);
        return;
      }
      for (int i = 0; i < m; ++i) {
        // A non-finite value (e.g. a subsegment's axis at 90 deg in CCsub's twist row) makes the
        // change NaN and ends the passes with the last finite x (std::max would skip it).
        const double d = std::isfinite(next[i]) ? weight[i] * std::abs(next[i] - xj[i]) : NAN;
        if (!(d <= change)) change = d;
      }
    }
    if (!(change <= 0.5 * last_change)) break;
    x = next_x_;
    last_change = change;
  }
  set_parameter(lambda);
}

bool LumpedProblem::warm_guess(const Solution& previous, Eigen::VectorXd& y) {
  if (previous.unknowns.size() != body_.per_subsegment * body_.N || !all_finite(previous.unknowns)) return false;
  const bool contacts = warm_contacts(previous);  // its contacts: candidates from the start
  x_ = previous.unknowns.head(body_.per_subsegment * active());
  residual_changed();
  on_warm(x_);
  lift(x_, y);
  if (contacts) append_contact_unknowns(y);
  return true;
}

void LumpedProblem::evaluate(const double* x) {
  last_valid_ = false;
  body_.compute_frames(x, active(), loads_.stretch_data(), frames_.data(), poses_.data(),
                       backbone_weight_on() ? centroids_.data() : nullptr);
  if (body_.statics.friction()) body_.statics.update_friction(loads_, frames_.data());
  if (!contacts_.empty()) return evaluate_contacts();
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), F_.data(), M_.data());
}

bool LumpedProblem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
  last_valid_ = false;
  const bool ok = banded_ ? banded_residual(y.data(), f.data()) : recursive_residual(y.data(), f.data());
  if (ok && damping_ > 0.0) f += damping_ * damping_scale_.cwiseProduct(y - damping_ref_);
  if (!(ok && all_finite(f))) return false;
  last_y_ = y;  // allocates only when the size changes
  last_f_ = f;
  last_lambda_ = loads_.loads.load_factor();
  last_valid_ = true;
  return true;
}

bool LumpedProblem::residual_with_frames(const Eigen::Ref<const Eigen::VectorXd>& y, const Frame* frames,
                                         const SubsegmentPose* poses, Eigen::Ref<Eigen::VectorXd> f) {
  if (banded_ || !contacts_.empty() || body_.statics.friction() || active() != body_.N) return residual(y, f);
  // evaluate() with the frames and poses given.
  last_valid_ = false;
  const bool bb = backbone_weight_on();
  for (int j = 0; j <= body_.N; ++j) frames_[j] = frames[j];
  for (int j = 1; j <= body_.N; ++j) {
    poses_[j] = poses[j];
    if (bb) centroids_[j] = frames[j - 1].p + frames[j - 1].R * poses[j].c;
  }
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), F_.data(), M_.data());
  constitutive_all(y.data(), f.data());
  // residual()'s end.
  if (damping_ > 0.0) f += damping_ * damping_scale_.cwiseProduct(y - damping_ref_);
  if (!all_finite(f)) return false;
  last_y_ = y;
  last_f_ = f;
  last_lambda_ = loads_.loads.load_factor();
  last_valid_ = true;
  return true;
}

bool LumpedProblem::evaluated_at(const Eigen::Ref<const Eigen::VectorXd>& y) const {
  return last_valid_ && last_lambda_ == loads_.loads.load_factor() && y.size() == last_y_.size() && y == last_y_;
}

bool LumpedProblem::final_residual(const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> f) {
  if (evaluated_at(y)) {
    f = last_f_;
    return true;
  }
  return residual(y, f);
}

bool LumpedProblem::set_damping(const Eigen::Ref<const Eigen::VectorXd>& x_ref, double rate) {
  if (!has_jacobian() || !contacts_.empty()) return false;
  residual_changed();
  damping_ = rate;
  if (rate > 0.0) {
    damping_ref_ = x_ref;  // allocates at a snap only
    damping_scale_.resize(size());
    unknown_scale(damping_scale_);
  }
  return true;
}

bool LumpedProblem::recursive_residual(const double* x, double* f) {
  if (!contacts_.empty()) read_contact_unknowns(x);
  evaluate(x);
  constitutive_all(x, f);
  if (!contacts_.empty()) contact_residuals(f + body_.per_subsegment * active());
  return true;
}

void LumpedProblem::evaluate_from(const double* x, int k) {
  last_valid_ = false;
  body_.compute_frames(x, active(), loads_.stretch_data(), frames_.data(), poses_.data(),
                       backbone_weight_on() ? centroids_.data() : nullptr, k);
  body_.statics.disk_loads(loads_, frames_.data(), disk_f_.data(), disk_m_.data(), k - 1);
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), disk_f_.data(), disk_m_.data(), F_.data(),
                                M_.data());
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
  // The tensions at full load: the path's limit test (follow_loading_path's fold_limit) finds a
  // tendon at its limit only among tensioned ones.
  solution.tensions = loads_.loads.full_tensions();
  gather_x(y, x_);
  Eigen::VectorXd full = Eigen::VectorXd::Zero(body_.per_subsegment * body_.N);
  full.head(x_.size()) = x_;
  // Right after the driver's final check the recursive form's evaluated frames are those of y.
  if (!banded_ && evaluated_at(y))
    solution.disk_frames.assign(frames_.begin(), frames_.end());
  else {
    solution.disk_frames.resize(body_.N + 1);
    body_.compute_frames(full.data(), active(), loads_.stretch_data(), solution.disk_frames.data());
  }
  solution.tendon_displacements = tendon::chord_displacements(solution.disk_frames, body_.statics.routing(), convention_);
  if (body_.statics.friction()) {
    const TendonRouting& routing = body_.statics.routing();
    body_.statics.update_friction(loads_, solution.disk_frames.data());
    solution.tendon_end_tensions = tendon::end_tensions(routing, loads_.chord.data(), static_cast<int>(routing.tendons.size()));
  }
  solution.unknowns = std::move(full);
  if (!contacts_.empty()) {
    if (!(!banded_ && evaluated_at(y))) {
      read_contact_unknowns(y.data());
      evaluate(y.data());
    }
    report_contacts(solution);
  }
}

bool LumpedProblem::set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) {
  residual_changed();
  for (std::size_t i = 0; i < index.size(); ++i)
    loads_.loads.set_fixed_tension(index[i], T[static_cast<Eigen::Index>(i)]);
  loads_.set_load_factor(loads_.loads.load_factor());
  return true;
}

bool LumpedProblem::tendon_pulls(const Eigen::VectorXd& y, Eigen::VectorXd& d) {
  gather_x(y, x_);
  pull_x_.setZero(body_.per_subsegment * body_.N);
  pull_x_.head(x_.size()) = x_;
  pull_frames_.resize(body_.N + 1);
  body_.compute_frames(pull_x_.data(), active(), loads_.stretch_data(), pull_frames_.data());
  const std::vector<double> pulls = tendon::chord_displacements(pull_frames_, body_.statics.routing(), convention_);
  d = Eigen::Map<const Eigen::VectorXd>(pulls.data(), static_cast<Eigen::Index>(pulls.size()));
  return all_finite(d);
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

std::vector<Frame> LumpedModel::frames(const Eigen::VectorXd& x, const ModelInput& input) const {
  detail::SubsegmentLoads loads;
  body_->statics.bind(input, loads);
  return body_->disk_frames(x, loads.stretch_data());
}

detail::ModelProblem& LumpedModel::bind(ModelWorkspace& workspace, const ModelInput& input,
                                        const SolverOptions&) const {
  detail::LumpedProblem& problem = *static_cast<detail::LumpedWorkspace&>(workspace).problem;
  problem.bind(input);
  return problem;
}

}  // namespace tdcr
