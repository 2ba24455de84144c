// The lumped models' analytic Jacobian (lumped_problem.hpp): forward differences that exploit the
// chain's structure (structured_jacobian()), the load sensitivities they rest on, and the dense
// Jacobian assembled from their factors (the structured Newton step is in lumped_structured.cpp).
#include "lumped/lumped_problem.hpp"

#include <algorithm>

#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

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
                                        const Eigen::Ref<const Eigen::VectorXd>& f, bool diagonal_only) {
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
  ++jac_serial_;
  jac_x_ = x;
  jac_f_.resize(m);
  jac_uscale_.resize(n);
  unknown_scale(jac_uscale_);
  const double noise = relative_noise();
  // frames_, poses_, centroids_, F_, M_ at x: KINSOL asks for the Jacobian where it has just
  // evaluated the residual, and then they are that evaluation's (the perturbations below restore
  // the frames they move).
  if (banded_ || !evaluated_at(x)) {
    if (contacts_.empty()) {
      evaluate_from(x.data(), 1);
    } else {
      read_contact_unknowns(x.data());
      evaluate(x.data());
    }
  }
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
  split_external_loads();  // contact forces are in the part moving with the frames
  // (The serial above is counted anyway: jac_* are no longer those of a structured Newton step's
  // factors, lumped_structured.cpp.)
  if (!diagonal_only) load_sensitivities();
  if (!contacts_.empty()) contact_loads();
  const int nx = m * J;  // the x_j (the contact force unknowns follow them)
  jac_dW_.resize(6, nx);
  jac_dW_.leftCols(m).setZero();  // subsegment 1 has no proximal rows
  jac_diag_.resize(m, nx);
  if (jac_external_) jac_Om_.resize(3, nx);
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
      body_.pose(k, xk, loads_.stretch_of(k), g);
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
      if (!contacts_.empty()) contact_column(k, c, Q, t, fk, base_k1, h, Fk, Mk);
      // Residual of subsegment k.
      const Mat3 Rt = prev.R.transpose();
      const Vec3 Wk = bb ? Vec3(Rt * backbone_weight(k)) : Vec3::Zero();
      constitutive(k, xk, g, Rt * Fk, Rt * Mk, Wk, jac_f_.data());
      for (int r = 0; r < m; ++r) jac_diag_(r, c) = (jac_f_[r] - f[m * (k - 1) + r]) / h;
      // The change of the distal wrench at disk k-1 (base frame, moment about the origin).
      if (k >= 2 && !diagonal_only) {
        Vec3 Fp = jac_df_[k - 1] + Fk, Mp = jac_dm_[k - 1] + Mk + (fk.p - prev.p).cross(Fk);
        if (!contacts_.empty()) {
          Fp += jac_cf_[k - 1];
          Mp += jac_cm_[k - 1];
        }
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
      if (jac_external_ && !diagonal_only)
        jac_Om_.col(c) = Vec3(Q(2, 1) - Q(1, 2), Q(0, 2) - Q(2, 0), Q(1, 0) - Q(0, 1)) / (2.0 * h);
      jac_x_[c] = x[c];
    }
    frames_[k] = base_k;
    if (has_next) frames_[k + 1] = base_k1;
  }
  jac_equations_ = -1;  // the recorded point (below) only for full blocks of the statics
  if (diagonal_only) return all_finite(jac_diag_);
  const bool finite = all_finite(jac_diag_) && all_finite(jac_dW_) && all_finite(jac_E_) &&
                      (!jac_external_ || (all_finite(jac_Om_) && all_finite(jac_D_)));
  if (finite && contacts_.empty() && !banded_) {
    jac_at_ = x;  // allocates only when the size changes
    jac_lambda_ = loads_.loads.load_factor();
    jac_equations_ = equations_serial_;
  }
  return finite;
}

bool LumpedProblem::undamped_structured_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                 const Eigen::Ref<const Eigen::VectorXd>& f, bool diagonal_only) {
  if (!(damping_ > 0.0)) return structured_jacobian(x, f, diagonal_only);
  damping_f_ = f - damping_ * damping_scale_.cwiseProduct(x - damping_ref_);
  return structured_jacobian(x, damping_f_, diagonal_only);
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
  if (!contacts_.empty()) return contact_jacobian(Jm);
  const int m = body_.per_subsegment, J = active();
  switch (m) {
    case 3: offdiagonal_blocks<3>(Jm); break;
    case 5: offdiagonal_blocks<5>(Jm); break;
    default: offdiagonal_blocks<Eigen::Dynamic>(Jm); break;
  }
  for (int k = 1; k <= J; ++k) Jm.block(m * (k - 1), m * (k - 1), m, m) = jac_diag_.middleCols(m * (k - 1), m);
  if (damping_ > 0.0) Jm.diagonal() += damping_ * damping_scale_;
  return all_finite(Jm);
}

bool LumpedProblem::diagonal_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>& f, Eigen::Ref<Eigen::MatrixXd> blocks) {
  if (!contacts_.empty() || !undamped_structured_jacobian(x, f, true)) return false;
  const int m = body_.per_subsegment;
  blocks = jac_diag_;
  if (damping_ > 0.0)
    for (Eigen::Index c = 0; c < blocks.cols(); ++c) blocks(c % m, c) += damping_ * damping_scale_[c];
  return all_finite(blocks);
}

}  // namespace tdcr::detail
