// Stability of a VCref equilibrium: the reduced stiffness in the disk poses.
//
// VCref's loads are conservative (Eq. 58 aside): the tendon pieces between the disks derive from
// the potential sum T_k l_k (l_k the chord lengths, functions of the disk poses), the tip force
// and the weights are dead loads. With the disk poses g_1..g_N as coordinates (g_0 the clamped
// base) and every rod between two disks in its equilibrium for the given end poses, the total
// potential is V(g) = sum_j E_j(g_j, g_j+1) + sum_k T_k l_k(g) - dead loads . displacements. Its
// gradient along (dp, R dtheta) at disk i is the disk's equilibrium residual E_i = (F_i, R_i^T M_i)
// (rod end wrenches minus the disk's tendon and weight loads, moments about the disk's backbone
// point), and at an equilibrium its Hessian is
//   K = dE / dg,  block tridiagonal, symmetric.
// The equilibrium is stable iff K is positive definite. This is the Hessian of the full potential
// reduced onto the disk poses (a Schur complement over the rod shapes); the two agree in inertia
// as long as each rod between two disks is itself stable with clamped ends, i.e. below its own
// buckling loads ~ pi^2 EI / h^2 (h the disk spacing), far above VCref's loads.
//
// Each rod's contribution comes from its transfer matrix: the variation of its end (pose, wrench)
// with its start (pose, wrench), [A B; C D], by forward differences (9 shots per interval: the
// position columns are the identity, the free rod being translation invariant; with RK4 and
// without the backbone's weight 6, the rotation columns following from the rod's rotation
// invariance; 6 for the first, whose start pose is the clamp; by the integrator the caller
// gives: the test's coarse RK4 mesh when the solve integrates with RK4,
// solve/stability_mesh.hpp). Its start wrench follows from both end poses,
// dw_j = B^-1 (dg_j+1 - A dg_j), and its end wrench dv_j+1 = C dg_j + D dw_j; disk i receives
// +dv_i - dw_i. The tendon wrenches are differentiated by forward differences of
// tendon::disk_wrench in the poses of the disks i-1, i, i+1 (no integration). Rows of moments are
// turned into the disk's body frame (R_i^T), the terms of R_i^T's variation vanish at an
// equilibrium. Dimensionless and per backbone length: Ks = (L / EI) S K S, S = sqrt(L / w_i)
// diag(L I, I) at disk i (w_i the backbone length it stands for), so that the margin converges
// as disks are added.
// A Kirchhoff rod (no shear or extension) has a singular B when straight: its shear and
// extension compliance is added as a penalty (stiff directions, inertia of the rest unchanged).
//   margin = the smallest eigenvalue of the symmetric part of Ks,
// to 1e-4 relative: where Ks is positive definite from Lanczos on Ks^-1, the bound checked by
// one block Cholesky factorisation (O(N) each), else by bisection on whether the block Cholesky
// factorisation of Ks - sigma I exists; stable if
// > 1e-6, unstable if < -1e-6, else undetermined (forward-difference noise). With Eq. 58 (disk
// normal forces removed) and a tensioned tendon the loads are not conservative and K is not
// symmetric; a positive definite symmetric part still excludes divergence (x' K x > 0 for every
// x: no real eigenvalue <= 0), so "stable" stays sound, "unstable" is then the energy criterion.
// On the paper's configurations with tip forces its smallest eigenvalue and the smallest real
// part of K's eigenvalues agree within 1 % (docs/design-notes/vcref.md).
// With contact (docs/contact.md, "Stability with contact"): a candidate's force at its disk, held
// at its magnitude, moves and turns with the disk's pose (differentiated like the tendons'); a
// compliant one's magnitude follows its gap (its penalty). A rigid contact with force constrains
// its disk's scaled pose to the tangent space of its gap: in the basis [Z Y] of that pose (Y
// along the gap's gradient) the Y rows and columns are pinned to a value above the eigenvalues of
// interest, so the smallest eigenvalue is Z^T K Z's exactly (Cauchy interlacing: never below the
// unconstrained one) and K stays block tridiagonal. Weakly active contacts: open, then closed.
#include "vcref/vcref_stability.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

#include "physics/contact_cone.hpp"
#include "physics/least_stable_mode.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using State = cosserat::State;

constexpr double kUndecided = 1e-6;
/// Largest disk count for a dense eigen-solve of a non-symmetric K (6 N unknowns; 240 at 40 disks).
constexpr int kDenseDisks = 100;

// Moves the state y along its local coordinate c (0-2 position, 3-5 rotation in the body frame,
// 6-8 force, 9-11 moment) by h.
void perturb(double* y, int c, double h) {
  if (c < 3) {
    cosserat::position(y)[c] += h;
  } else if (c < 6) {
    Vec3 w = Vec3::Zero();
    w[c - 3] = h;
    const Mat3 R = cosserat::rotation(y) * lie::exp_so3(w);
    cosserat::rotation(y) = R;
  } else if (c < 9) {
    cosserat::force(y)[c - 6] += h;
  } else {
    cosserat::moment(y)[c - 9] += h;
  }
}

// a - b in the local coordinates of b.
Eigen::Matrix<double, 12, 1> difference(const State& a, const State& b) {
  Eigen::Matrix<double, 12, 1> d;
  d.segment<3>(0) = cosserat::position(a.data()) - cosserat::position(b.data());
  d.segment<3>(3) = lie::log_so3(cosserat::rotation(b.data()).transpose() * cosserat::rotation(a.data()));
  d.segment<3>(6) = cosserat::force(a.data()) - cosserat::force(b.data());
  d.segment<3>(9) = cosserat::moment(a.data()) - cosserat::moment(b.data());
  return d;
}

// Frame f moved along its local coordinate c (0-2 position, 3-5 body rotation) by h.
Frame moved(const Frame& f, int c, double h) {
  Frame g = f;
  if (c < 3) {
    g.p[c] += h;
  } else {
    Vec3 w = Vec3::Zero();
    w[c - 3] = h;
    g.R = f.R * lie::exp_so3(w);
  }
  return g;
}

// A block tridiagonal matrix of 6 x 6 blocks (the reduced stiffness: disk i couples to i +- 1).
class BlockTridiagonal {
 public:
  explicit BlockTridiagonal(int n)
      : n_(n), diag_(n, Mat6::Zero()), upper_(n, Mat6::Zero()), lower_(n, Mat6::Zero()), llt_(n), pinv_u_(n), w_(n) {}
  // A copy takes the blocks, not the factors of the last above() (an unfactorised LLT's state is
  // uninitialised, and copying it reads it).
  BlockTridiagonal(const BlockTridiagonal& o) : BlockTridiagonal(o.n_) {
    diag_ = o.diag_;
    upper_ = o.upper_;
    lower_ = o.lower_;
  }
  BlockTridiagonal& operator=(const BlockTridiagonal& o) {
    if (this != &o) *this = BlockTridiagonal(o);  // the move assignment below
    return *this;
  }
  BlockTridiagonal(BlockTridiagonal&&) = default;
  BlockTridiagonal& operator=(BlockTridiagonal&&) = default;
  // Block (i, k), |i - k| <= 1, zero-based.
  Mat6& at(int i, int k) { return k == i ? diag_[i] : k > i ? upper_[i] : lower_[k]; }
  void symmetrize() {
    for (int i = 0; i < n_; ++i) {
      diag_[i] = (0.5 * (diag_[i] + diag_[i].transpose())).eval();
      if (i + 1 < n_) upper_[i] = lower_[i].transpose() = (0.5 * (upper_[i] + lower_[i].transpose())).eval();
    }
  }
  // The whole matrix (for the eigenvalues of a non-symmetric K).
  Eigen::MatrixXd dense() const {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * n_, 6 * n_);
    for (int i = 0; i < n_; ++i) {
      A.block<6, 6>(6 * i, 6 * i) = diag_[i];
      if (i + 1 < n_) {
        A.block<6, 6>(6 * i, 6 * i + 6) = upper_[i];
        A.block<6, 6>(6 * i + 6, 6 * i) = lower_[i];
      }
    }
    return A;
  }
  // Symmetric: whether K - sigma I is positive definite, i.e. no eigenvalue lies below sigma
  // (Sylvester's law of inertia): the block Cholesky factorisation, pivots
  // P_i = K_ii - sigma I - K_i,i-1 P_i-1^-1 K_i-1,i, succeeds.
  // The factors (llt_, pinv_u_) of the last call are kept: those of K - sigma I if it returned
  // true.
  bool above(double sigma) {
    Mat6 P;
    for (int i = 0; i < n_; ++i) {
      P = diag_[i] - sigma * Mat6::Identity();
      if (i > 0) P -= lower_[i - 1] * pinv_u_[i - 1];
      llt_[i].compute(P);
      if (llt_[i].info() != Eigen::Success) return false;
      if (i + 1 < n_) pinv_u_[i] = llt_[i].solve(upper_[i]);
    }
    return true;
  }
  // Symmetric and positive definite, its factors at sigma = 0 kept by above(0): an upper bound
  // of the smallest eigenvalue, 1 / (the largest Ritz value of Lanczos on K^-1), the Lanczos
  // vectors fully reorthogonalised, until it changes by less than 1e-7 relative (at most
  // kLanczosSteps); infinity if it breaks down.
  double lanczos_bound() {
    constexpr int kLanczosSteps = 40;
    const int m = std::min(kLanczosSteps, 6 * n_);
    basis_.resize(static_cast<std::size_t>(m + 1) * n_);
    auto q = [&](int k, int i) -> Vec6& { return basis_[static_cast<std::size_t>(k) * n_ + i]; };
    for (int i = 0; i < n_; ++i) q(0, i).setConstant(1.0 / std::sqrt(6.0 * n_));  // every direction
    Eigen::VectorXd alpha(m), beta(m);
    double last = 0.0;
    for (int k = 0; k < m; ++k) {
      // w = K^-1 q_k: forward, diagonal and backward sweeps of the block factorisation.
      for (int i = 0; i < n_; ++i) {
        Vec6 y = q(k, i);
        if (i > 0) y -= lower_[i - 1] * w_[i - 1];
        w_[i] = llt_[i].solve(y);
      }
      for (int i = n_ - 2; i >= 0; --i) w_[i] -= pinv_u_[i] * w_[i + 1];
      for (int pass = 0; pass < 2; ++pass)  // full reorthogonalisation, twice
        for (int l = 0; l <= k; ++l) {
          double c = 0.0;
          for (int i = 0; i < n_; ++i) c += q(l, i).dot(w_[i]);
          if (pass == 0 && l == k) alpha[k] = c;
          for (int i = 0; i < n_; ++i) w_[i] -= c * q(l, i);
        }
      double b = 0.0;
      for (int i = 0; i < n_; ++i) b += w_[i].squaredNorm();
      b = std::sqrt(b);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(
          [&] {
            Eigen::MatrixXd Tk = Eigen::MatrixXd::Zero(k + 1, k + 1);
            for (int l = 0; l <= k; ++l) {
              Tk(l, l) = alpha[l];
              if (l < k) Tk(l, l + 1) = Tk(l + 1, l) = beta[l];
            }
            return Tk;
          }(),
          Eigen::EigenvaluesOnly);
      const double theta = ritz.eigenvalues()[k];
      if (!(theta > 0.0) || !std::isfinite(theta)) return std::numeric_limits<double>::infinity();
      if (k > 0 && std::abs(theta - last) <= 1e-7 * theta) return 1.0 / theta;
      last = theta;
      if (!(b > 1e-300) || k + 1 == m) return 1.0 / theta;  // an invariant subspace, or the last step
      beta[k] = b;
      for (int i = 0; i < n_; ++i) q(k + 1, i) = w_[i] / b;
    }
    return 1.0 / last;
  }
  // Symmetric: the smallest eigenvalue to 1e-4 relative and 1e-9 absolute. Where K is positive
  // definite, the Lanczos bound q from above and above(q (1 - 5e-5)) from below (2
  // factorisations and a few sweeps); otherwise (or if that lower bound fails) by bisection on
  // above(), from [0, smallest diagonal entry] (or a negative bound found by doubling).
  double smallest_eigenvalue() {
    double hi = std::numeric_limits<double>::infinity();
    for (const Mat6& D : diag_) hi = std::min(hi, D.diagonal().minCoeff());
    double lo = 0.0;
    if (hi > 0.0 && !above(0.0)) hi = 0.0;
    if (hi > 0.0) {
      const double q = std::min(hi, lanczos_bound());
      if (q < hi) {
        hi = q;
        if (above(q * (1.0 - 5e-5))) lo = q * (1.0 - 5e-5);
      }
    }
    if (hi <= 0.0) {
      lo = std::min(hi, -1e-3);
      for (int it = 0; it < 60 && !above(lo); ++it) lo *= 4.0;
    }
    for (int it = 0; it < 200 && hi - lo > 1e-9 + 1e-4 * std::min(std::abs(lo), std::abs(hi)); ++it) {
      const double mid = 0.5 * (lo + hi);
      (above(mid) ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }

 private:
  int n_;
  std::vector<Mat6> diag_, upper_, lower_;  // upper_[i] = (i, i+1), lower_[i] = (i+1, i)
  // above(): the Cholesky factors of the pivots P_i and P_i^-1 upper_[i]; lanczos_bound()'s
  // vectors.
  std::vector<Eigen::LLT<Mat6>> llt_;
  std::vector<Mat6> pinv_u_;
  std::vector<Vec6> w_, basis_;
};

}  // namespace

Stability disk_pose_stability(const VcrefShooting& problem, bvp::Integrator& integrator,
                              const bvp::ShootingNodes& nodes) {
  Stability out;
  out.method = "reduced stiffness in the disk poses (rod transfer matrices and tendon chords), smallest eigenvalue";
  const VcrefModel::Data& d = problem.data();
  const int N = d.N;
  const std::vector<double>& s = d.routing->disk_s;
  const double EI = d.section.kbt.x(), L = d.length;
  const double rel = std::sqrt(std::max(std::numeric_limits<double>::epsilon(), integrator.relative_noise()));
  BlockTridiagonal K(N);
  auto block = [&](int i, int k) -> Mat6& { return K.at(i - 1, k - 1); };

  // The rods: transfer matrices, integrated from p = 0 (the free rod is translation invariant;
  // without the backbone's weight rotation invariant too, so 6 shots per interval with RK4;
  // CVODE keeps every rotation shot, the reference test).
  const bool rotation_invariant = !d.section.gravity && dynamic_cast<const bvp::Rk4Integrator*>(&integrator);
  std::vector<Frame> frames(N + 1);
  State y0, nominal, y;
  Eigen::Matrix<double, 12, 12> T;
  for (int j = 0; j < N; ++j) {
    y0 = Eigen::Map<const State>(nodes.start(j));
    frames[j] = cosserat::frame_of(y0.data());
    cosserat::position(y0.data()).setZero();
    nominal = y0;
    const bvp::OdeSystem& rod = problem.ode(j);
    if (!integrator.integrate(rod, s[j], s[j + 1], nominal.data())) {
      out.method += "; a rod shot failed";
      return out;
    }
    if (j == N - 1) {
      frames[N] = cosserat::frame_of(nodes.end(N - 1));
      frames[N].R = lie::nearest_rotation(frames[N].R);
    }
    // Natural scales of the interval: h, 1, EI / h^2, EI / h.
    const double h = s[j + 1] - s[j];
    const double scale[4] = {h, 1.0, EI / (h * h), EI / h};
    for (int c = j == 0 ? 6 : 0; c < 12; ++c) {
      if (c < 3) {  // the free rod is translation invariant: a start position moves the end alike
        T.col(c).setZero();
        T(c, c) = 1.0;
        continue;
      }
      if (c < 6 && rotation_invariant) continue;  // below
      const double value = c < 6 ? 0.0 : y0[12 + c - 6];
      const double step = rel * std::max(std::abs(value), scale[c / 3]);
      y = y0;
      perturb(y.data(), c, step);
      if (!integrator.integrate(rod, s[j], s[j + 1], y.data())) {
        out.method += "; a perturbed rod shot failed";
        return out;
      }
      T.col(c) = difference(y, nominal) / step;
    }
    if (j > 0 && rotation_invariant) {
      // Without weights the free rod is invariant under a rotation Q of its whole start state
      // about its start point, (R, n, m) -> (Q R, Q n, Q m): its end turns alike. A body rotation
      // w of R alone is that rigid rotation, spatial Q = exp(R_0 w), less the wrench perturbation
      // (Q n - n, Q m - m), whose response is the wrench columns'; so the rotation columns need
      // no shots.
      const Mat3 R0 = cosserat::rotation(y0.data()), Re = cosserat::rotation(nominal.data());
      const Vec3 pe = cosserat::position(nominal.data()), ne = cosserat::force(nominal.data()),
                 me = cosserat::moment(nominal.data()), n0 = cosserat::force(y0.data()),
                 m0 = cosserat::moment(y0.data());
      for (int c = 3; c < 6; ++c) {
        const Vec3 w = R0.col(c - 3);  // the spatial rotation of body rotation e_(c-3)
        Eigen::Matrix<double, 12, 1> rigid;
        rigid << w.cross(pe), Re.transpose() * w, w.cross(ne), w.cross(me);
        T.col(c) = rigid - T.middleCols<3>(6) * w.cross(n0) - T.middleCols<3>(9) * w.cross(m0);
      }
    }
    // A Kirchhoff rod's end pose does not see an axial force (B is singular when straight): the
    // compliance of shear and extension is added as a penalty on the constrained directions
    // (their stiffness ~ GA / h, EA / h, far above every other term; the sign of the smallest
    // eigenvalue is the constrained one's).
    if (!d.section.shear_extension) {
      const Mat3 R = cosserat::rotation(y0.data());
      T.block<3, 3>(0, 6) += h * R * d.section.inv_kse.asDiagonal() * R.transpose();
    }
    // B^-1 through the dimensionless B (its entries span h^3 / EI to 1 otherwise).
    Vec6 pose_scale, wrench_scale;
    pose_scale << h, h, h, 1.0, 1.0, 1.0;
    wrench_scale << scale[2], scale[2], scale[2], scale[3], scale[3], scale[3];
    const Eigen::FullPivLU<Mat6> B(pose_scale.asDiagonal().inverse() * T.block<6, 6>(0, 6) *
                                   wrench_scale.asDiagonal());
    if (!B.isInvertible()) {
      out.method += "; a rod's end pose does not determine its wrench";
      return out;
    }
    const Mat6 Binv = wrench_scale.asDiagonal() * B.inverse() * pose_scale.asDiagonal().inverse();
    const Mat6 D = T.block<6, 6>(6, 6);
    block(j + 1, j + 1) += D * Binv;
    if (j == 0) continue;
    const Mat6 A = T.block<6, 6>(0, 0), C = T.block<6, 6>(6, 0);
    block(j + 1, j) += C - D * Binv * A;
    block(j, j + 1) -= Binv;
    block(j, j) += Binv * A;
  }

  // The tendons: disk i's wrench depends on the poses of disks i-1, i, i+1.
  const TendonRouting& active = problem.active();
  const double* tensions = problem.tensions().data();
  std::vector<Frame> moved_frames = frames;
  std::vector<tendon::DiskWrench> unmoved(N + 1);  // every disk's tendon wrench at the answer
  for (int i = 1; i <= N && !active.tendons.empty(); ++i)
    if (problem.tendon_at(i)) unmoved[i] = tendon::disk_wrench(i, frames.data(), active, tensions, d.remove_normal);
  for (int k = 1; k <= N && !active.tendons.empty(); ++k) {
    for (int c = 0; c < 6; ++c) {
      const double step = rel * (c < 3 ? d.l_min : 1.0);
      moved_frames[k] = moved(frames[k], c, step);
      for (int i = std::max(1, k - 1); i <= std::min(N, k + 1); ++i) {
        if (!problem.tendon_at(i)) continue;
        const tendon::DiskWrench a = tendon::disk_wrench(i, moved_frames.data(), active, tensions, d.remove_normal);
        const tendon::DiskWrench& b = unmoved[i];
        block(i, k).col(c).head<3>() -= (a.force - b.force) / step;
        block(i, k).col(c).tail<3>() -= (a.moment - b.moment) / step;
      }
      moved_frames[k] = frames[k];
    }
  }

  // Contact (docs/contact.md, "Stability with contact"): a candidate's force on its disk moves and
  // turns with the disk's pose at fixed magnitude (the contact point, a curved obstacle's normal),
  // differentiated like the tendons' (K_held); a compliant one's magnitude follows its gap too
  // (its penalty: K_compliant). Rigid ones with force are constraints on their disk's pose (below).
  const std::vector<contact::Candidate>& cands = problem.candidates();
  const contact::Law& law = problem.law();
  bool compliant = false;
  BlockTridiagonal K_compliant(0);
  if (!cands.empty()) {
    compliant = law.stiffness > 0.0;
    if (compliant) K_compliant = K;
    const auto contact_wrench = [&](std::size_t i, const Frame& f, bool penalty) {
      const ContactPoint at = problem.contact_at(i, f);
      const double b = penalty ? law.stiffness * std::max(0.0, -at.gap) / law.force_scale : cands[i].lambda;
      const Vec3 force = (b * law.force_scale) * at.normal;
      Vec6 w;
      w << force, (at.point - f.p).cross(force);
      return w;
    };
    for (std::size_t i = 0; i < cands.size(); ++i) {
      const int k = cands[i].disk;
      if (k < 1 || k > N) continue;
      for (const bool penalty : {false, true}) {
        if (penalty && !compliant) continue;
        BlockTridiagonal& target = penalty ? K_compliant : K;
        const Vec6 w0 = contact_wrench(i, frames[k], penalty);
        for (int c = 0; c < 6; ++c) {
          const double step = rel * (c < 3 ? d.l_min : 1.0);
          target.at(k - 1, k - 1).col(c) -= (contact_wrench(i, moved(frames[k], c, step), penalty) - w0) / step;
        }
      }
    }
  }

  // Body-frame moment rows, dimensionless, per backbone length of each disk (w_i: half its two
  // intervals), so that the margin does not shrink with the number of disks.
  std::vector<Mat6> S(N + 1, Mat6::Identity());
  for (int i = 1; i <= N; ++i) {
    const double w = 0.5 * (s[i] - s[i - 1] + (i < N ? s[i + 1] - s[i] : 0.0));
    S[i].diagonal().head<3>().setConstant(L);
    S[i] *= std::sqrt(L / w);
  }
  Mat6 Ri = Mat6::Identity();
  for (BlockTridiagonal* M : {&K, compliant ? &K_compliant : nullptr}) {
    if (!M) continue;
    for (int i = 1; i <= N; ++i) {
      Ri.bottomRightCorner<3, 3>() = frames[i].R.transpose();
      for (int k = std::max(1, i - 1); k <= std::min(N, i + 1); ++k)
        M->at(i - 1, k - 1) = (L / EI) * S[i] * Ri * M->at(i - 1, k - 1) * S[k];
    }
  }

  // Non-conservative loads (Eq. 58 with a tensioned tendon): a positive definite symmetric part
  // proves stability; where it is indefinite, the real parts of K's eigenvalues decide (the
  // quasi-static divergence criterion, as for CCsub and PRB), by a dense eigen-solve up to
  // kDenseDisks disks, else undetermined.
  const bool conservative = !(d.remove_normal && !active.tendons.empty());
  // The verdict of one reduced stiffness (taken by value: symmetrised there), into `st`.
  const auto verdict = [&](BlockTridiagonal M, Stability& st) {
    const Eigen::MatrixXd full = conservative || N > kDenseDisks ? Eigen::MatrixXd() : M.dense();
    // Symmetric up to the difference noise when the loads are conservative.
    M.symmetrize();
    st.margin = M.smallest_eigenvalue();
    if (!conservative) {
      st.method += " of the symmetric part (disk normal forces removed: not conservative, a sufficient test)";
      if (!(st.margin > kUndecided)) {
        if (full.size() == 0) {
          st.method += "; indefinite, and the eigenvalues of K are not computed above " + std::to_string(kDenseDisks) +
                       " disks: undetermined";
          return;
        }
        std::string mode;
        st.margin = detail::least_stable_mode(Eigen::EigenSolver<Eigen::MatrixXd>(full, false).eigenvalues(), mode);
        st.method += "; indefinite: smallest real part of the eigenvalues of K" + mode;
      }
    }
    if (st.margin > kUndecided)
      st.status = StabilityStatus::Stable;
    else if (st.margin < -kUndecided)
      st.status = StabilityStatus::Unstable;
  };
  // Rigid contacts with force (active) and touching ones without (weakly active): their gaps'
  // gradients in the disk's scaled pose, n . dp + dtheta . R^T ((x_c - p) x n), times S.
  std::vector<std::pair<int, Vec6>> strong, weak;
  for (std::size_t i = 0; i < cands.size() && !compliant; ++i) {
    const int k = cands[i].disk;
    if (k < 1 || k > N) continue;
    const ContactPoint at = problem.contact_at(i, frames[k]);
    const bool is_strong = cands[i].lambda > physics::kActiveForce;
    if (!is_strong && !(at.gap / law.length_scale < physics::kTouching)) continue;
    Vec6 G;
    G << at.normal, frames[k].R.transpose() * ((at.point - frames[k].p).cross(at.normal));
    G = (S[k] * G).eval();  // G S (S diagonal)
    (is_strong ? strong : weak).emplace_back(k, G / G.norm());
  }
  if (!compliant && strong.empty() && weak.empty()) {
    verdict(K, out);
    return out;
  }
  // With contacts: the same stiffness with the forces held and no constraints first, what the
  // contacts change; then the compliant one, or the constrained ones.
  Stability held;
  verdict(K, held);
  char buf[200];
  std::snprintf(buf, sizeof buf, "; without the contacts' constraints (forces held) %.9g", held.margin);
  const std::string free_note = buf;
  if (compliant) {
    int penetrated = 0;
    for (std::size_t i = 0; i < cands.size(); ++i) {
      const int k = cands[i].disk;
      if (k >= 1 && k <= N && problem.contact_at(i, frames[k]).gap < 0.0) ++penetrated;
    }
    std::snprintf(buf, sizeof buf, " with the stiffness of %d compliant contacts", penetrated);
    out.method += buf;
    verdict(K_compliant, out);
    out.method += free_note;
    return out;
  }
  // A constrained reduced stiffness: per constrained disk the orthonormal basis [Z Y] of its
  // scaled pose (Y spanning the gaps' gradients), and the Y coordinates pinned (their rows and
  // columns replaced by `pinned` on the diagonal, above every eigenvalue of interest: the
  // smallest eigenvalue is then Z^T K Z's, exactly, and the matrix stays block tridiagonal).
  double pinned = 0.0;
  for (int i = 0; i < N; ++i) pinned = std::max(pinned, K.at(i, i).diagonal().cwiseAbs().maxCoeff());
  std::vector<Mat6> basis(static_cast<std::size_t>(N), Mat6::Identity());  // [Z Y] per disk, last call's
  const auto constrained = [&](bool with_weak) {
    BlockTridiagonal M = K;
    std::fill(basis.begin(), basis.end(), Mat6::Identity());
    for (int disk = 1; disk <= N; ++disk) {
      Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6> G(6, 0);
      for (const auto* list : {&strong, with_weak ? &weak : nullptr}) {
        if (!list) continue;
        for (const auto& [k, g] : *list)
          if (k == disk && G.cols() < 6) {
            G.conservativeResize(6, G.cols() + 1);
            G.col(G.cols() - 1) = g;
          }
      }
      const int c = static_cast<int>(G.cols());
      if (c == 0) continue;
      const Mat6 Q = Eigen::HouseholderQR<Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>>(G).householderQ();
      Mat6 P;  // [Z Y]
      P << Q.rightCols(6 - c), Q.leftCols(c);
      const int i = disk - 1;
      basis[static_cast<std::size_t>(i)] = P;
      M.at(i, i) = (P.transpose() * M.at(i, i) * P).eval();
      for (int j : {i - 1, i + 1}) {
        if (j < 0 || j >= N) continue;
        M.at(i, j) = (P.transpose() * M.at(i, j)).eval();
        M.at(j, i) = (M.at(j, i) * P).eval();
      }
      for (int r = 6 - c; r < 6; ++r) {
        M.at(i, i).row(r).setZero();
        M.at(i, i).col(r).setZero();
        M.at(i, i)(r, r) = pinned;
        for (int j : {i - 1, i + 1}) {
          if (j < 0 || j >= N) continue;
          M.at(i, j).row(r).setZero();
          M.at(j, i).col(r).setZero();
        }
      }
    }
    return M;
  };
  std::snprintf(buf, sizeof buf, " on the tangent space of %d active contacts", static_cast<int>(strong.size()));
  out.method += buf;
  BlockTridiagonal open = constrained(false);
  verdict(open, out);
  if (!weak.empty()) out.method += physics::weakly_active_note(static_cast<int>(weak.size()));
  if (out.status == StabilityStatus::Stable || weak.empty()) {
    out.method += free_note;
    return out;
  }
  // The cone test (physics/contact_cone.hpp): the open form is negative on the span of its
  // negative eigenvectors; a nonzero direction there that no weakly active contact closes proves
  // instability. Conservative loads (a symmetric K) and up to kDenseDisks disks: a dense
  // eigen-solve of the open form, only on this branch.
  if (out.status == StabilityStatus::Unstable && conservative && N <= kDenseDisks) {
    open.symmetrize();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(open.dense());
    if (eig.info() == Eigen::Success) {
      int d = 0;
      while (d < 6 * N && eig.eigenvalues()[d] < -kUndecided) ++d;
      Eigen::MatrixXd Gn(static_cast<int>(weak.size()), d);
      for (std::size_t w = 0; w < weak.size(); ++w) {
        const int i = weak[w].first - 1;
        const Vec6 g = basis[static_cast<std::size_t>(i)].transpose() * weak[w].second;
        Gn.row(static_cast<int>(w)) = g.transpose() * eig.eigenvectors().block(6 * i, 0, 6, d);
      }
      if (physics::cone_has_ray(Gn)) {
        out.method += physics::cone_unstable_note(d, "negative directions") + free_note;
        return out;
      }
    }
  }
  // Not proven stable with the weakly active contacts open: with them closed (a necessary test).
  Stability closed;
  verdict(constrained(true), closed);
  std::snprintf(buf, sizeof buf, "; with them closed %.6g", closed.margin);
  out.method += buf;
  if (closed.status == StabilityStatus::Unstable) {
    out.status = StabilityStatus::Unstable;
    out.margin = closed.margin;
  } else {
    out.status = StabilityStatus::Undetermined;
    out.method += ": undetermined between the two (the cone of the weakly active contacts is not tested)";
  }
  out.method += free_note;
  return out;
}

}  // namespace tdcr
