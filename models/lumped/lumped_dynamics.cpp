// The equations of motion of CCsub and PRB (lumped_dynamics.hpp, docs/dynamics.md), integrated
// by CVODE (BDF; Newton matrices M, K, D from the model's structured Jacobian, solved in O(N) by
// the articulated-body algorithm with K's diagonal blocks, or, under displacement input, as one
// dense n x n system).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "lumped/lumped_dynamics_integrator.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr::detail {

namespace {
// Displacement input: the fixed point of the driven tensions and the backbone's compression
// under them (effects.shear_extension) stops at this change (relative to EA_k / L_k times the
// robot's length, i.e. a pull change of 1e-14 L) or after kMaxTensionIterations.
constexpr double kTensionFixedPointTol = 1e-14;
constexpr int kMaxTensionIterations = 100;
// ... and a right-hand side whose fixed point is still this far off after them fails (CVODE
// retries a smaller step, then reports the step failed) rather than going on with tensions that
// do not meet their motors.
constexpr double kTensionFixedPointGiveUp = 1e-9;
// Slack events: the band (over the robot's length) by which a tendon's gap delta - d must pass
// zero before the root function fires again. At exactly zero a restarted CVODE would find the
// root it just stopped at (CV_CLOSE_ROOTS), and so would a tendon that stays at its slack limit
// (driven at 0 on the straight robot): each tendon is in one mode, taut or slack, and its root
// function is gap + band (taut) or gap - band (slack). The kink is straddled by at most 1e-12 L
// of pull: EA / L_free * 1e-12 L of tension (1e-9 N for EA = 400 N on the paper robot).
constexpr double kEventBandOverLength = 1e-12;

// CVODE's vector kernels on (q, q'): SUNDIALS' serial N_Vector operations, the same arithmetic
// case by case (so the same results to the bit), in this optimised build. The system's SUNDIALS
// (Debian's 6.4.1) has them compiled without optimisation (every operand through the stack,
// objdump of N_VWSqrSumLocal_Serial): they were 17 % of a PRB run (callgrind, bench_dynamics
// --models prb --no-reference). Only the operations CVODE calls on a serial vector without
// fused operations are replaced; clones (CVODE's own vectors) inherit them.
namespace fast_serial {
inline sunindextype len(N_Vector v) { return NV_LENGTH_S(v); }
inline sunrealtype* data(N_Vector v) { return NV_DATA_S(v); }

void linear_sum(sunrealtype a, N_Vector X, sunrealtype b, N_Vector Y, N_Vector Z) {
  const sunindextype n = len(X);
  const sunrealtype *x = data(X), *y = data(Y);
  sunrealtype* z = data(Z);
  // N_VLinearSum_Serial's cases, in its order.
  if (b == 1.0 && Z == Y) {  // y <- a x + y
    if (a == 1.0)
      for (sunindextype i = 0; i < n; ++i) z[i] += x[i];
    else if (a == -1.0)
      for (sunindextype i = 0; i < n; ++i) z[i] -= x[i];
    else
      for (sunindextype i = 0; i < n; ++i) z[i] += a * x[i];
    return;
  }
  if (a == 1.0 && Z == X) {  // x <- b y + x
    if (b == 1.0)
      for (sunindextype i = 0; i < n; ++i) z[i] += y[i];
    else if (b == -1.0)
      for (sunindextype i = 0; i < n; ++i) z[i] -= y[i];
    else
      for (sunindextype i = 0; i < n; ++i) z[i] += b * y[i];
    return;
  }
  if (a == 1.0 && b == 1.0) {
    for (sunindextype i = 0; i < n; ++i) z[i] = x[i] + y[i];
    return;
  }
  bool test;
  if ((test = (a == 1.0 && b == -1.0)) || (a == -1.0 && b == 1.0)) {
    const sunrealtype *v1 = test ? y : x, *v2 = test ? x : y;
    for (sunindextype i = 0; i < n; ++i) z[i] = v2[i] - v1[i];
    return;
  }
  if ((test = (a == 1.0)) || b == 1.0) {
    const sunrealtype c = test ? b : a;
    const sunrealtype *v1 = test ? y : x, *v2 = test ? x : y;
    for (sunindextype i = 0; i < n; ++i) z[i] = (c * v1[i]) + v2[i];
    return;
  }
  if ((test = (a == -1.0)) || b == -1.0) {
    const sunrealtype c = test ? b : a;
    const sunrealtype *v1 = test ? y : x, *v2 = test ? x : y;
    for (sunindextype i = 0; i < n; ++i) z[i] = (c * v1[i]) - v2[i];
    return;
  }
  if (a == b) {
    for (sunindextype i = 0; i < n; ++i) z[i] = a * (x[i] + y[i]);
    return;
  }
  if (a == -b) {
    for (sunindextype i = 0; i < n; ++i) z[i] = a * (x[i] - y[i]);
    return;
  }
  for (sunindextype i = 0; i < n; ++i) z[i] = (a * x[i]) + (b * y[i]);
}

void constant(sunrealtype c, N_Vector Z) {
  sunrealtype* z = data(Z);
  for (sunindextype i = 0, n = len(Z); i < n; ++i) z[i] = c;
}

void scale(sunrealtype c, N_Vector X, N_Vector Z) {
  const sunindextype n = len(X);
  const sunrealtype* x = data(X);
  sunrealtype* z = data(Z);
  if (Z == X) {
    for (sunindextype i = 0; i < n; ++i) z[i] *= c;
  } else if (c == 1.0) {
    for (sunindextype i = 0; i < n; ++i) z[i] = x[i];
  } else if (c == -1.0) {
    for (sunindextype i = 0; i < n; ++i) z[i] = -x[i];
  } else {
    for (sunindextype i = 0; i < n; ++i) z[i] = c * x[i];
  }
}

void absolute(N_Vector X, N_Vector Z) {
  const sunrealtype* x = data(X);
  sunrealtype* z = data(Z);
  for (sunindextype i = 0, n = len(X); i < n; ++i) z[i] = std::abs(x[i]);
}

void inverse(N_Vector X, N_Vector Z) {
  const sunrealtype* x = data(X);
  sunrealtype* z = data(Z);
  for (sunindextype i = 0, n = len(X); i < n; ++i) z[i] = 1.0 / x[i];
}

sunrealtype wsqrsum_local(N_Vector X, N_Vector W) {
  const sunrealtype *x = data(X), *w = data(W);
  sunrealtype sum = 0.0;
  for (sunindextype i = 0, n = len(X); i < n; ++i) {
    const sunrealtype p = x[i] * w[i];
    sum += p * p;
  }
  return sum;
}

sunrealtype wrms_norm(N_Vector X, N_Vector W) { return std::sqrt(wsqrsum_local(X, W) / len(X)); }

void install(N_Vector v) {
  v->ops->nvlinearsum = linear_sum;
  v->ops->nvconst = constant;
  v->ops->nvscale = scale;
  v->ops->nvabs = absolute;
  v->ops->nvinv = inverse;
  v->ops->nvwsqrsumlocal = wsqrsum_local;
  v->ops->nvwrmsnorm = wrms_norm;
}
}  // namespace fast_serial

// Throws InputError naming `robot.segments[i].tendons[k].stiffness` for a tendon that `a` drives
// by displacement and that has no stiffness (inextensible).
void require_elastic_driven(const Robot& robot, const Actuation& a) {
  if (a.kind == Actuation::Kind::Tensions && !a.mixed()) return;
  std::size_t g = 0;
  for (std::size_t i = 0; i < robot.segments.size(); ++i)
    for (std::size_t k = 0; k < robot.segments[i].tendons.size(); ++k, ++g) {
      if (g >= a.values.size() || a.kind_of(g) != Actuation::Kind::Displacements) continue;
      if (!robot.segments[i].tendons[k].stiffness)
        throw InputError("robot.segments[" + std::to_string(i) + "].tendons[" + std::to_string(k) + "].stiffness",
                         "absent (inextensible)",
                         "CCsub's and PRB's dynamics take a displacement-driven tendon only if it is elastic: its "
                         "tension is then EA / L_free times its stretch, a function of the shape; an inextensible one "
                         "is a constraint their equations of motion do not have (give its stiffness EA, or use VC "
                         "or VCref, which take inextensible tendons)");
    }
}
}  // namespace

void LumpedDynamics::check_displacement_input(const Timeline& timeline) const {
  for (const TimelineEntry& e : timeline.entries) require_elastic_driven(model_.robot(), e.input.actuation);
}

void LumpedDynamics::set_up_displacement_input(const ModelInput& input) {
  const Actuation& a = input.actuation;
  displacement_ = a.kind == Actuation::Kind::Displacements || a.mixed();
  driven_.clear();
  ea_over_l_.clear();
  if (!displacement_) return;
  require_elastic_driven(model_.robot(), a);
  const TendonRouting& routing = body_.statics.routing();
  const Robot& robot = model_.robot();
  std::vector<double> ea;
  for (const Segment& seg : robot.segments)
    for (const TendonSpec& spec : seg.tendons) ea.push_back(spec.stiffness ? *spec.stiffness : 0.0);
  const double EI = robot.backbone.effective_stiffness().EI;
  placeholder_.assign(a.values.size(), 0.0);
  for (std::size_t k = 0; k < a.values.size(); ++k) {
    if (a.kind_of(k) != Actuation::Kind::Displacements) continue;
    const RoutedTendon& t = routing.tendons[k];
    // L_k as the statics' DisplacementProblem and tendon::add_elastic_stretch take it: the free
    // length from the base to the end disk on the straight robot.
    const double L_free = physics::rest_length(t, 0.0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]);
    driven_.push_back(static_cast<int>(k));
    ea_over_l_.push_back(ea[k] / L_free);
    // Bound with a positive tension so that the model lets the tendon act (its tension is then
    // set per right-hand side): the statics' placeholder, EI / (r L_free).
    placeholder_[k] = EI / (std::max(t.r.norm(), 1e-12) * L_free);
  }
  driven_T_.setZero(static_cast<Eigen::Index>(driven_.size()));
  gap_.setZero(static_cast<Eigen::Index>(driven_.size()));
  root_dir_.assign(driven_.size(), 0);
  taut_.assign(driven_.size(), 0);
  pull_frames_.resize(N_ + 1);
  pull_base_.setZero(static_cast<Eigen::Index>(driven_.size()));
  pert_T_.setZero(static_cast<Eigen::Index>(driven_.size()));
  dd_.setZero(static_cast<Eigen::Index>(driven_.size()), n_);
  r_pert_.setZero(n_);
  u_.setZero(n_);
  tension_form_ = input;
  tension_form_.actuation.kind = Actuation::Kind::Tensions;
  tension_form_.actuation.kinds.clear();
}

bool LumpedDynamics::driven_tensions(const double* q) {
  if (!displacement_) return true;
  const TendonRouting& routing = body_.statics.routing();
  const Actuation::DisplacementConvention conv = input_.actuation.convention;
  const int nd = static_cast<int>(driven_.size());
  const double L = body_.length;
  double omega = 1.0, last_change = INFINITY, change = 0.0;
  for (int it = 0; it < kMaxTensionIterations; ++it) {
    // The backbone's compression under the current tensions, then the pulls of the paths at q.
    problem_->set_driven_tensions(driven_, driven_T_);
    const double* stretch = problem_->stretch();
    body_.compute_frames(q, N_, stretch, pull_frames_.data());
    change = 0.0;
    for (int i = 0; i < nd; ++i) {
      const int k = driven_[static_cast<std::size_t>(i)];
      const double d = tendon::chord_displacement(pull_frames_.data(), routing, k, conv);
      gap_[i] = input_.actuation.values[static_cast<std::size_t>(k)] - d;
      const double T = ea_over_l_[static_cast<std::size_t>(i)] * std::max(0.0, gap_[i]);
      if (!std::isfinite(T)) return false;
      change = std::max(change, std::abs(T - driven_T_[i]) / (ea_over_l_[static_cast<std::size_t>(i)] * L));
      driven_T_[i] += omega * (T - driven_T_[i]);
    }
    // Inextensible backbone: the pulls do not depend on the tensions, one pass is exact.
    if (!stretch || change <= kTensionFixedPointTol) break;
    // A stiff tendon on a compliant backbone overshoots (the compression lowers its pull): relax.
    if (change > 0.5 * last_change) omega *= 0.5;
    last_change = change;
  }
  problem_->set_driven_tensions(driven_, driven_T_);
  // Inextensible backbone: the one pass is exact, whatever it changed.
  return !problem_->stretch() || change <= kTensionFixedPointGiveUp;
}

bool LumpedDynamics::tendon_stiffness(const double* q) {
  // K += S dr/dT_k (dT_k/dq)^T for every taut driven tendon, dT_k/dq = -(EA_k / L_k) dd_k/dq:
  // dr/dT_k by a forward difference of the residual in T_k (one residual per taut tendon),
  // dd_k/dq by forward differences of the pulls (frames only, n of them). The Newton matrix of
  // a motor-driven robot then has the tendons' stiffness, which dominates the backbone's
  // bending for a stiff tendon (EA = 400 N on the paper robot: about 6 times).
  const TendonRouting& routing = body_.statics.routing();
  const Actuation::DisplacementConvention conv = input_.actuation.convention;
  const int nd = static_cast<int>(driven_.size());
  Eigen::Map<const Eigen::VectorXd> x(q, n_);
  const double* stretch = problem_->stretch();
  bool any = false;
  for (int i = 0; i < nd; ++i) any = any || driven_T_[i] > 0.0;
  if (!any) return true;
  // The pulls' derivatives (the frames at the current stretch; its own change with q is left out).
  qs_ = x;
  for (int i = 0; i < nd; ++i) pull_base_[i] = tendon::chord_displacement(frames_b_.data(), routing, driven_[static_cast<std::size_t>(i)], conv);
  constexpr double h = 1e-7;
  for (int c = 0; c < n_; ++c) {
    qs_[c] = q[c] + h;
    body_.compute_frames(qs_.data(), N_, stretch, pull_frames_.data());
    for (int i = 0; i < nd; ++i)
      dd_(i, c) = (tendon::chord_displacement(pull_frames_.data(), routing, driven_[static_cast<std::size_t>(i)], conv) -
                   pull_base_[i]) / h;
    qs_[c] = q[c];
  }
  for (int i = 0; i < nd; ++i) {
    const double T = driven_T_[i];
    if (!(T > 0.0)) continue;
    const double hT = 1e-6 * std::max(1.0, T);
    pert_T_ = driven_T_;
    pert_T_[i] = T + hT;
    problem_->set_driven_tensions(driven_, pert_T_);
    if (!problem_->residual(x, r_pert_)) return false;
    u_ = (r_pert_ - r_) / hT;  // dr/dT_i (r_: the residual at q, from the Jacobian's evaluation)
    // Map as the rows of K (S dr for CCsub; c dr, the phi row times a, for PRB).
    for (int j = 1; j <= N_; ++j) {
      const int r0 = m_ * (j - 1);
      if (m_ == 3) {
        const Vec3 w = S_[j] * u_.segment<3>(r0);
        u_.segment<3>(r0) = w;
      } else {
        u_.segment(r0, 5) *= body_.EI / length_[j];
        u_[r0 + 3] *= S_[j](0, 0);
      }
    }
    K_.noalias() -= ea_over_l_[static_cast<std::size_t>(i)] * u_ * dd_.row(i);
  }
  problem_->set_driven_tensions(driven_, driven_T_);
  last_valid_ = false;  // the problem's residual state is that of the differences
  return all_finite(K_);
}

double LumpedDynamics::tendon_energy() const {
  // Displacement (and mixed) input: the driven tendons' elastic energy (EA_k / 2 L_k) max(0,
  // delta_k - d_k)^2, and the given tensions' potential T_k times the path length as for tension
  // input (frames_b_ and gap_ of the current q).
  if (!displacement_) return 0.0;
  double U = 0.0;
  for (std::size_t i = 0; i < driven_.size(); ++i) {
    const double g = std::max(0.0, gap_[static_cast<Eigen::Index>(i)]);
    U += 0.5 * ea_over_l_[i] * g * g;
  }
  const TendonRouting& routing = body_.statics.routing();
  for (std::size_t k = 0; k < input_.actuation.values.size(); ++k)
    if (input_.actuation.kind_of(k) == Actuation::Kind::Tensions && input_.actuation.values[k] != 0.0)
      U += input_.actuation.values[k] * tendon::chord_length(frames_b_.data(), routing, static_cast<int>(k), 0);
  return U;
}

int LumpedDynamics::root_fn(sunrealtype t, N_Vector y, sunrealtype* g, void* user) {
  auto& s = *static_cast<LumpedDynamics*>(user);
  s.last_valid_ = false;  // the problem's tensions are set at this y now
  s.input_at(t);
  if (!s.driven_tensions(N_VGetArrayPointer(y))) return 1;
  // g_k = delta_k(t) - d_k(q): through zero where tendon k goes slack or taut (the kink of T_k),
  // shifted by the band away from the tendon's current mode.
  const double band = kEventBandOverLength * s.body_.length;
  for (Eigen::Index i = 0; i < s.gap_.size(); ++i)
    g[i] = s.gap_[i] + (s.taut_[static_cast<std::size_t>(i)] ? band : -band);
  return 0;
}


LumpedDynamics::LumpedDynamics(const LumpedModel& model, const LumpedBody& body, const DynamicsSettings& settings,
                               double dt, const SolverOptions& solver)
    : model_(model), body_(body), settings_(settings), dt_(dt), m_(body.per_subsegment), N_(body.N), n_(m_ * N_) {
  settings.validate();
  const Robot& robot = model.robot();
  const double mu = robot.backbone.linear_mass();
  // Disks: their own mass, on the routing's disk list (segment by segment).
  mass_.assign(N_ + 1, 0.0);
  inertia_.assign(N_ + 1, Vec3::Zero());
  air_length_.assign(N_ + 1, 0.0);
  length_.assign(N_ + 2, 0.0);
  for (int j = 1; j <= N_; ++j) length_[j] = body.statics.length(j);
  double disk_mass_total = 0.0, hole_radius = 0.0;
  for (const RoutedTendon& t : body.statics.routing().tendons) hole_radius = std::max(hole_radius, physics::max_offset(t));
  int k = 1;
  for (const Segment& s : robot.segments)
    for (int d = 0; d < s.disks && k <= N_; ++d, ++k) {
      mass_[k] = s.disk_mass;
      disk_mass_total += s.disk_mass;
      // A thin disk out to the tendon holes (the robot gives no disk radius).
      const double r2 = hole_radius * hole_radius;
      inertia_[k] = s.disk_mass * Vec3(r2 / 4.0, r2 / 4.0, r2 / 2.0);
    }
  if (!(mu > 0.0) && !(disk_mass_total > 0.0))
    throw InputError("robot.backbone.density", format_value(robot.backbone.density),
                     "a moving robot needs mass: give robot.backbone.density (or mass_per_length) or the disks' "
                     "disk_mass");
  // The backbone: half of each subsegment at each of its disks (the half at the base disk does
  // not move), with the rotary inertia of the section and of the half-length about the disk.
  const double ro = robot.backbone.outer_radius, ri = robot.backbone.inner_radius;
  const double rg2 = 0.25 * (ro * ro + ri * ri);
  links_ = m_ == 5;
  link_mass_.assign(kLinks * (N_ + 1), 0.0);
  link_c_.assign(kLinks * (N_ + 1), Vec3::Zero());
  for (auto& st : link_stencil_) st.assign(kLinks * (N_ + 1), Vec3::Zero());
  link_J_.assign(kLinks * (N_ + 1), Eigen::Matrix<double, 3, 5>::Zero());
  link_J_step_ = link_J_;
  tv_step_.assign(N_ + 1, Vec6::Zero());
  ljv_step_.assign(kLinks * (N_ + 1), Vec3::Zero());
  link_U_.assign(links_ ? N_ + 1 : 0, Eigen::Matrix<double, 6, 5>::Zero());
  link_D_.assign(links_ ? N_ + 1 : 0, Eigen::Matrix<double, 5, 5>::Zero());
  link_I_.assign(links_ ? N_ + 1 : 0, Mat6::Zero());
  const PrbParameters& prb = model.effects().prb;
  const double gsum = prb.gamma[0] + prb.gamma[1] + prb.gamma[2] + prb.gamma[3];
  for (int j = 1; j <= N_; ++j) {
    for (int side : {j - 1, j}) {
      if (side == 0) continue;
      const double h = 0.5 * length_[j], mh = mu * h;
      // The section's rotary inertia always; CCsub: the half-length's mass and its rotary inertia
      // about the disk too.
      inertia_[side] += Vec3(mh * rg2, mh * rg2, 2.0 * mh * rg2);
      if (!links_) {
        mass_[side] += mh;
        inertia_[side] += Vec3(mh * h * h / 3.0, mh * h * h / 3.0, 0.0);
      }
      air_length_[side] += h;
    }
    if (links_)
      for (int i = 0; i < kLinks; ++i) link_mass_[kLinks * j + i] = mu * length_[j] * prb.gamma[i] / gsum;
  }
  if (links_)
    for (int i = 0; i < kLinks; ++i) {
      const unsigned mask = body.link_unknowns(i);
      for (int c = 0; c < m_; ++c)
        if (mask & (1u << c)) link_cols_[i][link_ncols_[i]++] = c;
    }
  // Accuracy (docs/dynamics.md, "Accuracy"): CVODE's absolute tolerance on q is the tip
  // tolerance as an angle, tip_tolerance / L; on q' that over the output step. A scene without
  // its own solver.tip_tolerance (0) gets the dynamics' default kDynamicsTipToleranceOverLength L,
  // not the statics' (1e-7 L): on the paper robot's tension step (bench_dynamics) that keeps the
  // tip within 2-4 mm of a converged run, below the Cosserat models' own time discretisation
  // error at dt = 1/60 s (1.7 cm), at 1/3 (CCsub) to 1/4 (PRB) of the CVODE steps of 1e-7 L.
  // The relative tolerance is solver.cvode_rtol as given.
  const double L = body.length;
  const double tip_tol = solver.tip_tolerance > 0.0 ? solver.tip_tolerance : kDynamicsTipToleranceOverLength * L;
  rtol_ = std::max(solver.cvode_rtol, 1e-12);
  atol_q_ = tip_tol / L;
  atol_v_ = atol_q_ / std::max(dt_, 1e-6);

  problem_ = body.make_problem();
  {
    const std::vector<double> zero(m_, 0.0);
    SubsegmentPose g;
    SubsegmentRates d;
    rates_ = body.local_rates(1, zero.data(), g, d);
  }
  frames_.resize(N_ + 1);
  frames_b_.resize(N_ + 1);
  poses_.resize(N_ + 1);
  frames_q_.resize(N_ + 1);
  poses_q_.resize(N_ + 1);
  T_.setZero(6, n_);
  Tp_.setZero(6, n_);
  r_.setZero(n_);
  Q_.setZero(n_);
  rhs_.setZero(n_);
  damp_.setZero(n_);
  q_.setZero(n_);
  v_.setZero(n_);
  qs_.setZero(n_);
  S_.assign(N_ + 1, Mat3::Zero());
  last_y_.setZero(2 * n_);
  damp_const_.setZero(n_);
  pbody_.assign(N_ + 1, Vec6::Zero());
  aba3_.size(N_);
  aba5_.size(N_);
  for (int i = 0; i < n_; ++i) damp_const_[i] = settings_.bending_damping_time * spring(i, q_.data());
  schur_b_.setZero(n_);
  Kd_.setZero(m_, n_);
  chain_b_.setZero(n_);
  chain3_.size(N_);
  chain5_.size(N_);
  IC_.assign(N_ + 2, Mat6::Zero());
  Io_.assign(N_ + 1, Mat6::Zero());
  V_.assign(N_ + 1, Vec6::Zero());
  A_.assign(N_ + 1, Vec6::Zero());
}

void LumpedDynamics::size_dense() {
  if (M_.rows() == n_) return;
  M_.setZero(n_, n_);
  Jr_.setZero(n_, n_);
  K_.setZero(n_, n_);
  schur_.setZero(n_, n_);
  schur_A21_.setZero(n_, n_);
  schur_M_.setZero(n_, n_);
  schur_lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n_);
}

void LumpedDynamics::free_cvode() {
  if (cvode_) CVodeFree(&cvode_);
  if (ls_) SUNLinSolFree(ls_);
  if (A_mat_) SUNMatDestroy(A_mat_);
  if (y_) N_VDestroy(y_);
  if (abstol_) N_VDestroy(abstol_);
  if (ele_) N_VDestroy(ele_);
  if (ewt_) N_VDestroy(ewt_);
  ele_ = nullptr, ewt_ = nullptr;
  if (ctx_) SUNContext_Free(&ctx_);
  cvode_ = nullptr, ls_ = nullptr, A_mat_ = nullptr, y_ = nullptr, abstol_ = nullptr, ctx_ = nullptr;
}

void LumpedDynamics::input_at(double t) {
  if (timeline_) timeline_->at(t, input_);
  if (displacement_) {
    // The problem is bound with the tension form: the driven tendons' placeholders, the given
    // tensions and the loads (a displacement ramp alone binds nothing anew).
    tension_form_.loads = input_.loads;
    for (std::size_t k = 0; k < input_.actuation.values.size(); ++k)
      tension_form_.actuation.values[k] =
          input_.actuation.kind_of(k) == Actuation::Kind::Displacements ? placeholder_[k] : input_.actuation.values[k];
  }
  const ModelInput& in = displacement_ ? tension_form_ : input_;
  if (bound_valid_ && in.actuation.values == bound_.actuation.values && in.loads.tip_force == bound_.loads.tip_force &&
      in.loads.tip_moment == bound_.loads.tip_moment && in.loads.gravity == bound_.loads.gravity)
    return;
  // A new input (every right-hand side along a ramp): binding resolves its loads in place, the
  // buffers keep their sizes (tests/test_dynamics_lumped.cpp, RampAllocatesNothing).
  problem_->bind_all(in);
  problem_->set_parameter(1.0);
  bound_ = in;
  bound_valid_ = true;
}

int LumpedDynamics::rhs_fn(sunrealtype t, N_Vector y, N_Vector yd, void* user) {
  auto& s = *static_cast<LumpedDynamics*>(user);
  const double* yv = N_VGetArrayPointer(y);
  double* d = N_VGetArrayPointer(yd);
  const int n = s.n_;
  const double* q = yv;
  const double* v = yv + n;
  s.last_valid_ = false;
  s.input_at(t);
  if (!s.driven_tensions(q)) return 1;  // displacement input: T_k(q, t) of the elastic tendons
  s.twists(q, s.T_);
  if (!s.generalized_force(q)) return 1;  // recoverable: CVODE retries a smaller step
  s.body_inertias();  // no M: the accelerations by the articulated-body algorithm
  s.bias(q, v);
  Eigen::Map<const Eigen::VectorXd> vv(v, n);
  // D = tau_bt K: constant but for PRB's phi rows (their stiffness grows with the bend a^2).
  s.damp_ = s.damp_const_;
  if (s.m_ == 5)
    for (int j = 0; j < s.N_; ++j) s.damp_[5 * j + 3] = s.settings_.bending_damping_time * s.spring(5 * j + 3, q);
  Eigen::Map<Eigen::VectorXd> dq(d, n), dv(d + n, n);
  dq = vv;
  s.rhs_ = s.Q_ - s.damp_.cwiseProduct(vv);  // the velocity products are the bodies' (pbody_)
  s.articulated(dv);
  if (!all_finite(dv)) return 1;
  s.last_valid_ = true;
  s.last_t_ = t;
  s.last_y_ = Eigen::Map<const Eigen::VectorXd>(yv, 2 * n);
  return 0;
}

int LumpedDynamics::jac_fn(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector tmp1,
                           N_Vector, N_Vector) {
  (void)fy;
  auto& s = *static_cast<LumpedDynamics*>(user);
  const int n = s.n_;
  const double* q = N_VGetArrayPointer(y);
  // Every buffer at this y: CVODE's setups usually come right after the right-hand side at the
  // same (t, y) (its prediction), otherwise it is evaluated again here.
  Eigen::Map<const Eigen::VectorXd> yy(q, 2 * n);
  if (!(s.last_valid_ && t == s.last_t_ && yy == s.last_y_) && rhs_fn(t, y, tmp1, user) != 0) return 1;
  Eigen::Map<const Eigen::VectorXd> x(q, n);
  NewtonMatrix& nm = *static_cast<NewtonMatrix*>(J->content);
  if (s.chain_) {
    // K's diagonal blocks only (the rows as below, block by block), and what chain_factor()
    // needs at q: the right-hand side's twists, inertias and links. No M: the factorisation
    // holds it implicitly. Leaving out K's blocks off the diagonal (a subsegment's law against
    // the distal shape: the tendon forces' moment arms, a few % of the springs on the paper
    // robot) left CVODE's Newton iterations and failures as they were with the dense K
    // (bench_dynamics, PRB: 410 iterations, 27 failures, 267 steps against 405, 27, 264).
    // Every step's Newton matrix (PRB, initialize()): K's blocks from the statics' differences
    // every kChainStiffnessEvery Jacobians and after a convergence failure, M at every one.
    long fails = 0;
    CVodeGetNumNonlinSolvConvFails(s.cvode_, &fails);
    if (s.kd_age_ < 0 || s.kd_age_ >= kChainStiffnessEvery || fails != s.kd_fails_) {
      s.kd_age_ = 0;
      if (!s.problem_->diagonal_jacobian(x, s.r_, s.Kd_)) return 1;
      for (int j = 1; j <= s.N_; ++j) {
        const double c = s.body_.EI / s.length_[j];
        const int r0 = s.m_ * (j - 1);
        if (s.m_ == 3) {
          const Mat3 B = s.S_[j] * s.Kd_.middleCols<3>(r0);
          s.Kd_.middleCols<3>(r0) = B;
        } else {
          auto B = s.Kd_.middleCols<5>(r0);
          B *= c;
          B.row(3) *= s.S_[j](0, 0);
          const double* v = q + n;
          const double a = s.S_[j](0, 0);
          const double kd = s.settings_.bending_damping_time * s.model_.effects().prb.k_theta[1] * c * 2.0 * a * v[r0 + 3];
          for (int i = 0; i < 3; ++i) B(3, i) += c * s.r_[r0 + 3] + kd;
        }
      }
    }
    s.kd_fails_ = fails;
    ++s.kd_age_;
    // Moved, not copied: the next right-hand side computes the twists, inertias and links anew
    // (and no buffer of this y is reused: last_valid_).
    nm.T.swap(s.T_);
    nm.Io.swap(s.Io_);
    nm.link_U.swap(s.link_U_);
    nm.link_D.swap(s.link_D_);
    nm.link_I.swap(s.link_I_);
    s.last_valid_ = false;
    nm.Kd = s.Kd_;  // (kept: computed anew only every kChainStiffnessEvery Jacobians)
    nm.D = s.damp_;
    nm.gamma = 0.0;
    nm.scaled = false;
    return all_finite(nm.Kd) ? 0 : 1;
  }
  s.mass_matrix();  // the right-hand side forms no M
  if (!s.problem_->jacobian(x, s.r_, s.Jr_)) return 1;
  // dQ/dq ~ -S dr/dq (S's own derivative meets r, zero at every equilibrium); d(b)/d(q, q') and
  // dM/dq are left out: the Newton matrix of a modified Newton iteration.
  for (int j = 1; j <= s.N_; ++j) {
    const double c = s.body_.EI / s.length_[j];
    const int r0 = s.m_ * (j - 1);
    if (s.m_ == 3) {
      s.K_.middleRows(r0, 3).noalias() = s.S_[j] * s.Jr_.middleRows(r0, 3);
    } else {
      s.K_.middleRows(r0, 5) = c * s.Jr_.middleRows(r0, 5);
      s.K_.row(r0 + 3) *= s.S_[j](0, 0);
      // The phi row is Q_phi = -c a r_phi (a = theta_1 + theta_2 + theta_3): its factor's own
      // derivative meets r_phi, which is not zero in motion; and its damping tau K_Theta c a^2 v_phi.
      const double* v = q + n;
      const double a = s.S_[j](0, 0);
      const double kd = s.settings_.bending_damping_time * s.model_.effects().prb.k_theta[1] * c * 2.0 * a * v[r0 + 3];
      for (int i = 0; i < 3; ++i) s.K_(r0 + 3, r0 + i) += c * s.r_[r0 + 3] + kd;
    }
  }
  if (s.displacement_ && !s.tendon_stiffness(q)) return 1;
  nm.M = s.M_;
  nm.K = s.K_;
  nm.D = s.damp_;
  nm.gamma = 0.0;
  nm.scaled = false;
  return all_finite(nm.M) && all_finite(nm.K) ? 0 : 1;
}

// The Jacobian of (q, v)' = (v, M^-1 (Q - D v - b)) without M's and b's own derivatives is
// J = [0 I; -M^-1 K, -M^-1 D]: a NewtonMatrix keeps M, K and D (n x n, n x n, n) instead of the
// dense 2n x 2n J, and CVODE's A = I - gamma J as gamma alone (CVODE copies and scales it between
// steps: on the dense 2n x 2n matrix those copies took 14 % of a run, perf, bench_dynamics).
SUNMatrix LumpedDynamics::make_newton_matrix(SUNContext ctx, const LumpedDynamics* owner) {
  SUNMatrix A = SUNMatNewEmpty(ctx);
  if (!A) return nullptr;
  auto* c = new NewtonMatrix;
  const int n = owner->n_;
  c->owner = owner;
  c->D.setZero(n);
  if (owner->chain_) {
    c->T.setZero(6, n);
    c->Kd.setZero(owner->m_, n);
    c->Io.assign(owner->Io_.size(), Mat6::Zero());
    c->link_U = owner->link_U_;
    c->link_D = owner->link_D_;
    c->link_I = owner->link_I_;
  } else {
    c->M.setZero(n, n);
    c->K.setZero(n, n);
  }
  A->content = c;
  A->ops->getid = [](SUNMatrix) { return SUNMATRIX_CUSTOM; };
  A->ops->clone = [](SUNMatrix A) -> SUNMatrix {
    return make_newton_matrix(A->sunctx, static_cast<NewtonMatrix*>(A->content)->owner);
  };
  A->ops->destroy = [](SUNMatrix A) {
    delete static_cast<NewtonMatrix*>(A->content);
    A->content = nullptr;
    SUNMatFreeEmpty(A);
  };
  // CVODE zeroes the matrix right before jac_fn, which sets every block of its form (chain or
  // dense): only the scaling is reset here (zeroing the blocks was 2 % of a PRB run, callgrind,
  // bench_dynamics --models prb --no-reference).
  A->ops->zero = [](SUNMatrix A) -> int {
    auto& c = *static_cast<NewtonMatrix*>(A->content);
    c.gamma = 0.0;
    c.scaled = false;
    return 0;
  };
  A->ops->copy = [](SUNMatrix A, SUNMatrix B) -> int {
    *static_cast<NewtonMatrix*>(B->content) = *static_cast<const NewtonMatrix*>(A->content);
    return 0;
  };
  // A = c A + I: CVODE's c = -gamma on a fresh copy of J.
  A->ops->scaleaddi = [](sunrealtype c, SUNMatrix A) -> int {
    auto& m = *static_cast<NewtonMatrix*>(A->content);
    if (m.scaled) return -1;
    m.gamma = -c;
    m.scaled = true;
    return 0;
  };
  return A;
}

// CVODE's Newton systems (I - gamma J) x = b with J = [0 I; -M^-1 K, -M^-1 D]: the first block
// row gives x1 = b1 + gamma x2, and the second, times M, (M + gamma D + gamma^2 K) x2 =
// M b2 - gamma K b1: one n x n LU (Eigen's, blocked) of M, D, K as the model has them, no
// inverse of M and no 2n x 2n matrix (SUNDIALS' unblocked 2n x 2n LU took 57 % of a CCsub run,
// perf, bench_dynamics). The chain form (chain_, tension and load input) factors
// M + gamma D + gamma^2 blockdiag(K) by the articulated-body algorithm instead, O(N): on PRB's
// n = 100 the dense LU and the copies of M and K were a quarter of a run (callgrind,
// bench_dynamics --models prb --no-reference: 361 M instructions, 223 M with the chain form).
SUNLinearSolver LumpedDynamics::make_schur_solver() {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx_);
  if (!S) throw std::runtime_error("lumped dynamics: SUNLinSolNewEmpty failed");
  S->content = this;
  S->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  S->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  S->ops->setup = [](SUNLinearSolver ls, SUNMatrix A) -> int {
    auto& d = *static_cast<LumpedDynamics*>(ls->content);
    const NewtonMatrix& m = *static_cast<const NewtonMatrix*>(A->content);
    const double g = m.scaled ? m.gamma : 0.0;
    d.schur_gamma_ = g;
    if (d.chain_) {
      d.chain_nm_ = &m;
      return (d.m_ == 3 ? d.chain_factor<3>(m, g) : d.chain_factor<5>(m, g)) ? 0 : 1;
    }
    d.schur_A21_ = m.K;  // K and M of this Newton matrix, for solve()
    d.schur_M_ = m.M;
    d.schur_ = m.M + (g * g) * m.K;
    d.schur_.diagonal() += g * m.D;
    d.schur_lu_.compute(d.schur_);
    // A singular or non-finite block: recoverable, CVODE retries with a smaller step.
    // (The pivots, not rcond(): its estimate allocates.)
    const double pivot = d.schur_lu_.matrixLU().diagonal().cwiseAbs().minCoeff();
    return pivot > 0.0 && all_finite(d.schur_) ? 0 : 1;
  };
  S->ops->solve = [](SUNLinearSolver ls, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) -> int {
    auto& d = *static_cast<LumpedDynamics*>(ls->content);
    const int n = d.n_;
    Eigen::Map<const Eigen::VectorXd> bb(N_VGetArrayPointer(b), 2 * n);
    Eigen::Map<Eigen::VectorXd> xx(N_VGetArrayPointer(x), 2 * n);
    if (d.chain_) {
      // x2 = b2 + z with (M + gamma D + gamma^2 K) z = -gamma (D b2 + K (b1 + gamma b2)): no
      // product with M (the chain factors hold it only implicitly).
      const double g = d.schur_gamma_;
      if (d.m_ == 3)
        d.chain_solve<3>(bb.data(), g);
      else
        d.chain_solve<5>(bb.data(), g);
      xx.tail(n) = bb.tail(n) - g * d.chain_b_;
      xx.head(n) = bb.head(n) + g * xx.tail(n);
      return all_finite(xx) ? 0 : 1;
    }
    d.schur_b_.noalias() = d.schur_M_ * bb.tail(n);
    d.schur_b_.noalias() -= d.schur_gamma_ * (d.schur_A21_ * bb.head(n));
    xx.tail(n) = d.schur_lu_.solve(d.schur_b_);
    xx.head(n) = bb.head(n) + d.schur_gamma_ * xx.tail(n);
    return all_finite(xx) ? 0 : 1;
  };
  S->ops->free = [](SUNLinearSolver ls) -> int {
    ls->content = nullptr;
    SUNLinSolFreeEmpty(ls);
    return 0;
  };
  return S;
}

void LumpedDynamics::initialize(const Solution& at_rest, const ModelInput& input) {
  if (!at_rest.converged()) throw InputError("timeline[0]", "", "the static answer at t = 0 did not converge");
  if (at_rest.unknowns.size() != n_)
    throw InputError("unknowns", std::to_string(at_rest.unknowns.size()), "not a static answer of this model");
  timeline_ = nullptr;
  input_ = input;
  bound_valid_ = false;
  last_valid_ = false;
  set_up_displacement_input(input);
  input_at(0.0);
  // The rest shape's tensions as the fixed point's start.
  if (displacement_)
    for (std::size_t i = 0; i < driven_.size(); ++i)
      if (static_cast<std::size_t>(driven_[i]) < at_rest.tensions.size())
        driven_T_[static_cast<Eigen::Index>(i)] = at_rest.tensions[static_cast<std::size_t>(driven_[i])];
  Eigen::VectorXd y0(2 * n_);
  y0.head(n_) = at_rest.unknowns;
  y0.tail(n_).setZero();
  // PRB's gauge references (the bending planes of straight subsegments) from the rest shape.
  Eigen::VectorXd ignored;
  problem_->warm_guess(at_rest, ignored);
  q_ = at_rest.unknowns;
  v_.setZero();
  t_ = 0.0;
  free_cvode();
  check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
  y_ = N_VNew_Serial(2 * n_, ctx_);
  abstol_ = N_VNew_Serial(2 * n_, ctx_);
  ele_ = N_VNew_Serial(2 * n_, ctx_);
  ewt_ = N_VNew_Serial(2 * n_, ctx_);
  if (!y_ || !abstol_ || !ele_ || !ewt_) throw std::runtime_error("lumped dynamics: N_VNew_Serial failed");
  for (N_Vector v : {y_, abstol_, ele_, ewt_}) fast_serial::install(v);
  std::copy(y0.data(), y0.data() + 2 * n_, N_VGetArrayPointer(y_));
  double* at = N_VGetArrayPointer(abstol_);
  for (int i = 0; i < n_; ++i) at[i] = atol_q_, at[n_ + i] = atol_v_;
  cvode_ = CVodeCreate(CV_BDF, ctx_);
  if (!cvode_) throw std::runtime_error("lumped dynamics: CVodeCreate failed");
  check(CVodeInit(cvode_, &rhs_fn, 0.0, y_), "CVodeInit");
  check(CVodeSetErrHandlerFn(cvode_, &on_error, this), "CVodeSetErrHandlerFn");
  check(CVodeSetUserData(cvode_, this), "CVodeSetUserData");
  check(CVodeSVtolerances(cvode_, rtol_, abstol_), "CVodeSVtolerances");
  // Per output step: a step that needs more has met a singularity (e.g. a CCsub subsegment bent
  // to 90 deg, where its twist law degenerates), not a hard stretch of motion.
  check(CVodeSetMaxNumSteps(cvode_, kMaxStepsPerOutput), "CVodeSetMaxNumSteps");
  chain_ = !displacement_;
  if (!chain_) size_dense();
  A_mat_ = make_newton_matrix(ctx_, this);
  ls_ = make_schur_solver();
  if (!A_mat_ || !ls_) throw std::runtime_error("lumped dynamics: dense matrix or solver creation failed");
  check(CVodeSetLinearSolver(cvode_, ls_, A_mat_), "CVodeSetLinearSolver");
  if (problem_->has_jacobian()) check(CVodeSetJacFn(cvode_, &jac_fn), "CVodeSetJacFn");
  kd_age_ = -1;
  if (chain_ && m_ == 5) {
    // PRB: a Newton matrix at every step (the chain form's setup is O(N)). Its bending-plane
    // rows' inertia and stiffness grow with the bend squared, so near straight they change
    // within a few steps: with CVODE's reuse (setup every 20 steps or on a gamma change, a
    // Jacobian every 51 or after a failure) 27 convergence failures, 267 steps, 413 right-hand
    // sides on the paper robot's tension step (bench_dynamics); with a fresh M at every step
    // and K's blocks every kChainStiffnessEvery steps none, 205 steps, 263 right-hand sides.
    // CCsub converges with the reuse (1.05 Newton iterations per step) and keeps it.
    check(CVodeSetLSetupFrequency(cvode_, 1), "CVodeSetLSetupFrequency");
    check(CVodeSetJacEvalFrequency(cvode_, 1), "CVodeSetJacEvalFrequency");
  }
  // Slack events: CVODE's root finding on g_k = delta_k(t) - d_k(q) stops the integration at the
  // kink of T_k (advance() restarts it there), so that no step straddles a tendon going slack or taut.
  if (displacement_) {
    driven_tensions(q_.data());
    for (std::size_t i = 0; i < driven_.size(); ++i) taut_[i] = gap_[static_cast<Eigen::Index>(i)] > 0.0;
    last_valid_ = false;
    check(CVodeRootInit(cvode_, static_cast<int>(driven_.size()), &root_fn), "CVodeRootInit");
    check(CVodeSetNoInactiveRootWarn(cvode_), "CVodeSetNoInactiveRootWarn");
    // The taut tendons add stiffness that the backbone's Kelvin-Voigt damping barely damps: at the
    // default tolerance BDF orders 3-5 (not A-stable) kept such a mode ringing (CCsub, the motor
    // example: tip +-1.3 mm at 2 s); stability limit detection lowers the order there (settled, 292
    // CVODE steps instead of 351).
    check(CVodeSetStabLimDet(cvode_, SUNTRUE), "CVodeSetStabLimDet");
  }
  cvode_ready_ = true;
}

SimulationStep LumpedDynamics::advance(double t_next, const Timeline& timeline) {
  if (!cvode_ready_) throw std::logic_error("lumped dynamics: advance() before initialize()");
  if (timeline_ != &timeline) check_displacement_input(timeline);
  timeline_ = &timeline;
  if (!chart_chosen_) choose_bending_planes(timeline);
  SimulationStep step;
  long steps = 0;  // summed per CVode call: CVodeReInit (at timeline entries) resets the count
  int flag = CV_SUCCESS;
  while (t_ < t_next) {
    // Stop at the timeline's entries: the input's slope jumps there, and CVODE restarts. Output
    // times are no stops: CVODE steps past them and interpolates (its steps follow the motion,
    // not the output step).
    double entry = INFINITY;
    for (const TimelineEntry& e : timeline.entries)
      if (e.t > t_ * (1.0 + 1e-14) + 1e-300 && e.t < entry) entry = e.t;
    const bool to_entry = entry <= t_next;
    const double stop = to_entry ? entry : t_next;
    check(CVodeSetStopTime(cvode_, std::isfinite(entry) ? entry : 1e300), "CVodeSetStopTime");
    sunrealtype reached = t_;
    cvode_message_.clear();
    long n0 = 0, n1 = 0;
    CVodeGetNumSteps(cvode_, &n0);
    flag = CVode(cvode_, stop, y_, &reached, CV_NORMAL);
    CVodeGetNumSteps(cvode_, &n1);
    steps += n1 - n0;
    if (flag < 0) {
      t_ = reached;
      break;
    }
    t_ = reached;
    if (flag == CV_ROOT_RETURN) {
      // A driven tendon went slack or taut: its mode flips, and CVODE restarts at the kink of
      // its tension (below, if the root is the stop itself).
      step.tendon_events.push_back(t_);
      check(CVodeGetRootInfo(cvode_, root_dir_.data()), "CVodeGetRootInfo");
      for (std::size_t i = 0; i < root_dir_.size(); ++i)
        if (root_dir_[i] != 0) taut_[i] = !taut_[i];
      if (t_ < stop) {
        check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
        continue;
      }
      if (!to_entry) check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
    }
    if (t_ >= stop) {
      t_ = stop;
      if (to_entry) check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
    }
  }
  const double* yv = N_VGetArrayPointer(y_);
  q_ = Eigen::Map<const Eigen::VectorXd>(yv, n_);
  v_ = Eigen::Map<const Eigen::VectorXd>(yv + n_, n_);
  step.iterations = static_cast<int>(steps);
  step.t = flag < 0 ? t_ : t_next;
  // CVODE's weighted local error of its last step (RMS norm; below 1 when accepted).
  if (CVodeGetEstLocalErrors(cvode_, ele_) == CV_SUCCESS && CVodeGetErrWeights(cvode_, ewt_) == CV_SUCCESS)
    step.residual = N_VWrmsNorm(ele_, ewt_);
  step.status = flag < 0 ? TerminationType::IntegrationFailed : TerminationType::Converged;
  // Energies and the tip at the reached state (the buffers are no longer those of CVODE's last
  // right-hand side).
  last_valid_ = false;
  input_at(step.t);
  driven_tensions(q_.data());
  step.kinetic_energy = kinetic_energy(q_.data(), v_.data());
  step.potential_energy = potential_energy(q_.data()) + tendon_energy();
  step.tip = frames_b_[N_];
  if (displacement_) {
    // The step's tensions: the driven ones computed (exactly 0 when slack), the rest as given;
    // the tendon displacements as the statics report them (the path's pull plus the stretch).
    const std::size_t m = input_.actuation.values.size();
    step.tensions.assign(m, 0.0);
    for (std::size_t k = 0; k < m; ++k)
      if (input_.actuation.kind_of(k) == Actuation::Kind::Tensions) step.tensions[k] = input_.actuation.values[k];
    for (std::size_t i = 0; i < driven_.size(); ++i)
      step.tensions[static_cast<std::size_t>(driven_[i])] = driven_T_[static_cast<Eigen::Index>(i)];
    step.tendon_displacements = tendon::chord_displacements(frames_b_, body_.statics.routing(), input_.actuation.convention);
    tendon::add_elastic_stretch(model_.robot(), body_.statics.routing(), step.tensions, step.tendon_displacements);
  }
  return step;
}

double LumpedDynamics::potential_energy() {
  input_at(t_);
  driven_tensions(q_.data());
  twists_along(q_.data(), v_.data());  // the frames and link points at q
  return potential_energy(q_.data()) + tendon_energy();
}

void LumpedDynamics::choose_bending_planes(const Timeline& timeline) {
  chart_chosen_ = true;
  last_valid_ = false;
  if (m_ != 5) return;
  double* y = N_VGetArrayPointer(y_);
  std::vector<bool> open(N_ + 1, false);
  bool any = false;
  for (int j = 1; j <= N_; ++j) {
    const double* x = y + m_ * (j - 1);
    open[j] = std::abs(x[0]) + std::abs(x[1]) + std::abs(x[2]) < 1e-12;
    any = any || open[j];
  }
  if (!any) return;
  std::unique_ptr<ModelWorkspace> ws = model_.make_workspace();
  for (const TimelineEntry& e : timeline.entries) {
    const Solution s = solve(model_, *ws, e.input);
    if (!s.converged()) continue;
    for (int j = 1; j <= N_; ++j) {
      const double* x = s.unknowns.data() + m_ * (j - 1);
      if (open[j] && std::abs(x[0]) + std::abs(x[1]) + std::abs(x[2]) > 1e-9) {
        y[m_ * (j - 1) + 3] = x[3];
        open[j] = false;
      }
    }
  }
  // Subsegments no static answer bends (e.g. a segment without pulled tendons, swung by the
  // others): the plane of the nearest bent subsegment, proximal first, so that a planar motion
  // stays in one plane (its straight subsegments would otherwise swing through straight by
  // turning phi, the singular way).
  std::vector<double> phi(N_ + 1, 0.0);
  std::vector<bool> set(N_ + 1, false);
  for (int j = 1; j <= N_; ++j) set[j] = !open[j], phi[j] = y[m_ * (j - 1) + 3];
  for (int j = 1; j <= N_; ++j) {
    if (set[j]) continue;
    for (int d = 1; d < N_; ++d) {
      if (j - d >= 1 && set[j - d]) {
        y[m_ * (j - 1) + 3] = phi[j - d];
        break;
      }
      if (j + d <= N_ && set[j + d]) {
        y[m_ * (j - 1) + 3] = phi[j + d];
        break;
      }
    }
  }
  Solution chart;
  chart.unknowns = Eigen::Map<const Eigen::VectorXd>(y, n_);
  Eigen::VectorXd ignored;
  problem_->warm_guess(chart, ignored);  // the gauge references follow
  check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
}

Solution LumpedDynamics::shape() const {
  Solution s;
  s.unknowns = q_;
  s.disk_frames = body_.disk_frames(q_, problem_->stretch());
  s.summary.termination = TerminationType::Converged;
  return s;
}

std::unique_ptr<DynamicsIntegrator> make_lumped_dynamics(const LumpedModel& model, const LumpedBody& body,
                                                         const DynamicsSettings& settings, double dt,
                                                         const SolverOptions& solver) {
  return std::make_unique<LumpedDynamics>(model, body, settings, dt, solver);
}

Eigen::VectorXd lumped_natural_frequencies(const LumpedModel& model, const LumpedBody& body, const Eigen::VectorXd& x,
                                           const ModelInput& input) {
  LumpedDynamics d(model, body, DynamicsSettings{}, 1.0, SolverOptions{});
  return d.frequencies(x, input);
}

}  // namespace tdcr::detail

namespace tdcr {

std::unique_ptr<DynamicsIntegrator> LumpedModel::make_dynamics_integrator(const DynamicsSettings& settings, double dt,
                                                                          const SolverOptions& solver) const {
  return detail::make_lumped_dynamics(*this, body(), settings, dt, solver);
}

Eigen::VectorXd LumpedModel::natural_frequencies(const Eigen::VectorXd& x, const ModelInput& input) const {
  return detail::lumped_natural_frequencies(*this, body(), x, input);
}

}  // namespace tdcr
