// Displacement input: the driven tendons' tensions as unknowns of the model's own residual
// system (displacement_input.hpp, docs/models.md "Displacement input").
#include "solve/displacement_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "solve/newton_summary.hpp"
#include "physics/geometry_check.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

namespace {
// The homotopy compliance a cold solve starts with (DisplacementProblem::bind), and below which
// the next step is zero.
constexpr double kStartCompliance = 1e-2;
constexpr double kMinCompliance = 1e-12;
constexpr int kMaxConstraintUpdates = 8;
}  // namespace

bool needs_displacement_solve(const StaticModel& model, const ModelInput& input) {
  return input.actuation.kind == Actuation::Kind::Displacements &&
         model.capabilities().displacement_statics;
}

ModelInput tension_form(const ModelInput& input, const std::vector<double>& placeholder) {
  ModelInput out = input;
  out.actuation.kind = Actuation::Kind::Tensions;
  out.actuation.kinds.clear();
  for (std::size_t k = 0; k < out.actuation.values.size(); ++k)
    if (input.actuation.kind_of(k) == Actuation::Kind::Displacements) out.actuation.values[k] = placeholder[k];
  return out;
}

DisplacementProblem::DisplacementProblem() = default;
DisplacementProblem::~DisplacementProblem() = default;

std::vector<double> DisplacementProblem::placeholders(const StaticModel& model, const ModelInput& input) {
  const double EI = model.robot().backbone.effective_stiffness().EI;
  const TendonRouting& routing = model.routing();
  std::vector<double> p(input.actuation.values.size(), 0.0);
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (input.actuation.kind_of(k) != Actuation::Kind::Displacements) continue;
    const RoutedTendon& t = routing.tendons[k];
    p[k] = EI / (t.r.norm() * physics::rest_length(t, 0.0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]));
  }
  return p;
}

void DisplacementProblem::bind(const StaticModel& model, ModelProblem& inner, const ModelInput& input,
                               const SolverOptions& options, const Solution* warm) {
  model_ = &model;
  tolerance_ = options.function_tolerance;
  inner_ = &inner;
  sys_ = inner.system();
  n_ = sys_->size();
  const Robot& robot = model.robot();
  const TendonRouting& routing = model.routing();
  const double EI = robot.backbone.effective_stiffness().EI;
  index_.clear();
  std::vector<double> stiffness;
  {
    std::size_t k = 0;
    for (const Segment& seg : robot.segments)
      for (const TendonSpec& spec : seg.tendons) {
        if (input.actuation.kind_of(k) == Actuation::Kind::Displacements) {
          index_.push_back(static_cast<int>(k));
          stiffness.push_back(spec.stiffness ? *spec.stiffness : 0.0);
        }
        ++k;
      }
  }
  k_ = static_cast<int>(index_.size());
  delta_.resize(k_);
  r_.resize(k_);
  ts_.resize(k_);
  stretch_.resize(k_);
  std::vector<double> l_free(static_cast<std::size_t>(k_));
  longest_.resize(k_);
  for (int i = 0; i < k_; ++i) {
    const RoutedTendon& t = routing.tendons[static_cast<std::size_t>(index_[i])];
    const bool per_segment = input.actuation.convention == Actuation::DisplacementConvention::PerSegment && t.segment > 0;
    const double s0 = per_segment ? routing.segment_end_s[static_cast<std::size_t>(t.segment - 1)] : 0.0;
    longest_[i] = physics::rest_length(t, s0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]);
    delta_[i] = input.actuation.values[static_cast<std::size_t>(index_[i])];
    r_[i] = t.r.norm();
    l_free[i] = physics::rest_length(t, 0.0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]);
    ts_[i] = EI / (r_[i] * l_free[i]);
    stretch_[i] = stiffness[i] > 0.0 ? l_free[i] / stiffness[i] : 0.0;
  }
  // Linear beam theory on the straight robot: tendon j's tension bends every segment it spans
  // with curvature T_j r_j / EI towards it, which pulls tendon i by (r_i . r_j) / EI per length
  // they share (the base offsets: a guess, exact for straight routing).
  // The tendons given by tension pull the driven ones by linear_given_ (in units of r).
  const auto pull = [&](int i, int j) {  // d pull_i / d T_j (m/N), global indices
    const RoutedTendon& a = routing.tendons[static_cast<std::size_t>(i)];
    const RoutedTendon& b = routing.tendons[static_cast<std::size_t>(j)];
    return a.r.dot(b.r) * routing.disk_s[static_cast<std::size_t>(std::min(a.end_disk, b.end_disk))] / EI;
  };
  linear_.resize(k_, k_);
  linear_given_.setZero(k_);
  for (int i = 0; i < k_; ++i) {
    for (int j = 0; j < k_; ++j) linear_(i, j) = pull(index_[i], index_[j]) * ts_[j] / r_[i];
    for (std::size_t j = 0; j < input.actuation.values.size(); ++j)
      if (input.actuation.kind_of(j) == Actuation::Kind::Tensions)
        linear_given_[i] += pull(index_[i], static_cast<int>(j)) * input.actuation.values[j] / r_[i];
  }
  // Which tendons start taut: a warm start's tensioned ones, else those the linear guess
  // tensions (a tendon it leaves slack is moved to taut after the solve if its path is too long:
  // update_constraints; starting it taut at zero tension can make the loading path's first
  // Jacobian singular, PRB's bending planes set by the external load alone).
  taut_.assign(static_cast<std::size_t>(k_), 0);
  Eigen::VectorXd tau;
  const bool from_warm = warm && tensions_of(*warm, tau);
  if (!from_warm) linear_guess(tau);
  for (int i = 0; i < k_; ++i) taut_[static_cast<std::size_t>(i)] = tau[i] > 0.0;
  lambda_ = 1.0;
  start_.resize(0);
  base_.setZero(k_);
  T_.setZero(k_);
  applied_valid_ = false;
  // A cold solve starts with every taut tendon compliant (complete() takes it to zero): co-
  // contraction that the pulls decide only weakly is then held down on the way, not sent far.
  compliance_ = from_warm ? 0.0 : kStartCompliance;

  // The Jacobian's pattern: the inner one bordered by k full rows (the pulls read every unknown
  // that moves a disk) and k full columns (a tension loads every disk it passes).
  const bvp::SparsityPattern* p = sys_->sparsity();
  sparse_ = p != nullptr;
  if (sparse_) {
    const int m = n_ + k_;
    pattern_.rows = pattern_.cols = m;
    pattern_.col_ptr.assign(static_cast<std::size_t>(m) + 1, 0);
    pattern_.row_idx.clear();
    inner_pos_.resize(static_cast<std::size_t>(p->nnz()));
    for (int j = 0; j < n_; ++j) {
      for (int q = p->col_ptr[j]; q < p->col_ptr[j + 1]; ++q) {
        inner_pos_[static_cast<std::size_t>(q)] = static_cast<int>(pattern_.row_idx.size());
        pattern_.row_idx.push_back(p->row_idx[q]);
      }
      for (int i = 0; i < k_; ++i) pattern_.row_idx.push_back(n_ + i);
      pattern_.col_ptr[static_cast<std::size_t>(j) + 1] = static_cast<int>(pattern_.row_idx.size());
    }
    for (int j = n_; j < m; ++j) {
      for (int i = 0; i < m; ++i) pattern_.row_idx.push_back(i);
      pattern_.col_ptr[static_cast<std::size_t>(j) + 1] = static_cast<int>(pattern_.row_idx.size());
    }
    inner_values_.assign(static_cast<std::size_t>(p->nnz()), 0.0);
    fd_.prepare(*p);
  } else {
    fd_.prepare(n_);
  }
}

bool DisplacementProblem::tensions_of(const Solution& s, Eigen::VectorXd& tau) const {
  tau.resize(k_);
  for (int i = 0; i < k_; ++i) {
    const auto k = static_cast<std::size_t>(index_[i]);
    if (k >= s.tensions.size() || !std::isfinite(s.tensions[k])) return false;
    tau[i] = s.tensions[k] / ts_[i];
  }
  return true;
}

bool DisplacementProblem::apply(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  for (int i = 0; i < k_; ++i) T_[i] = taut_[static_cast<std::size_t>(i)] ? ts_[i] * tau[i] : 0.0;
  if (applied_valid_ && T_ == applied_) return true;
  if (!inner_->set_driven_tensions(index_, T_)) return false;
  applied_ = T_;
  applied_valid_ = true;
  return true;
}

void DisplacementProblem::driven_rows(const Eigen::Ref<const Eigen::VectorXd>& tau,
                                      Eigen::Ref<Eigen::VectorXd> r) const {
  for (int i = 0; i < k_; ++i)
    r[i] = taut_[static_cast<std::size_t>(i)]
               ? (pulls_[index_[i]] + stretch_[i] * ts_[i] * tau[i] - target(i)) / r_[i] + compliance_ * tau[i]
               : tau[i];
}

bool DisplacementProblem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
  if (!apply(y.tail(k_))) return false;
  if (!sys_->residual(y.head(n_), f.head(n_))) return false;
  x_ = y.head(n_);
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  driven_rows(y.tail(k_), f.tail(k_));
  return f.allFinite();
}

bool DisplacementProblem::final_residual(const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> f) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  if (!inner_->final_residual(x_, f.head(n_))) return false;
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  driven_rows(y.tail(k_), f.tail(k_));
  return f.allFinite();
}

bool DisplacementProblem::border(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                                 Eigen::Ref<Eigen::MatrixXd>* Jxx) {
  const double noise = sys_->relative_noise();
  Eigen::VectorXd tau = y.tail(k_);
  x_ = y.head(n_);
  if (!apply(tau) || !inner_->tendon_pulls(x_, pulls_)) return false;
  const Eigen::VectorXd p0 = pulls_;
  // dF/dtau and d rows / dtau: one inner residual and one pull per taut tendon (the pulls move
  // with the tensions at fixed unknowns where the unknowns do not fix the shape: VC's base wrench).
  col_.setZero(n_, k_);
  tt_.setZero(k_, k_);
  fp_.resize(n_);
  for (int j = 0; j < k_; ++j) {
    if (taut_[static_cast<std::size_t>(j)]) {  // a slack tendon's tension is held at zero
      const double h = bvp::finite_difference_step(tau[j], 1.0, noise);
      tau[j] += h;
      if (!apply(tau) || !sys_->residual(x_, fp_) || !inner_->tendon_pulls(x_, dp_)) return false;
      col_.col(j) = (fp_ - f.head(n_)) / h;
      for (int i = 0; i < k_; ++i)
        if (taut_[static_cast<std::size_t>(i)]) tt_(i, j) = (dp_[index_[i]] - p0[index_[i]]) / (h * r_[i]);
      tau[j] = y[n_ + j];
    }
    tt_(j, j) += taut_[static_cast<std::size_t>(j)] ? stretch_[j] * ts_[j] / r_[j] + compliance_ : 1.0;
  }
  if (!apply(tau)) return false;
  // d rows / dx: the pulls with each unknown moved; with Jxx, also the model's residual there
  // (its forward-difference Jacobian from the same evaluations: VC's shots record the tendon
  // lengths, so its pulls come with its residual).
  Eigen::VectorXd uscale(n_);
  sys_->unknown_scale(uscale);
  row_.setZero(k_, n_);
  for (int j = 0; j < n_; ++j) {
    const double h = bvp::finite_difference_step(x_[j], uscale[j], noise);
    const double xj = x_[j];
    x_[j] = xj + h;
    bool ok = true;
    if (Jxx) {
      ok = sys_->residual(x_, fp_);
      if (ok) Jxx->col(j) = (fp_ - f.head(n_)) / h;
    }
    ok = ok && inner_->tendon_pulls(x_, dp_);
    x_[j] = xj;
    if (!ok) return false;
    for (int i = 0; i < k_; ++i)
      if (taut_[static_cast<std::size_t>(i)]) row_(i, j) = (dp_[index_[i]] - p0[index_[i]]) / (h * r_[i]);
  }
  pulls_ = p0;
  return col_.allFinite() && row_.allFinite() && tt_.allFinite();
}

bool DisplacementProblem::jacobian(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                                   Eigen::Ref<Eigen::MatrixXd> J) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  J.setZero();
  Eigen::Ref<Eigen::MatrixXd> Jxx = J.topLeftCorner(n_, n_);
  if (sys_->has_jacobian()) {
    if (!bvp::analytic_jacobian_dense(*sys_, x_, f.head(n_), Jxx) || !border(y, f, nullptr)) return false;
  } else if (!border(y, f, &Jxx)) {  // forward differences with the pulls'
    return false;
  }
  J.topRightCorner(n_, k_) = col_;
  J.bottomLeftCorner(k_, n_) = row_;
  J.bottomRightCorner(k_, k_) = tt_;
  return J.allFinite();
}

bool DisplacementProblem::sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                                          const Eigen::Ref<const Eigen::VectorXd>& f, double* values) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  const bvp::SparsityPattern& p = *sys_->sparsity();
  const bool ok = sys_->has_jacobian()
                      ? sys_->sparse_jacobian(x_, f.head(n_), inner_values_.data())
                      : bvp::finite_difference_sparse_jacobian(*sys_, x_, f.head(n_), p, inner_values_.data(), &fd_);
  if (!ok || !border(y, f, nullptr)) return false;
  std::fill(values, values + pattern_.nnz(), 0.0);
  for (std::size_t q = 0; q < inner_pos_.size(); ++q) values[inner_pos_[q]] = inner_values_[q];
  for (int j = 0; j < n_; ++j) {
    const int end = pattern_.col_ptr[static_cast<std::size_t>(j) + 1];
    for (int i = 0; i < k_; ++i) values[end - k_ + i] = row_(i, j);
  }
  for (int j = 0; j < k_; ++j) {
    const int start = pattern_.col_ptr[static_cast<std::size_t>(n_ + j)];
    for (int i = 0; i < n_; ++i) values[start + i] = col_(i, j);
    for (int i = 0; i < k_; ++i) values[start + n_ + i] = tt_(i, j);
  }
  return true;
}

void DisplacementProblem::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  sys_->residual_scale(s.head(n_));
  s.tail(k_).setOnes();
}

void DisplacementProblem::unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  sys_->unknown_scale(s.head(n_));
  s.tail(k_).setOnes();
}

double DisplacementProblem::relative_noise() const { return sys_->relative_noise(); }

void DisplacementProblem::set_parameter(double lambda) {
  lambda_ = lambda;
  sys_->set_parameter(start_.size() > 0 ? 1.0 : lambda);
}

ColdStart DisplacementProblem::cold_start() const {
  constexpr int kStartPathSteps = 128;
  if (start_.size() == 0) return inner_->cold_start();
  ColdStart c;
  c.max_path_steps = kStartPathSteps;
  return c;
}

void DisplacementProblem::start_from(const Solution& start) {
  Eigen::VectorXd y;
  if (!warm_guess(start, y)) return;  // stays from rest
  base_.resize(k_);
  for (int i = 0; i < k_; ++i) base_[i] = start.tendon_displacements[static_cast<std::size_t>(index_[i])];
  start_ = y;
  compliance_ = 0.0;
  sys_->set_parameter(1.0);
}

void DisplacementProblem::accept_step(Eigen::VectorXd& y) {
  x_ = y.head(n_);
  sys_->accept_step(x_);
  y.head(n_) = x_;
}

bool DisplacementProblem::recenter(Eigen::Ref<Eigen::VectorXd> y) { return sys_->recenter(y.head(n_)); }

void DisplacementProblem::adjust(bvp::NewtonOptions& options) const {
  inner_->adjust(options);
  if (!sparse_ && options.linear_solver == bvp::LinearSolverKind::SparseKLU)
    options.linear_solver = bvp::LinearSolverKind::Dense;
}

void DisplacementProblem::adjust_warm(bvp::NewtonOptions& options, bool same_input) const {
  constexpr int kReuseSetupCalls = 10;
  constexpr int kStaleAfterIterations = 3;
  options.reuse_jacobian = same_input || last_iterations_ <= kStaleAfterIterations;
  options.max_setup_calls = kReuseSetupCalls;
}

void DisplacementProblem::linear_guess(Eigen::VectorXd& tau) const {
  // The linear complementarity problem w = L tau + p - delta / r >= 0, tau >= 0, tau . w = 0 (p:
  // the pulls of the tendons given by tension), by
  // moving tendons between the taut set (w = 0, minimum-norm) and the slack set (tau = 0).
  tau.setZero(k_);
  if (k_ == 0) return;
  Eigen::VectorXd q(k_);
  for (int i = 0; i < k_; ++i) q[i] = delta_[i] / r_[i] - linear_given_[i];
  std::vector<char> taut(static_cast<std::size_t>(k_));
  for (int i = 0; i < k_; ++i) taut[static_cast<std::size_t>(i)] = q[i] > 0.0;
  for (int pass = 0; pass < 2 * k_ + 2; ++pass) {
    std::vector<int> A;
    for (int i = 0; i < k_; ++i)
      if (taut[static_cast<std::size_t>(i)]) A.push_back(i);
    tau.setZero();
    if (!A.empty()) {
      Eigen::MatrixXd M(A.size(), A.size());
      Eigen::VectorXd b(A.size());
      for (std::size_t a = 0; a < A.size(); ++a) {
        b[static_cast<Eigen::Index>(a)] = q[A[a]];
        for (std::size_t c = 0; c < A.size(); ++c)
          M(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(c)) = linear_(A[a], A[c]);
      }
      // Minimum norm by a singular value decomposition: antagonistic tendons taut together make M
      // singular, and Eigen's CompleteOrthogonalDecomposition read uninitialised memory in its
      // solve of a rank-deficient matrix (valgrind, Eigen 3.4).
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
      Eigen::VectorXd c = svd.matrixU().transpose() * b;
      const Eigen::VectorXd& sv = svd.singularValues();
      for (Eigen::Index q = 0; q < sv.size(); ++q) c[q] = sv[q] > 1e-12 * sv[0] ? c[q] / sv[q] : 0.0;
      const Eigen::VectorXd t = svd.matrixV() * c;
      for (std::size_t a = 0; a < A.size(); ++a) tau[A[a]] = t[static_cast<Eigen::Index>(a)];
    }
    const Eigen::VectorXd w = linear_ * tau - q;
    bool moved = false;
    for (int i = 0; i < k_; ++i) {
      char& ti = taut[static_cast<std::size_t>(i)];
      if ((ti && tau[i] < 0.0) || (!ti && w[i] < -1e-12)) {
        ti = !ti;
        moved = true;
      }
    }
    if (!moved) break;
  }
  tau = tau.cwiseMax(0.0);
}

std::vector<double> DisplacementProblem::linear_tensions(std::vector<double> values) const {
  Eigen::VectorXd tau;
  linear_guess(tau);
  for (int i = 0; i < k_; ++i) values[static_cast<std::size_t>(index_[i])] = ts_[i] * tau[i];
  return values;
}

void DisplacementProblem::cold_guess(Eigen::VectorXd& y) {
  if (start_.size() > 0) {
    y = start_;
    return;
  }
  Eigen::VectorXd tau;
  linear_guess(tau);
  apply(tau);
  inner_->cold_guess(x_);
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
}

bool DisplacementProblem::alternative_guess(Eigen::VectorXd& y) {
  if (start_.size() > 0) return false;
  Eigen::VectorXd tau;
  linear_guess(tau);
  apply(tau);
  if (!inner_->alternative_guess(x_)) return false;
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
  return true;
}

void DisplacementProblem::rest_state(Eigen::VectorXd& y) {
  if (start_.size() > 0) {  // the tension solve's equilibrium solves the pulls' homotopy at 0
    y = start_;
    return;
  }
  // The straight robot with every driven tension 0.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(k_);
  apply(zero);
  inner_->rest_state(x_);
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_).setZero();
  // A model whose rest state has a gauge that the loads set (PRB's bending planes of straight
  // subsegments) takes it from the tensions the commanded pulls will need (the linear guess):
  // from the external loads alone the plane can lie across a driven tendon, whose pull then does
  // not move to first order and the loading path's first Jacobian is singular. Kept where it is a
  // rest state at zero tension as well (the shape is straight either way).
  Eigen::VectorXd tau;
  linear_guess(tau);
  if (!(tau.array() > 0.0).any()) return;
  apply(tau);
  Eigen::VectorXd xg;
  inner_->rest_state(xg);
  Eigen::VectorXd yg(n_ + k_), f(n_ + k_), s(n_ + k_);
  yg.head(n_) = xg;
  yg.tail(k_).setZero();
  residual_scale(s);
  if (residual(yg, f) && f.cwiseProduct(s).lpNorm<Eigen::Infinity>() <= 1e-14) {
    y = yg;
    return;
  }
  apply(zero);  // its gauge state back to the zero-tension rest state's
  inner_->rest_state(x_);
}

bool DisplacementProblem::warm_guess(const Solution& previous, Eigen::VectorXd& y) {
  Eigen::VectorXd tau;
  if (!tensions_of(previous, tau)) return false;
  for (int i = 0; i < k_; ++i) taut_[static_cast<std::size_t>(i)] = tau[i] > 0.0 || (previous.tendon_slack.empty() && delta_[i] > 0.0);
  apply(tau);
  if (!inner_->warm_guess(previous, x_)) return false;
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
  return true;
}

void DisplacementProblem::extract(const Eigen::VectorXd& y, bool evaluated, Solution& solution) {
  last_iterations_ = solution.summary.iterations;
  Eigen::VectorXd tau = y.tail(k_);
  for (int i = 0; i < k_; ++i)
    if (!taut_[static_cast<std::size_t>(i)]) tau[i] = 0.0;
  apply(tau);
  x_ = y.head(n_);
  solution.unknowns = x_;
  inner_->extract(x_, evaluated, solution);
  solution.tendon_slack.assign(solution.tensions.size(), false);
  std::string slack;
  for (int i = 0; i < k_; ++i) {
    const auto k = static_cast<std::size_t>(index_[i]);
    if (k >= solution.tensions.size()) continue;
    const bool taut = taut_[static_cast<std::size_t>(i)];
    solution.tensions[k] = taut ? std::max(0.0, ts_[i] * tau[i]) : 0.0;
    solution.tendon_slack[k] = !taut;
    if (!taut) slack += (slack.empty() ? "" : ", ") + std::to_string(k);
  }
  solution.summary.message += "; displacement input: " + std::to_string(k_) + " driven tendons, slack: " +
                              (slack.empty() ? "none" : slack);
}

Stability DisplacementProblem::stability(const Eigen::VectorXd& y, double load_factor) {
  if (!apply(y.tail(k_))) return Stability{};
  return held_tensions(inner_->stability(y.head(n_), load_factor));
}

Stability DisplacementProblem::direct_stability(const Eigen::VectorXd& y, double load_factor) {
  if (!apply(y.tail(k_))) return Stability{};
  return held_tensions(inner_->direct_stability(y.head(n_), load_factor));
}

Stability DisplacementProblem::held_tensions(Stability s) const {
  // The test holds the driven tensions fixed. A tendon held at its length instead only adds a
  // constraint, which cannot make a stable equilibrium unstable, but can stabilise an unstable
  // one: stable stays stable, unstable is not decided.
  if (s.status == StabilityStatus::Unstable) {
    s.status = StabilityStatus::Undetermined;
    s.method += " (unstable at the answer's tensions held fixed; the displacement-driven tendons, held at their "
                "lengths, may stabilise it: not decided)";
  } else if (s.status == StabilityStatus::Stable) {
    s.method += " (at the answer's tensions held fixed; the displacement-driven tendons held at their lengths can "
                "only stiffen it)";
  }
  return s;
}

bool DisplacementProblem::infeasibility(const Eigen::VectorXd& y, double threshold, std::string& why) {
  if (!apply(y.tail(k_))) return false;
  return inner_->infeasibility(y.head(n_), threshold, why);
}

bool DisplacementProblem::impossible_input(std::string& why) const {
  for (int i = 0; i < k_; ++i) {
    if (stretch_[i] > 0.0 || !(delta_[i] >= longest_[i])) continue;
    const int k = index_[i];
    why = "infeasible actuation: tendon T" + std::to_string(k + 1) + " (index " + std::to_string(k) +
          ") commanded a pull of " + format_value(delta_[i]) + " m, not less than its path's length " +
          format_value(longest_[i]) + " m on the straight robot: no shape shortens its path that much";
    return true;
  }
  return false;
}

bool DisplacementProblem::stiffen(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) {
  double factor = 0.0;  // straight to zero first; where that fails, in decades, then shorter steps
  Eigen::VectorXd last = y;
  bvp::NewtonOptions o = options;
  while (compliance_ > 0.0) {
    const double from = compliance_;
    compliance_ = from * factor < kMinCompliance ? 0.0 : from * factor;
    const bvp::NewtonResult res = newton_.solve(*this, y, o);
    copy_newton_result(res, summary);
    o.reuse_jacobian = true;  // the next compliance changes only the diagonal
    if (res.converged()) {
      last = y;
      continue;
    }
    y = last;
    compliance_ = from;
    factor = factor == 0.0 ? 1e-2 : std::sqrt(factor);
    o.reuse_jacobian = false;
    if (factor > 0.9) {
      summary.message += "; the taut tendons' homotopy compliance could not be taken below " + format_value(from);
      compliance_ = 0.0;
      return false;
    }
  }
  return true;
}

bool DisplacementProblem::flip(const Eigen::VectorXd& y) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  bool changed = false;
  for (int i = 0; i < k_; ++i) {
    char& t = taut_[static_cast<std::size_t>(i)];
    const double gap = (pulls_[index_[i]] + stretch_[i] * ts_[i] * std::max(0.0, y[n_ + i]) - target(i)) / r_[i];
    if (t && y[n_ + i] < -tolerance_) {
      t = 0;  // it would push: slack
      changed = true;
    } else if (!t && gap < -tolerance_) {
      t = 1;  // its path is too long for it: taut
      changed = true;
    }
  }
  if (changed) applied_valid_ = false;
  return changed;
}

ModelProblem::Completion DisplacementProblem::complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options,
                                                      SolverSummary& summary) {
  const std::string path = summary.message;
  std::string what;
  bvp::NewtonOptions fresh = options;  // exact Newton: the last Jacobian is of other equations
  fresh.reuse_jacobian = false;
  fresh.max_setup_calls = 1;
  if (compliance_ > 0.0) {
    if (!stiffen(y, options, summary)) {
      // The compliant tendons' answer with a tendon at its geometric limit: the commanded pulls
      // need it past the limit (the compliance only let it stop short).
      std::string why;
      if (at_limit(y, why)) {
        summary.termination = TerminationType::Infeasible;
        summary.message = why + "; the commanded pulls need it further (" + summary.message + ")";
      }
      return Completion::Done;
    }
    what = "homotopy compliance " + format_value(kStartCompliance) + " taken to zero";
  }
  int updates = 0;
  while (flip(y)) {
    if (++updates > kMaxConstraintUpdates) {
      summary.termination = TerminationType::NoConvergence;
      summary.message = path + "; slack and taut tendons changed more than " + std::to_string(kMaxConstraintUpdates) +
                        " times (cycling)";
      return Completion::Done;
    }
    // A direct solve from the last answer; where it fails, from the same answer with the taut
    // tendons compliant and the compliance taken to zero (a tendon moved to taut at zero
    // tension may need co-contraction that its pull decides only weakly).
    const Eigen::VectorXd start = y;
    constexpr int kDirectIterations = 20;
    bvp::NewtonOptions first = fresh;
    first.max_iterations = std::min(options.max_iterations, kDirectIterations);
    bvp::NewtonResult res = newton_.solve(*this, y, first);
    copy_newton_result(res, summary);
    if (!res.converged()) {
      y = start;
      compliance_ = kStartCompliance;
      res = newton_.solve(*this, y, fresh);
      copy_newton_result(res, summary);
      if (!res.converged() || !stiffen(y, fresh, summary)) {
        // Solved cold instead, with the new branches and the compliance back.
        compliance_ = kStartCompliance;
        applied_valid_ = false;
        summary.message = path + "; after tendons changed between slack and taut, from the answer: " + summary.message;
        return Completion::FollowAgain;
      }
    }
  }
  if (updates > 0) what += (what.empty() ? "" : ", ") + std::string("slack and taut tendons changed ") +
                           std::to_string(updates) + (updates == 1 ? " time" : " times");
  refine(y, options);
  if (!what.empty()) summary.message = path + "; then " + what + ": " + summary.message;
  return Completion::Done;
}

bool DisplacementProblem::at_limit(const Eigen::VectorXd& y, std::string& why) {
  if (infeasibility(y, physics::kTendonLimitNear, why)) return true;
  Solution shape;
  Eigen::VectorXd f(size());
  const bool evaluated = final_residual(y, f);
  extract(y, evaluated, shape);
  return evaluated && physics::tendon_limit(model_->routing(), shape, physics::kTendonLimitNear, why);
}

void DisplacementProblem::refine(Eigen::VectorXd& y, const bvp::NewtonOptions& options) {
  constexpr double kRefineTighter = 1e-3;
  constexpr double kRefineFloor = 1e-15;
  constexpr int kRefineIterations = 3;
  Eigen::VectorXd f(size()), s(size());
  residual_scale(s);
  if (!residual(y, f)) return;
  const double before = f.cwiseProduct(s).lpNorm<Eigen::Infinity>();
  bvp::NewtonOptions o = options;
  o.function_tolerance = std::max(kRefineTighter * options.function_tolerance, kRefineFloor);
  if (before <= o.function_tolerance) return;
  o.max_iterations = kRefineIterations;
  o.reuse_jacobian = false;
  o.max_setup_calls = 1;
  o.freeze_jacobian_below = 0.0;
  Eigen::VectorXd z = y;
  newton_.solve(*this, z, o);
  if (residual(z, f) && f.cwiseProduct(s).lpNorm<Eigen::Infinity>() < before) y = z;
}

}  // namespace tdcr::detail

namespace tdcr {

detail::DisplacementProblem& ModelWorkspace::displacement_problem() {
  if (!displacement_) displacement_ = std::make_unique<detail::DisplacementProblem>();
  return *displacement_;
}

}  // namespace tdcr

namespace tdcr::detail {

bool tension_start(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                   const SolverOptions& options, Solution& start) {
  const auto& D =
      static_cast<const DisplacementProblem&>(bind_displacement_problem(model, workspace, input, options, nullptr, nullptr));
  ModelInput tensions = input;
  tensions.actuation.kind = Actuation::Kind::Tensions;
  tensions.actuation.kinds.clear();
  tensions.actuation.values = D.linear_tensions(input.actuation.values);
  SolverOptions o = options;
  o.stability = StabilityCheck::Never;
  o.differential_kinematics = false;
  start = tdcr::solve(model, workspace, tensions, o);
  return start.converged();
}

ModelProblem& bind_displacement_problem(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                        const SolverOptions& options, const Solution* warm_start,
                                        const Solution* tension_start) {
  const ModelInput tensions = tension_form(input, DisplacementProblem::placeholders(model, input));
  ModelProblem& inner = model.bind(workspace, tensions, options);
  DisplacementProblem& D = workspace.displacement_problem();
  D.bind(model, inner, input, options, warm_start ? warm_start : tension_start);
  if (tension_start && !warm_start) D.start_from(*tension_start);
  return D;
}

}  // namespace tdcr::detail
