// The mechanics of the lumped models' equations of motion (lumped_dynamics.hpp): the bodies'
// twists, the mass matrix from composite inertias, the generalized force from the static
// residual, the velocity-product forces and drag, the springs, the energies, the linearised
// frequencies.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "lumped/lumped_dynamics_integrator.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

void LumpedDynamics::twists(const double* q, Twists& T, std::vector<Vec3>* points) {
  std::vector<Vec3>& c = points ? *points : link_c_;
  const double* stretch = problem_->stretch();  // the tendons' compression (effects.shear_extension)
  if (rates_) {
    // Closed-form rates of the subsegments' poses (LumpedBody::local_rates), the frames from the
    // same poses in one pass (as LumpedBody::compute_frames).
    SubsegmentRates d;
    frames_b_[0] = Frame{};
    for (int j = 1; j <= N_; ++j) {
      SubsegmentPose& g = poses_[j];
      body_.pose_rates(j, q + m_ * (j - 1), stretch ? stretch[j] : 1.0, g, d);
      const Frame& prev = frames_b_[j - 1];
      Frame& f = frames_b_[j];
      f.R = prev.R * g.R;
      f.p = prev.p + prev.R * g.p;
      const Mat3& R0 = prev.R;
      if (links_)
        for (int i = 0; i < kLinks; ++i) c[kLinks * j + i] = prev.p + R0 * g.aux[3 + i];
      for (int i = 0; i < m_; ++i) {
        // (Not the comma initializer: it was a fifth of PRB's twists() here,
        // callgrind, bench_dynamics --models prb --no-reference.)
        const Vec3 w = R0 * d.w[i];
        auto Ti = T.col(m_ * (j - 1) + i);
        Ti.head<3>() = w;
        Ti.tail<3>() = R0 * d.dp[i] - w.cross(f.p);
      }
      if (links_) {
        // The columns that move each link (the others stay zero).
        auto& J = points ? link_J_step_ : link_J_;
        for (int l = 0; l < kLinks; ++l)
          for (int a = 0; a < link_ncols_[l]; ++a) {
            const int i = link_cols_[l][a];
            J[kLinks * j + l].col(i) = R0 * d.dmid[l][i];
          }
      }
    }
    return;
  }
  body_.compute_frames(q, N_, stretch, frames_b_.data(), poses_.data());
  if (links_)
    for (int j = 1; j <= N_; ++j)
      for (int i = 0; i < kLinks; ++i)
        c[kLinks * j + i] = frames_b_[j - 1].p + frames_b_[j - 1].R * poses_[j].aux[3 + i];
  double xs[8];
  SubsegmentPose g[4];
  static constexpr double kOffset[4] = {2.0, 1.0, -1.0, -2.0};
  static constexpr double kWeight[4] = {-1.0 / 12.0, 8.0 / 12.0, -8.0 / 12.0, 1.0 / 12.0};
  for (int j = 1; j <= N_; ++j) {
    const double* xj = q + m_ * (j - 1);
    const Mat3& R0 = frames_b_[j - 1].R;
    const Vec3& pj = frames_b_[j].p;
    for (int i = 0; i < m_; ++i) {
      // Fourth-order central differences: the mass matrix is ill-conditioned (torsion against
      // bending), so its columns' noise must stay near rounding.
      std::copy(xj, xj + m_, xs);
      for (int k = 0; k < 4; ++k) {
        xs[i] = xj[i] + kOffset[k] * kTwistStep;
        body_.pose(j, xs, problem_->stretch() ? problem_->stretch()[j] : 1.0, g[k]);
      }
      Mat3 dR = Mat3::Zero();
      Vec3 dp = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        dR += kWeight[k] * g[k].R;
        dp += kWeight[k] * g[k].p;
      }
      dR /= kTwistStep;
      dp /= kTwistStep;
      const Vec3 w_loc = lie::vee(dR * poses_[j].R.transpose());
      if (links_)
        for (int l = 0; l < kLinks; ++l) {
          if (!std::count(link_cols_[l], link_cols_[l] + link_ncols_[l], i)) continue;  // stays zero
          Vec3 dc = Vec3::Zero();
          for (int k = 0; k < 4; ++k) dc += kWeight[k] * g[k].aux[3 + l];
          (points ? link_J_step_ : link_J_)[kLinks * j + l].col(i) = R0 * dc / kTwistStep;
        }
      const Vec3 a = R0 * dp;
      const Vec3 w = R0 * w_loc;
      T.col(m_ * (j - 1) + i).head<3>() = w;
      T.col(m_ * (j - 1) + i).tail<3>() = a - w.cross(pj);
    }
  }
}

void LumpedDynamics::twists_along(const double* q, const double* v) {
  const double* stretch = problem_->stretch();
  if (!rates_) {
    // Differenced twists: all columns, then their products with v.
    twists(q, Tp_, &link_stencil_[3]);
    for (int j = 1; j <= N_; ++j) {
      tv_step_[j].noalias() = Tp_.middleCols(m_ * (j - 1), m_) * Eigen::Map<const Eigen::VectorXd>(v + m_ * (j - 1), m_);
      if (links_)
        for (int l = 0; l < kLinks; ++l)
          ljv_step_[kLinks * j + l].noalias() =
              link_J_step_[kLinks * j + l] * Eigen::Map<const Eigen::Matrix<double, 5, 1>>(v + m_ * (j - 1));
    }
    return;
  }
  // twists()' closed-form pass with each subsegment's columns summed along v in its own frame
  // first: one rotation to the base per twist and per link instead of one per column.
  SubsegmentRates d;
  frames_b_[0] = Frame{};
  for (int j = 1; j <= N_; ++j) {
    SubsegmentPose& g = poses_[j];
    body_.pose_rates(j, q + m_ * (j - 1), stretch ? stretch[j] : 1.0, g, d);
    const Frame& prev = frames_b_[j - 1];
    Frame& f = frames_b_[j];
    f.R = prev.R * g.R;
    f.p = prev.p + prev.R * g.p;
    const Mat3& R0 = prev.R;
    const double* vj = v + m_ * (j - 1);
    Vec3 wl = Vec3::Zero(), dl = Vec3::Zero();
    for (int i = 0; i < m_; ++i) {
      wl += vj[i] * d.w[i];
      dl += vj[i] * d.dp[i];
    }
    const Vec3 w = R0 * wl;
    tv_step_[j].head<3>() = w;
    tv_step_[j].tail<3>() = R0 * dl - w.cross(f.p);
    if (links_)
      for (int l = 0; l < kLinks; ++l) {
        link_stencil_[3][kLinks * j + l] = prev.p + R0 * g.aux[3 + l];
        Vec3 s = Vec3::Zero();
        for (int a = 0; a < link_ncols_[l]; ++a) s += vj[link_cols_[l][a]] * d.dmid[l][link_cols_[l][a]];
        ljv_step_[kLinks * j + l] = R0 * s;
      }
  }
}

bool LumpedDynamics::generalized_force(const double* q) {
  Eigen::Map<const Eigen::VectorXd> x(q, n_);
  // The frames and poses of twists() at q: the residual does not compute them again.
  if (!problem_->residual_with_frames(x, frames_b_.data(), poses_.data(), r_)) return false;
  const double EI = body_.EI;
  for (int j = 1; j <= N_; ++j) {
    const double* rj = r_.data() + m_ * (j - 1);
    double* Qj = Q_.data() + m_ * (j - 1);
    const double c = EI / length_[j];
    Mat3& S = S_[j];
    if (m_ == 3) {
      // CCsub: r = B y with B = [e_x e_y z_j] (frame of disk j-1); y's spring part is
      // (b_x, b_y, (GJ/EI) eps), the gradient of the springs' energy times l/EI.
      const Vec3 z = poses_[j].R.col(2);
      Mat3 B = Mat3::Identity();
      B.col(2) = z;
      S = c * B.inverse();
      const Vec3 Qv = -(S * Eigen::Map<const Vec3>(rj));
      std::copy(Qv.data(), Qv.data() + 3, Qj);
    } else {
      // PRB: the joint, twist rows are spring gradients times l/EI; the bending-plane row is the
      // gradient component divided by the bend angle a (lumped_problem.hpp, set_damping).
      const double a = q[m_ * (j - 1)] + q[m_ * (j - 1) + 1] + q[m_ * (j - 1) + 2];
      for (int i = 0; i < m_; ++i) Qj[i] = -c * rj[i];
      Qj[3] *= a;
      S.setZero();
      S(0, 0) = a;  // the phi row's factor (over c), read by jac_fn
    }
  }
  return all_finite(Q_);
}

template <int m>
void LumpedDynamics::mass_blocks() {
  for (int bj = 1; bj <= N_; ++bj) {
    Eigen::Matrix<double, 6, m> U = IC_[bj] * T_.middleCols<m>(m * (bj - 1));
    if (links_)
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * bj + i;
        const Eigen::Matrix<double, 3, 5>& J = link_J_[l];
        for (int c = 0; c < m; ++c) {
          U.col(c).template head<3>() += link_mass_[l] * link_c_[l].cross(Vec3(J.col(c)));
          U.col(c).template tail<3>() += link_mass_[l] * J.col(c);
        }
      }
    for (int aj = 1; aj <= bj; ++aj) {
      const Eigen::Matrix<double, m, m> B = T_.middleCols<m>(m * (aj - 1)).transpose() * U;
      M_.block<m, m>(m * (aj - 1), m * (bj - 1)) = B;
      if (aj != bj) M_.block<m, m>(m * (bj - 1), m * (aj - 1)) = B.transpose();
    }
  }
}

void LumpedDynamics::body_inertias() {
  for (int k = 1; k <= N_; ++k) {
    const Frame& f = frames_b_[k];
    const Mat3 Ic = f.R * inertia_[k].asDiagonal() * f.R.transpose();
    Io_[k] = spatial_inertia(mass_[k], f.p, Ic);
    // PRB: the links of subsegment k + 1 that no unknown moves are rigid with disk k: one body
    // (articulated_m() and bias() then skip them, their velocity products are the disk's).
    if (links_ && k < N_)
      for (int i = 0; i < kLinks; ++i)
        if (link_rigid(i)) add_point_inertia(Io_[k], link_mass_[kLinks * (k + 1) + i], link_c_[kLinks * (k + 1) + i]);
  }
}

namespace {

// The inverse of a symmetric positive definite m x m matrix A (its lower triangle read) by
// Cholesky, A = L L^T, A^-1 = L^-T L^-1, in plain loops (Eigen's LLT solve with a matrix
// right-hand side goes through its general blocked triangular solver, slow at m = 3, 5), fully
// unrolled: GCC left the triangular loops rolled, and their control was most of the work at
// m = 5 (unrolled, the articulated pass is 11 % cheaper, callgrind, bench_dynamics --models prb
// --no-reference; unrolling general_inverse()'s pivoted loops made it dearer).
// False where A is not numerically positive definite.
template <int m>
bool spd_inverse(const Eigen::Matrix<double, m, m>& A, Eigen::Matrix<double, m, m>& inv) {
  double L[m][m] = {}, Li[m][m] = {};
  #pragma GCC unroll 8
  for (int j = 0; j < m; ++j) {
    double d = A(j, j);
    #pragma GCC unroll 8
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    if (!(d > 0.0)) return false;
    L[j][j] = std::sqrt(d);
    #pragma GCC unroll 8
    for (int i = j + 1; i < m; ++i) {
      double s = A(i, j);
      #pragma GCC unroll 8
      for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
      L[i][j] = s / L[j][j];
    }
  }
  // Li = L^-1 (lower triangular), column by column.
  #pragma GCC unroll 8
  for (int j = 0; j < m; ++j) {
    Li[j][j] = 1.0 / L[j][j];
    #pragma GCC unroll 8
    for (int i = j + 1; i < m; ++i) {
      double s = 0.0;
      #pragma GCC unroll 8
      for (int k = j; k < i; ++k) s -= L[i][k] * Li[k][j];
      Li[i][j] = s / L[i][i];
    }
  }
  // inv = Li^T Li (symmetric).
  #pragma GCC unroll 8
  for (int i = 0; i < m; ++i)
    #pragma GCC unroll 8
    for (int j = 0; j <= i; ++j) {
      double s = 0.0;
      #pragma GCC unroll 8
      for (int k = i; k < m; ++k) s += Li[k][i] * Li[k][j];
      inv(i, j) = s;
      inv(j, i) = s;
    }
  return true;
}

// The inverse of a general m x m matrix by Gauss-Jordan elimination with partial pivoting, in
// plain loops (Eigen's fixed-size PartialPivLU inverse goes through its general triangular
// solver: at m = 5 it was half of chain_factor()). False where a pivot is zero or not finite.
template <int m>
bool general_inverse(const Eigen::Matrix<double, m, m>& A, Eigen::Matrix<double, m, m>& inv) {
  double a[m][2 * m];
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      a[i][j] = A(i, j);
      a[i][m + j] = i == j ? 1.0 : 0.0;
    }
  for (int c = 0; c < m; ++c) {
    int p = c;
    for (int i = c + 1; i < m; ++i)
      if (std::abs(a[i][c]) > std::abs(a[p][c])) p = i;
    if (!(std::abs(a[p][c]) > 0.0) || !std::isfinite(a[p][c])) return false;
    if (p != c)
      for (int j = 0; j < 2 * m; ++j) std::swap(a[p][j], a[c][j]);
    const double d = 1.0 / a[c][c];
    for (int j = 0; j < 2 * m; ++j) a[c][j] *= d;
    for (int i = 0; i < m; ++i) {
      if (i == c) continue;
      const double f = a[i][c];
      if (f == 0.0) continue;
      for (int j = 0; j < 2 * m; ++j) a[i][j] -= f * a[c][j];
    }
  }
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) inv(i, j) = a[i][m + j];
  return true;
}

}  // namespace

template <int m>
void LumpedDynamics::articulated_m(Eigen::Map<Eigen::VectorXd>& qdd) {
  // Featherstone's articulated-body algorithm in base coordinates. Joint k (the m unknowns of
  // subsegment k) carries the subtree at disk k (motion subspace T_k, velocity-product
  // acceleration c_k = T_k' v_k = A_k - A_{k-1}, bias()) and, PRB, the four link masses of
  // subsegment k, each a child of the same joint with its own subspace S_l = (0; J_l) (a point
  // mass moving with disk k-1's rotation and its own translation J_l v_k). For children b with
  // articulated inertias IA_b, bias wrenches pA_b and accelerations a_b = a_{k-1} + c_b + S_b q'':
  //   U = sum IA_b S_b, D = sum S_b^T IA_b S_b (+ PRB's phi inertia), w_b = pA_b + IA_b c_b,
  //   u = tau - sum S_b^T w_b, q'' = D^-1 (u - U^T a_{k-1}),
  // and disk k-1 receives sum IA_b - U D^-1 U^T and sum w_b + U D^-1 u. tau = Q - D v (rhs_).
  using Um = Eigen::Matrix<double, 6, m>;
  using Mm = Eigen::Matrix<double, m, m>;
  using Vm = Eigen::Matrix<double, m, 1>;
  auto& Us = aba_store<m>().U;
  auto& Dinvs = aba_store<m>().Dinv;
  auto& us = aba_store<m>().u;
  Mat6 IA = Io_[N_];
  Vec6 pA = pbody_[N_];
  for (int k = N_; k >= 1; --k) {
    const auto Tk = T_.middleCols<m>(m * (k - 1));
    const Vec6 c = A_[k] - A_[k - 1];
    Um U = IA * Tk;
    Mm D = Tk.transpose() * U;
    Vec6 w = pA + IA * c;
    Vm u = rhs_.segment<m>(m * (k - 1)) - Tk.transpose() * w;
    Mat6 IAsum = IA;
    Vec6 wsum = w;
    if constexpr (m == 5) {
      if (links_) {
        const Vec6& Ap = A_[k - 1];
        // The links are point masses: IA_l = spatial_inertia(m, c, 0), summed into IAsum as
        // their total mass, first and second moments; the wrench w_l = IA_l c_l + V_l x* IA_l V_l
        // of a point is (c x f, f) with f = m times its acceleration less the parent's a_{k-1}
        // part (Ap.v + Ap.w x c): m acc from bias()'s forward difference.
        // Only the columns that move each link (link_cols_), and not the links rigid with disk
        // k - 1 (in Io_[k - 1]): PRB's links 1..3 have 2, 3 and 4 of the 5 columns.
        double msum = 0.0, m2 = 0.0;
        Vec3 mc = Vec3::Zero();
        Mat3 mcc = Mat3::Zero();
        Um LU = Um::Zero();
        Mm LD = Mm::Zero();
        for (int i = 0; i < kLinks; ++i) {
          const int nc = link_ncols_[i];
          if (nc == 0) continue;
          const int* cols = link_cols_[i];
          const int l = kLinks * k + i;
          const double ml = link_mass_[l];
          const Vec3& cl = link_c_[l];
          const Eigen::Matrix<double, 3, 5>& J = link_J_[l];
          Vec3 f = bias_h_ > 0.0 ? link_force(l) : Vec3::Zero();
          f -= ml * (Ap.tail<3>() + Ap.head<3>().cross(cl));
          // IA_l S_l = (m [c] J; m J); S_l^T IA_l S_l = m J^T J (its lower triangle here).
          for (int a = 0; a < nc; ++a) {
            const int ca = cols[a];
            const Vec3 Ja = J.col(ca);
            const Vec3 mJ = ml * Ja;
            LU.col(ca).template head<3>() += cl.cross(mJ);
            LU.col(ca).template tail<3>() += mJ;
            u[ca] -= Ja.dot(f);
            for (int b = 0; b <= a; ++b) LD(ca, cols[b]) += mJ.dot(J.col(cols[b]));
          }
          wsum.head<3>() += cl.cross(f);
          wsum.tail<3>() += f;
          msum += ml;
          m2 += ml * cl.squaredNorm();
          mc += ml * cl;
          mcc.noalias() += ml * cl * cl.transpose();
        }
        for (int a = 0; a < m; ++a)
          for (int b = a + 1; b < m; ++b) LD(a, b) = LD(b, a);
        // sum of spatial_inertia(m, c, 0): (m [c]^T [c], m [c]; m [c]^T, m I).
        const Mat3 C = lie::hat(mc);
        Mat6& LI = link_I_[k];
        LI.template topLeftCorner<3, 3>() = m2 * Mat3::Identity() - mcc;
        LI.template topRightCorner<3, 3>() = C;
        LI.template bottomLeftCorner<3, 3>() = C.transpose();
        LI.template bottomRightCorner<3, 3>() = msum * Mat3::Identity();
        IAsum += LI;
        LD(3, 3) += kPhiInertia * phi_mass(k) * length_[k] * length_[k];
        U += LU;
        D += LD;
        link_U_[k] = LU;
        link_D_[k] = LD;
      }
    }
    // D = S^T IA S is symmetric positive definite (an articulated inertia; PRB's phi has its
    // added inertia): PRB's 5 x 5 inverse by Cholesky, cheaper than the pivoted LU of inverse(),
    // which stays the fallback should rounding make D indefinite.
    // (CCsub's 3 x 3: Eigen's closed-form inverse is cheaper still.)
    Mm Dinv;
    if (m == 3 || !spd_inverse<m>(D, Dinv)) Dinv = D.inverse();
    Us[k] = U;
    Dinvs[k] = Dinv;
    us[k] = u;
    if (k > 1) {
      const Um UD = U * Dinv;
      IA = Io_[k - 1] + IAsum - UD * U.transpose();
      pA = pbody_[k - 1] + wsum + UD * u;
    }
  }
  // Outward: the accelerations.
  Vec6 a = Vec6::Zero();
  for (int k = 1; k <= N_; ++k) {
    const Vm x = Dinvs[k] * (us[k] - Us[k].transpose() * a);
    qdd.segment<m>(m * (k - 1)) = x;
    a += A_[k] - A_[k - 1];
    a.noalias() += T_.middleCols<m>(m * (k - 1)) * x;
  }
}

template <int m>
bool LumpedDynamics::chain_factor(const NewtonMatrix& nm, double gamma) {
  // articulated_m()'s inward pass at the Jacobian's q (nm) without velocities: the articulated
  // inertias of M, with gamma D + gamma^2 Kd_k added to joint k's m x m block as a joint's own
  // inertia is. Kd_k is not symmetric (PRB's phi row, the load terms), so neither are the
  // articulated inertias below joint k: IA_{k-1} = ... - (IA T) D^-1 (T^T IA), kept as two
  // factors.
  using Um = Eigen::Matrix<double, 6, m>;
  using Mm = Eigen::Matrix<double, m, m>;
  ChainFactors<m>& F = chain_store<m>();
  const double g2 = gamma * gamma;
  Mat6 IA = nm.Io[N_];
  for (int k = N_; k >= 1; --k) {
    const auto Tk = nm.T.template middleCols<m>(m * (k - 1));
    Um UL = IA * Tk;
    Um UR = IA.transpose() * Tk;
    Mm D = Tk.transpose() * UL;
    Mat6 IAsum = IA;
    if constexpr (m == 5) {
      if (links_) {
        UL += nm.link_U[k];
        UR += nm.link_U[k];
        D += nm.link_D[k];
        IAsum += nm.link_I[k];
      }
    }
    D.noalias() += g2 * nm.Kd.template middleCols<m>(m * (k - 1));
    D.diagonal() += gamma * nm.D.template segment<m>(m * (k - 1));
    Mm Dinv;
    if (!general_inverse<m>(D, Dinv) || !all_finite(Dinv)) return false;
    F.UL[k] = UL;
    F.UR[k] = UR;
    F.Dinv[k] = Dinv;
    if (k > 1) IA = nm.Io[k - 1] + IAsum - (UL * Dinv) * UR.transpose();
  }
  return all_finite(IA);
}

template <int m>
void LumpedDynamics::chain_solve(const double* b, double gamma) {
  // articulated_m()'s two passes with the factors of chain_factor() and no velocity terms.
  using Vm = Eigen::Matrix<double, m, 1>;
  ChainFactors<m>& F = chain_store<m>();
  const NewtonMatrix& nm = *chain_nm_;
  const Twists& T = nm.T;
  double* z = chain_b_.data();
  Vec6 p = Vec6::Zero();
  for (int k = N_; k >= 1; --k) {
    const int r0 = m * (k - 1);
    const Vm b1 = Eigen::Map<const Vm>(b + r0), b2 = Eigen::Map<const Vm>(b + n_ + r0);
    Vm tau = nm.D.template segment<m>(r0).cwiseProduct(b2);
    tau.noalias() += nm.Kd.template middleCols<m>(r0) * (b1 + gamma * b2);
    const Vm u = tau - T.template middleCols<m>(r0).transpose() * p;
    F.u[k] = u;
    if (k > 1) p.noalias() += F.UL[k] * (F.Dinv[k] * u);
  }
  Vec6 a = Vec6::Zero();
  for (int k = 1; k <= N_; ++k) {
    const Vm x = F.Dinv[k] * (F.u[k] - F.UR[k].transpose() * a);
    Eigen::Map<Vm>(z + m * (k - 1)) = x;
    a.noalias() += T.template middleCols<m>(m * (k - 1)) * x;
  }
}

template bool LumpedDynamics::chain_factor<3>(const NewtonMatrix&, double);
template bool LumpedDynamics::chain_factor<5>(const NewtonMatrix&, double);
template void LumpedDynamics::chain_solve<3>(const double*, double);
template void LumpedDynamics::chain_solve<5>(const double*, double);

void LumpedDynamics::articulated(Eigen::Map<Eigen::VectorXd>& qdd) {
  if (m_ == 3)
    articulated_m<3>(qdd);
  else
    articulated_m<5>(qdd);
}

void LumpedDynamics::mass_matrix() {
  // Composite inertias from the tip: IC_j = sum of the disks k >= j.
  body_inertias();
  IC_[N_ + 1].setZero();
  for (int k = N_; k >= 1; --k) {
    IC_[k] = IC_[k + 1] + Io_[k];
    // PRB: the links of subsegment k + 1 are rigid with disk k.
    if (links_ && k < N_)
      for (int i = 0; i < kLinks; ++i)
        if (!link_rigid(i))  // (the rigid ones are in Io_[k])
          IC_[k] += spatial_inertia(link_mass_[kLinks * (k + 1) + i], link_c_[kLinks * (k + 1) + i], Mat3::Zero());
  }
  // Block (a, b), a <= b: the bodies moving rigidly with both columns are the disks k >= b and
  // the links of subsegments > b; PRB: the links of b move with its columns through link_J_.
  // Fixed-size blocks (CCsub 3, PRB 5 columns per subsegment).
  if (m_ == 3)
    mass_blocks<3>();
  else
    mass_blocks<5>();
  if (links_)
    for (int j = 1; j <= N_; ++j) {
      // The diagonal block's own links: U above holds their rigid part (twist T of b), which
      // for b's own columns is not their motion: replace it by J^T m J.
      const auto Tj = T_.middleCols<5>(5 * (j - 1));
      Eigen::Matrix<double, 5, 5> own = Eigen::Matrix<double, 5, 5>::Zero();
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * j + i;
        const Eigen::Matrix<double, 3, 5>& J = link_J_[l];
        // The rigid motion of the link's point by the columns of b: v_o + w x c.
        Eigen::Matrix<double, 3, 5> P;
        for (int r = 0; r < 5; ++r) P.col(r) = Tj.col(r).tail<3>() + Tj.col(r).head<3>().cross(link_c_[l]);
        own.noalias() += link_mass_[l] * ((J - P).transpose() * J);
      }
      M_.block<5, 5>(5 * (j - 1), 5 * (j - 1)) += own;
      M_(m_ * (j - 1) + 3, m_ * (j - 1) + 3) += kPhiInertia * phi_mass(j) * length_[j] * length_[j];
    }
}

void LumpedDynamics::bias(const double* q, const double* v) {
  Eigen::Map<const Eigen::VectorXd> qv(q, n_), vv(v, n_);
  const double vn = vv.norm();
  // The columns' rates T' = dT/dq q' by a forward difference along q', from the twists at q
  // (T_) and one more set at q + h q' (a central difference took two: with the closed-form
  // rates the twists are exact to rounding, so the step can be small enough, kBiasStep, for a
  // first-order difference; paper robot scene, bench_dynamics: PRB's right-hand side one twist
  // set cheaper).
  const bool moving = vn > 0.0;
  bias_h_ = 0.0;
  double h = 0.0;
  if (moving) {
    h = kBiasStep / vn;
    bias_h_ = h;
    // The step's twists() overwrite the frames and poses: keep those of q (aside in the buffers
    // frames_q_, poses_q_ by a swap; not a second pose set at q: its sines and cosines were a
    // tenth of PRB's right-hand side).
    frames_b_.swap(frames_q_);
    poses_.swap(poses_q_);
    qs_ = qv + h * vv;
    twists_along(qs_.data(), v);
    if (links_) {
      // PRB: the links' accelerations at q'' = 0, d/dt of their velocities
      // V_{j-1}.v + V_{j-1}.w x c + J_l v_j, by the same forward difference (into link_stencil_[2]).
      Vec6 V0 = Vec6::Zero(), V1 = Vec6::Zero();
      for (int j = 1; j <= N_; ++j) {
        const auto vj = vv.segment<5>(5 * (j - 1));
        for (int i = 0; i < kLinks; ++i) {
          if (link_rigid(i)) continue;  // part of disk j - 1 (body_inertias())
          const int l = kLinks * j + i;
          const Vec3& c0 = link_c_[l];
          const Vec3& c1 = link_stencil_[3][l];
          const Vec3 u0 = V0.tail<3>() + V0.head<3>().cross(c0) + link_J_[l] * vj;
          const Vec3 u1 = V1.tail<3>() + V1.head<3>().cross(c1) + ljv_step_[l];
          link_stencil_[2][l] = (u1 - u0) / h;
        }
        V0.noalias() += T_.middleCols<5>(5 * (j - 1)) * vj;
        V1 += tv_step_[j];
      }
    }
    frames_b_.swap(frames_q_);  // back to q
    poses_.swap(poses_q_);
  }
  // Spatial velocities and bias accelerations of the disks, from the base.
  Vec6 V = Vec6::Zero(), A = Vec6::Zero();
  for (int k = 1; k <= N_; ++k) {
    Vec6 tv;
    if (m_ == 5)
      tv.noalias() = T_.middleCols<5>(5 * (k - 1)) * vv.segment<5>(5 * (k - 1));
    else
      tv.noalias() = T_.middleCols<3>(3 * (k - 1)) * vv.segment<3>(3 * (k - 1));
    V += tv;
    if (moving) A += (tv_step_[k] - tv) / h;
    V_[k] = V;
    A_[k] = A;
  }
  // The disks' wrenches at zero acceleration: velocity products, minus drag (articulated()
  // adds the inertial part, and PRB's links).
  for (int k = N_; k >= 1; --k) {
    Vec6 f = Vec6::Zero();
    if (moving) f = cross_force(V_[k], Io_[k] * V_[k]);
    if (settings_.air_drag > 0.0) {
      const Vec3& p = frames_b_[k].p;
      const Vec3 vel = V_[k].tail<3>() + V_[k].head<3>().cross(p);
      const Vec3 drag = -settings_.air_drag * air_length_[k] * vel.norm() * vel;
      f.head<3>() -= p.cross(drag);
      f.tail<3>() -= drag;
    }
    pbody_[k] = f;
  }
}

double LumpedDynamics::spring(int i, const double* q) const {
  const int j = i / m_ + 1, c = i % m_;
  const double EI = body_.EI, GJ = body_.GJ, l = length_[j];
  if (m_ == 3) return c == 2 ? GJ / l : EI / l;
  if (c == 4) return GJ / l;
  const auto& prb = model_.effects().prb;
  if (c < 3) return prb.k_theta[c] * EI / l;
  // phi: turning the plane of a bend a changes the curvature vector's direction at the rate a.
  const double a = q[m_ * (j - 1)] + q[m_ * (j - 1) + 1] + q[m_ * (j - 1) + 2];
  return prb.k_theta[1] * EI / l * a * a;
}

double LumpedDynamics::kinetic_energy(const double* q, const double* v) {
  // v^T M v / 2 body by body (O(N), M is not formed): disk k moves with the spatial velocity
  // V_k = sum_{j <= k} T_j v_j; the links of subsegment k with V_{k-1} and their own rates. The
  // products T_j v_j and J_l v_j of twists_along() are all it takes (not every column, twists():
  // at every output step that was 6 % of a PRB run, callgrind, bench_dynamics --models prb).
  twists_along(q, v);
  Eigen::Map<const Eigen::VectorXd> vv(v, n_);
  const std::vector<Vec3>& c = link_stencil_[3];
  double ke = 0.0;
  Vec6 V = Vec6::Zero();
  for (int k = 1; k <= N_; ++k) {
    if (links_) {
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * k + i;
        const Vec3 vel = V.tail<3>() + V.head<3>().cross(c[l]) + ljv_step_[l];
        ke += 0.5 * link_mass_[l] * vel.squaredNorm();
      }
      const double vphi = vv[m_ * (k - 1) + 3];
      ke += 0.5 * kPhiInertia * phi_mass(k) * length_[k] * length_[k] * vphi * vphi;
    }
    V += tv_step_[k];
    const Frame& f = frames_b_[k];
    const Vec3 w_body = f.R.transpose() * V.head<3>();
    const Vec3 vel = V.tail<3>() + V.head<3>().cross(f.p);
    ke += 0.5 * (mass_[k] * vel.squaredNorm() + w_body.dot(inertia_[k].asDiagonal() * w_body));
  }
  return ke;
}

double LumpedDynamics::phi_mass(int j) const {
  double mj = mass_[j];  // disk j and the subsegment's links (massless disks: the links alone)
  for (int i = 0; i < kLinks; ++i) mj += link_mass_[kLinks * j + i];
  return mj;
}

double LumpedDynamics::potential_energy(const double* q) {
  double U = 0.0;
  for (int i = 0; i < n_; ++i) {
    const int c = i % m_;
    if (m_ == 5 && c == 3) continue;  // phi: no spring of its own
    U += 0.5 * spring(i, q) * q[i] * q[i];
  }
  // Conservative loads: gravity on the lumped masses, the tip force, constant tendon tensions.
  const Loads& L = input_.loads;
  for (int k = 1; k <= N_; ++k) U -= mass_[k] * L.gravity.dot(frames_b_[k].p);
  if (links_)
    for (int l = kLinks; l < kLinks * (N_ + 1); ++l) U -= link_mass_[l] * L.gravity.dot(link_stencil_[3][l]);
  U -= L.tip_force.dot(frames_b_[N_].p);
  if (input_.actuation.kind == Actuation::Kind::Tensions && !input_.actuation.mixed()) {
    const TendonRouting& routing = body_.statics.routing();
    for (const RoutedTendon& t : routing.tendons) {
      const double T = input_.actuation.values[t.index];
      if (T == 0.0) continue;
      Vec3 prev = physics::hole_position(frames_b_[0], t, routing.disk_s[0]);
      for (int c = 1; c <= t.end_disk; ++c) {
        const Vec3 h = physics::hole_position(frames_b_[c], t, routing.disk_s[c]);
        U += T * (h - prev).norm();
        prev = h;
      }
    }
  }
  return U;
}

Eigen::VectorXd LumpedDynamics::frequencies(const Eigen::VectorXd& x, const ModelInput& input) {
  size_dense();
  last_valid_ = false;
  timeline_ = nullptr;
  input_ = input;
  bound_valid_ = false;
  input_at(0.0);
  twists(x.data(), T_);
  if (!generalized_force(x.data())) throw std::runtime_error("lumped dynamics: residual failed");
  mass_matrix();
  // K = -dQ/dq by central differences of Q (the model's Jacobian is a forward difference).
  Eigen::VectorXd xp = x, Q0(n_);
  for (int i = 0; i < n_; ++i) {
    const double h = 1e-6;
    xp[i] = x[i] + h;
    twists(xp.data(), T_);
    generalized_force(xp.data());
    Q0 = Q_;
    xp[i] = x[i] - h;
    twists(xp.data(), T_);
    generalized_force(xp.data());
    K_.col(i) = -(Q0 - Q_) / (2.0 * h);
    xp[i] = x[i];
  }
  twists(x.data(), T_);
  mass_matrix();
  // PRB: phi is no coordinate of a straight subsegment (a polar angle at zero bend): held fixed.
  std::vector<int> keep;
  for (int i = 0; i < n_; ++i)
    if (!(m_ == 5 && i % m_ == 3)) keep.push_back(i);
  const int nk = static_cast<int>(keep.size());
  Eigen::MatrixXd Ks(nk, nk), Mk(nk, nk);
  for (int a = 0; a < nk; ++a)
    for (int b = 0; b < nk; ++b) {
      Ks(a, b) = 0.5 * (K_(keep[a], keep[b]) + K_(keep[b], keep[a]));
      Mk(a, b) = M_(keep[a], keep[b]);
    }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Ks, Mk);
  Eigen::VectorXd f = es.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * M_PI);
  std::sort(f.data(), f.data() + f.size());
  return f;
}

}  // namespace tdcr::detail
