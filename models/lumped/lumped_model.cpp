// The common base of CCsub and PRB (lumped_model.hpp): workspace, binding, guesses, outputs, the
// recursive formulation (the banded one is in lumped_banded.cpp).
#include "tdcr/models/lumped_model.hpp"

#include <cmath>

#include "lumped/lumped_problem.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
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
  residual_changed();
  body_.statics.bind(input, loads_);
  convention_ = input.actuation.convention;
  banded_ = body_.banded();
  reduced_ = body_.reduced(active());
  damping_ = 0.0;  // a snap switches it off again; a new input never starts damped
  if (banded_ && pattern_J_ != active()) build_pattern();
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
  residual_changed();
  guess_x(x_, false);
  lift(x_, y);
}

void LumpedProblem::rest_state(Eigen::VectorXd& y) {
  residual_changed();
  guess_x(x_, true);
  lift(x_, y);
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
  if (previous.unknowns.size() != body_.per_subsegment * body_.N || !previous.unknowns.allFinite()) return false;
  x_ = previous.unknowns.head(body_.per_subsegment * active());
  residual_changed();
  on_warm(x_);
  lift(x_, y);
  return true;
}

void LumpedProblem::evaluate(const double* x) {
  last_valid_ = false;
  body_.compute_frames(x, active(), frames_.data(), poses_.data(), backbone_weight_on() ? centroids_.data() : nullptr);
  if (body_.statics.friction()) body_.statics.update_friction(loads_, frames_.data());
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), F_.data(), M_.data());
}

bool LumpedProblem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
  last_valid_ = false;
  const bool ok = banded_ ? banded_residual(y.data(), f.data()) : recursive_residual(y.data(), f.data());
  if (ok && damping_ > 0.0) f += damping_ * damping_scale_.cwiseProduct(y - damping_ref_);
  if (!(ok && f.allFinite())) return false;
  last_y_ = y;  // allocates only when the size changes
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
  if (!has_jacobian()) return false;
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
  evaluate(x);
  constitutive_all(x, f);
  return true;
}

void LumpedProblem::evaluate_from(const double* x, int k) {
  last_valid_ = false;
  body_.compute_frames(x, active(), frames_.data(), poses_.data(), backbone_weight_on() ? centroids_.data() : nullptr, k);
  body_.statics.disk_loads(loads_, frames_.data(), disk_f_.data(), disk_m_.data(), k - 1);
  body_.statics.distal_wrenches(loads_, frames_.data(), centroids_.data(), disk_f_.data(), disk_m_.data(), F_.data(),
                                M_.data());
}

namespace {

// eps : (G Q), i.e. sum_e r_e x (Q^T f_e) for G = sum_e r_e f_e^T.
Vec3 axial_contraction(const Mat3& G, const Mat3& Q) {
  const Mat3 X = G * Q;
  return Vec3(X(1, 2) - X(2, 1), X(2, 0) - X(0, 2), X(0, 1) - X(1, 0));
}

}  // namespace

void LumpedProblem::split_external_loads() {
  // The distal wrenches F_, M_ split into a part carried by the body (tendon forces: it moves
  // with the frames) and the external part (tip wrench, weights: fixed in the base frame, acting
  // at points that move with the frames). For the external part also
  // G_j = sum_e (p_e - O_j) f_e^T over its distal point loads and the distal pure moment, so that
  // after a rigid motion Q of everything distal of disk j its moment about O_j is
  // Q (eps : (G_j Q)) + m_pure (see structured_jacobian()).
  const int J = active();
  const physics::LoadCase& L = loads_.loads;
  const bool bb = backbone_weight_on(), dw = L.has_disk_weight();
  const bool tip = J == body_.N && L.has_tip_wrench();
  jac_external_ = bb || dw || tip;
  if (!jac_external_) {
    for (int j = 1; j <= J; ++j) {
      jac_FT_[j] = F_[j];
      jac_MT_[j] = M_[j];
    }
    return;
  }
  Vec3 FE = Vec3::Zero(), ME = Vec3::Zero(), pure = Vec3::Zero();
  Mat3 P = Mat3::Zero();  // sum_e p_e f_e^T
  for (int j = J; j >= 1; --j) {
    const Vec3& o = frames_[j].p;
    Vec3 fj = dw ? L.disk_weight(j) : Vec3::Zero();
    if (tip && j == J) {
      fj += L.tip_force();
      pure = L.tip_moment();
    }
    if (j < J) {
      // Shift the distal external wrench from O_{j+1} to O_j, and add W_{j+1} at its centroid.
      ME += (frames_[j + 1].p - o).cross(FE);
      if (bb) {
        const Vec3 W = backbone_weight(j + 1);
        FE += W;
        ME += (centroids_[j + 1] - o).cross(W);
        P += centroids_[j + 1] * W.transpose();
      }
    }
    FE += fj;
    P += o * fj.transpose();
    if (j == J) ME += pure;
    jac_FE_[j] = FE;
    jac_G_[j] = P - o * FE.transpose();
    jac_pure_[j] = pure;
    jac_FT_[j] = F_[j] - FE;
    jac_MT_[j] = M_[j] - ME;
  }
}

void LumpedProblem::load_sensitivities() {
  // Fixed-size blocks for the models' subsegment sizes (CCsub 3, PRB 5).
  switch (body_.per_subsegment) {
    case 3: load_sensitivities_m<3>(); break;
    case 5: load_sensitivities_m<5>(); break;
    default: load_sensitivities_m<Eigen::Dynamic>(); break;
  }
}

template <int Rows>
void LumpedProblem::load_sensitivities_m() {
  // L_j = d r_j / d(F, M, W) in the frame of disk j-1 (m x 9): the model's closed form
  // (load_jacobian: CCsub, PRB), else forward differences of the constitutive law, mapped to
  //  - E_j: the response to a change (dF, dM0) of the distal wrench, base frame, moment about the
  //    base origin, with the frames of subsegment j fixed (proximal rows of a column);
  //  - D_j: the response to a small rotation w of everything distal of disk j-1 with the
  //    external loads fixed in the base frame (distal rows): in the moving frame the tendon forces
  //    are unchanged and the external force, moment and weight turn by -w.
  const int m = body_.per_subsegment, J = active();
  const bool bb = backbone_weight_on();
  const int q_count = bb ? 9 : 6;
  jac_E_.resize(m * J, 6);
  if (jac_external_) jac_D_.resize(m * J, 3);
  double r0[8], r1[8];  // m <= 8 (CCsub 3, PRB 5), as L's row bound
  constexpr int MaxRows = Rows == Eigen::Dynamic ? 8 : Rows;
  Eigen::Matrix<double, Rows, 9, 0, MaxRows, 9> L(m, 9);
  for (int j = 1; j <= J; ++j) {
    const double* xj = jac_x_.data() + m * (j - 1);
    const Mat3 Rt = frames_[j - 1].R.transpose();
    const Vec3 W = bb ? backbone_weight(j) : Vec3::Zero();
    Vec3 v[3] = {Rt * F_[j], Rt * M_[j], Rt * W};
    L.setZero();
    const bool closed = load_jacobian(j, xj, poses_[j], v[0], v[1], v[2], L.data());
    if (!closed) constitutive(j, xj, poses_[j], v[0], v[1], v[2], r0);
    const double l = body_.statics.length(j);
    const double scale[3] = {body_.EI / (l * l), body_.EI / l, body_.EI / (l * l)};
    for (int q = 0; q < q_count && !closed; ++q) {
      Vec3& target = v[q / 3];
      const double keep = target[q % 3];
      const double h = 1e-7 * std::max(target.norm(), scale[q / 3]);
      target[q % 3] = keep + h;
      constitutive(j, xj, poses_[j], v[0], v[1], v[2], r1);
      target[q % 3] = keep;
      for (int r = 0; r < m; ++r) L(r, q) = (r1[r] - r0[r]) / h;
    }
    const auto LF = L.template leftCols<3>(), LM = L.template middleCols<3>(3), LW = L.template rightCols<3>();
    auto E = jac_E_.template middleRows<Rows>(m * (j - 1), m);
    E.template leftCols<3>().noalias() = LF * Rt - LM * (Rt * lie::hat(frames_[j].p));
    E.template rightCols<3>().noalias() = LM * Rt;
    if (jac_external_) {
      // eps : (G [w]x) as a matrix in w.
      Mat3 C;
      for (int i = 0; i < 3; ++i) C.col(i) = axial_contraction(jac_G_[j], lie::hat(Vec3::Unit(i)));
      auto D = jac_D_.template middleRows<Rows>(m * (j - 1), m);
      D.noalias() = LF * (Rt * lie::hat(jac_FE_[j])) + LM * (Rt * (C + lie::hat(jac_pure_[j])));
      if (bb) D.noalias() += LW * (Rt * lie::hat(W));
    }
  }
}

bool LumpedProblem::structured_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                        const Eigen::Ref<const Eigen::VectorXd>& f) {
  // Forward differences that exploit the chain's structure. A change of x_k moves every frame
  // distal of disk k-1 by one rigid motion (Q, t); the loads of the disks k-1 and k (whose chords
  // reach across disk k) change otherwise and are recomputed, and so is the residual of
  // subsegment k. Distal of disk k every tendon force moves with the frames, so in the frame of
  // disk j-1 (j > k) it is unchanged and only the external loads (fixed in the base frame) turn
  // by Q^T = I - [w]x; proximal of disk k-1 the distal wrench changes by one wrench (dF, dM0).
  // Both act on the residuals through the load sensitivities of load_sensitivities(), so the
  // off-diagonal blocks are products of m x 6 (m x 3) and 6 x m (3 x m) matrices: a column costs
  // one subsegment's kinematics and two disks' tendon forces (tests/test_lumped_jacobian.cpp
  // compares the result with plain and central differences). The factors are kept for the dense
  // Jacobian (jacobian()) and for the structured Newton step (lumped_structured.cpp).
  const int m = body_.per_subsegment, n = size(), J = active();
  const bool bb = backbone_weight_on();
  jac_x_ = x;
  jac_f_.resize(m);
  jac_uscale_.resize(n);
  unknown_scale(jac_uscale_);
  const double noise = relative_noise();
  // frames_, poses_, centroids_, F_, M_ at x: KINSOL asks for the Jacobian where it has just
  // evaluated the residual, and then they are that evaluation's (the perturbations below restore
  // the frames they move).
  if (banded_ || !evaluated_at(x)) evaluate_from(x.data(), 1);
  if (static_cast<int>(jac_FT_.size()) < J + 2) {
    const std::size_t sz = static_cast<std::size_t>(body_.N) + 2;
    jac_FT_.resize(sz);
    jac_MT_.resize(sz);
    jac_FE_.resize(sz);
    jac_pure_.resize(sz);
    jac_G_.resize(sz);
    jac_df_.resize(sz);
    jac_dm_.resize(sz);
  }
  split_external_loads();
  load_sensitivities();
  jac_dW_.resize(6, n);
  jac_dW_.leftCols(m).setZero();  // subsegment 1 has no proximal rows
  jac_diag_.resize(m, n);
  if (jac_external_) jac_Om_.resize(3, n);
  SubsegmentPose g;
  for (int k = 1; k <= J; ++k) {
    const Frame& prev = frames_[k - 1];
    const Frame base_k = frames_[k];
    const bool has_next = k + 1 <= body_.N;
    const Frame base_k1 = has_next ? frames_[k + 1] : Frame{};
    for (int i = 0; i < m; ++i) {
      const int c = m * (k - 1) + i;
      const double h = bvp::finite_difference_step(x[c], jac_uscale_[c], noise);
      jac_x_[c] = x[c] + h;
      const double* xk = jac_x_.data() + m * (k - 1);
      body_.local(k, xk, g);
      // The perturbed frame k, the rigid motion (Q, t) of everything distal of it, frame k+1.
      Frame& fk = frames_[k];
      fk.R = prev.R * g.R;
      fk.p = prev.p + prev.R * g.p;
      const Mat3 Q = fk.R * base_k.R.transpose();
      const Vec3 t = fk.p - Q * base_k.p;
      if (has_next) {
        frames_[k + 1].R = Q * base_k1.R;
        frames_[k + 1].p = Q * base_k1.p + t;
      }
      // Frames below k are not perturbed: after the first column of subsegment k their holes
      // and chords are the ones in the scratch.
      body_.statics.disk_loads(loads_, frames_.data(), jac_df_.data(), jac_dm_.data(), k - 1, k, i == 0 ? -1 : k);
      // Distal wrench at disk k (about O_k', base frame).
      Vec3 Fk = jac_df_[k], Mk = jac_dm_[k];
      if (k < J) {
        Vec3 F1 = Q * jac_FT_[k + 1], M1 = Q * jac_MT_[k + 1];
        if (jac_external_) {
          F1 += jac_FE_[k + 1];
          M1 += Q * axial_contraction(jac_G_[k + 1], Q) + jac_pure_[k + 1];
        }
        Fk += F1;
        Mk += M1 + (Q * (base_k1.p - base_k.p)).cross(F1);
        if (bb) {
          const Vec3 W = backbone_weight(k + 1);
          Fk += W;
          Mk += (Q * (centroids_[k + 1] - base_k.p)).cross(W);
        }
      }
      // Residual of subsegment k.
      const Mat3 Rt = prev.R.transpose();
      const Vec3 Wk = bb ? Vec3(Rt * backbone_weight(k)) : Vec3::Zero();
      constitutive(k, xk, g, Rt * Fk, Rt * Mk, Wk, jac_f_.data());
      for (int r = 0; r < m; ++r) jac_diag_(r, c) = (jac_f_[r] - f[m * (k - 1) + r]) / h;
      // The change of the distal wrench at disk k-1 (base frame, moment about the origin).
      if (k >= 2) {
        Vec3 Fp = jac_df_[k - 1] + Fk, Mp = jac_dm_[k - 1] + Mk + (fk.p - prev.p).cross(Fk);
        if (bb) {
          const Vec3 W = backbone_weight(k);
          Fp += W;
          Mp += (prev.R * g.c).cross(W);
        }
        const Vec3 dF = Fp - F_[k - 1], dM = Mp - M_[k - 1];
        jac_dW_.col(c).head<3>() = dF / h;
        jac_dW_.col(c).tail<3>() = (dM + prev.p.cross(dF)) / h;
      }
      // The rotation of everything distal of disk k, per unit change of x_c.
      if (jac_external_)
        jac_Om_.col(c) = Vec3(Q(2, 1) - Q(1, 2), Q(0, 2) - Q(2, 0), Q(1, 0) - Q(0, 1)) / (2.0 * h);
      jac_x_[c] = x[c];
    }
    frames_[k] = base_k;
    if (has_next) frames_[k + 1] = base_k1;
  }
  return jac_diag_.allFinite() && jac_dW_.allFinite() && jac_E_.allFinite() &&
         (!jac_external_ || (jac_Om_.allFinite() && jac_D_.allFinite()));
}

bool LumpedProblem::undamped_structured_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                 const Eigen::Ref<const Eigen::VectorXd>& f) {
  if (!(damping_ > 0.0)) return structured_jacobian(x, f);
  damping_f_ = f - damping_ * damping_scale_.cwiseProduct(x - damping_ref_);
  return structured_jacobian(x, damping_f_);
}

template <int Rows>
void LumpedProblem::offdiagonal_blocks(Eigen::Ref<Eigen::MatrixXd> Jm) const {
  // The block upper part of E dW (n x 6 by 6 x n) and the block lower part of D Om (n x 3 by
  // 3 x n), block by block (m x 6 by 6 x m, m x 3 by 3 x m: fixed sizes for CCsub and PRB); the
  // diagonal blocks are the differences of structured_jacobian().
  const int m = body_.per_subsegment, J = active();
  for (int k = 1; k <= J; ++k) {
    const auto dW = jac_dW_.template middleCols<Rows>(m * (k - 1), m);
    for (int j = 1; j < k; ++j)
      Jm.template block<Rows, Rows>(m * (j - 1), m * (k - 1), m, m).noalias() =
          jac_E_.template middleRows<Rows>(m * (j - 1), m) * dW;
    if (!jac_external_) {
      Jm.block(m * k, m * (k - 1), m * (J - k), m).setZero();
      continue;
    }
    const auto Om = jac_Om_.template middleCols<Rows>(m * (k - 1), m);
    for (int j = k + 1; j <= J; ++j)
      Jm.template block<Rows, Rows>(m * (j - 1), m * (k - 1), m, m).noalias() =
          jac_D_.template middleRows<Rows>(m * (j - 1), m) * Om;
  }
}

bool LumpedProblem::jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                             Eigen::Ref<Eigen::MatrixXd> Jm) {
  if (!undamped_structured_jacobian(x, f)) return false;
  const int m = body_.per_subsegment, J = active();
  switch (m) {
    case 3: offdiagonal_blocks<3>(Jm); break;
    case 5: offdiagonal_blocks<5>(Jm); break;
    default: offdiagonal_blocks<Eigen::Dynamic>(Jm); break;
  }
  for (int k = 1; k <= J; ++k) Jm.block(m * (k - 1), m * (k - 1), m, m) = jac_diag_.middleCols(m * (k - 1), m);
  if (damping_ > 0.0) Jm.diagonal() += damping_ * damping_scale_;
  return Jm.allFinite();
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
    body_.compute_frames(full.data(), active(), solution.disk_frames.data());
  }
  solution.tendon_displacements = tendon::chord_displacements(solution.disk_frames, body_.statics.routing(), convention_);
  if (body_.statics.friction()) {
    const TendonRouting& routing = body_.statics.routing();
    body_.statics.update_friction(loads_, solution.disk_frames.data());
    solution.tendon_end_tensions = tendon::end_tensions(routing, loads_.chord.data(), static_cast<int>(routing.tendons.size()));
  }
  solution.unknowns = std::move(full);
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
  body_.compute_frames(pull_x_.data(), active(), pull_frames_.data());
  const std::vector<double> pulls = tendon::chord_displacements(pull_frames_, body_.statics.routing(), convention_);
  d = Eigen::Map<const Eigen::VectorXd>(pulls.data(), static_cast<Eigen::Index>(pulls.size()));
  return d.allFinite();
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
