// The common base of CCsub and PRB (lumped_model.hpp): workspace, binding, guesses, outputs.
#include "tdcr/models/lumped_model.hpp"

#include "common/lumped_problem.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace detail {

namespace {

class LumpedWorkspace final : public ModelWorkspace {
 public:
  LumpedWorkspace(const StaticModel& owner, const LumpedBody& body) : ModelWorkspace(owner), problem(body.make_problem()) {}
  std::unique_ptr<LumpedProblem> problem;
};

}  // namespace

LumpedBody::LumpedBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, int per_subsegment)
    : statics(robot, routing, effects), per_subsegment(per_subsegment), N(statics.subsegments()) {
  const BackboneStiffness k = robot.backbone.effective_stiffness();
  EI = k.EI;
  GJ = k.GJ;
}

LumpedBody::~LumpedBody() = default;

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
  centroids_.assign(body.N + 1, Vec3::Zero());
  F_.assign(body.N + 1, Vec3::Zero());
  M_.assign(body.N + 1, Vec3::Zero());
}

void LumpedProblem::bind(const ModelInput& input) {
  body_.statics.bind(input, loads_);
  convention_ = input.actuation.convention;
}

void LumpedProblem::adjust(bvp::NewtonOptions& options) const { options.linear_solver = LinearSolverKind::Dense; }

bool LumpedProblem::warm_guess(const Solution& previous, Eigen::VectorXd& x) {
  if (previous.unknowns.size() != body_.per_subsegment * body_.N || !previous.unknowns.allFinite()) return false;
  x = previous.unknowns.head(size());
  return true;
}

void LumpedProblem::evaluate(const double* x) {
  geometry(x);
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), F_.data(), M_.data());
}

void LumpedProblem::extract(const Eigen::VectorXd& x, bool evaluated, Solution& solution) {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(body_.per_subsegment * body_.N);
  full.head(x.size()) = x;
  // The driver has just evaluated the residual at x: frames_ are the answer's.
  if (evaluated) {
    solution.disk_frames = frames_;
  } else {
    solution.disk_frames.resize(body_.N + 1);
    body_.compute_frames(full.data(), active(), solution.disk_frames.data());
  }
  solution.tendon_displacements = tendon::chord_displacements(solution.disk_frames, body_.statics.routing(), convention_);
  solution.unknowns = std::move(full);
}

}  // namespace detail

LumpedModel::LumpedModel(const Robot& robot, const Effects& effects, BodyFactory make_body)
    : StaticModel(robot, effects), body_(make_body(this->robot(), routing(), this->effects())) {}

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
