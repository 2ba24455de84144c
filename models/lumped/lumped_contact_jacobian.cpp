// The Jacobian of the contact system of CCsub and PRB (docs/contact.md): the structured
// differences of lumped_jacobian.cpp with the contact forces in the disk loads, plus
//  - the rows distal of a perturbed subsegment k: a contact force distal of disk k does not move
//    rigidly with the frames (its normal follows the obstacle's surface, a rim point turns in its
//    disk), and its change beyond the rigid motion, pulled back to the unperturbed frames, acts
//    on row j > k through E_j (the response to a change of the distal wrench), summed over the
//    contacts at disks >= j. That change is linear in the column's twist xi_c (w, v: a point x
//    moves by h (w x x + v)): A_i xi_c, A_i (6 x 6) from central differences of candidate i's
//    contact point under twists of its disk, so row j gets E_j B_j xi_c, B_j = sum_{d_i >= j} A_i;
//  - the columns of the force unknowns b_i: a unit force F_s n_i at the contact point c_i of disk
//    d_i changes the distal wrench of every subsegment j <= d_i by (F_s n_i, c_i x F_s n_i), exact
//    through E_j;
//  - the complementarity rows: phi(a, b) with a = g / r_o, its derivatives in closed form, the
//    gap's change per column a_i . xi_c (a_i from the same twists: the gaps depend on the
//    kinematics alone).
// The structured Newton step (contact_setup_newton_step) solves the same Jacobian as the
// block-banded system of lumped_structured.cpp, the twists' partial sums tau_j = sum_{k<j} Xi_k
// d_k (6) in place of the rotations' t_j, the force unknowns b_i entering the wrench sums s_j at
// their disks, and the gap rows a_i . (tau_{d_i} + Xi_{d_i} d_{d_i}): O(J + candidates).
// A column costs the structured one plus one contact point per candidate distal of it, so the
// Jacobian costs about one residual evaluation instead of one per unknown.
// tests/test_contact_lumped.cpp compares it with central differences of the contact residual.
#include <algorithm>
#include <cmath>
#include <utility>

#include "lumped/lumped_problem.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

namespace {
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
}  // namespace

void LumpedProblem::contact_loads() {
  const Eigen::Index nc = static_cast<Eigen::Index>(contacts_.size());
  const int N = body_.N;
  jac_cf_.assign(static_cast<std::size_t>(N) + 2, Vec3::Zero());  // allocates once per N
  jac_cm_.assign(static_cast<std::size_t>(N) + 2, Vec3::Zero());
  jac_A_.resize(6, 6 * nc);
  jac_a_.resize(6, nc);
  jac_B_.setZero(6, 6 * (N + 2));
  jac_Xi_.resize(6, body_.per_subsegment * active());
  for (Eigen::Index i = 0; i < nc; ++i) {
    const ContactCandidate& cand = contacts_[static_cast<std::size_t>(i)];
    const Frame& F = frames_[cand.disk];
    const double fs = cand.lambda * contact_force_scale_;
    const Vec3 f = fs * cand.at.normal;
    jac_cf_[cand.disk] += f;
    jac_cm_[cand.disk] += (cand.at.point - F.p).cross(f);
    // Twists of the disk: rotations of 1e-5 rad (a 10 mm rim moves 0.1 um), translations of
    // 1e-3 r_o; central differences (the obstacles' curvature enters at second order).
    const double radius = cand.body == ContactBody::Disk ? body_.disk_radius[cand.disk] : body_.backbone_radius;
    for (int q = 0; q < 6; ++q) {
      const double eps = q < 3 ? 1e-5 : 1e-3 * contact_length_scale_;
      Vec6 W[2];
      double gap[2];
      for (int side = 0; side < 2; ++side) {
        Vec3 w = Vec3::Zero(), v = Vec3::Zero();
        (q < 3 ? w[q] : v[q - 3]) = side == 0 ? eps : -eps;
        const Mat3 Q = lie::exp_so3(w);
        Frame moved;
        moved.R = Q * F.R;
        moved.p = Q * F.p + v;
        const ContactPoint cp = contact_point(obstacles_[cand.obstacle], moved, cand.body, radius);
        const Vec3 g = Q.transpose() * (fs * cp.normal), u = Q.transpose() * (cp.point - v);
        W[side].head<3>() = g;
        W[side].tail<3>() = u.cross(g);
        gap[side] = cp.gap;
      }
      jac_A_.col(6 * i + q) = (W[0] - W[1]) / (2.0 * eps);
      jac_a_(q, i) = (gap[0] - gap[1]) / (2.0 * eps);
    }
  }
  // B_j = sum of A_i over the candidates at disks >= j.
  for (int j = N; j >= 1; --j) {
    auto B = jac_B_.middleCols<6>(6 * j);
    B = jac_B_.middleCols<6>(6 * (j + 1));
    for (Eigen::Index i = 0; i < nc; ++i)
      if (contacts_[static_cast<std::size_t>(i)].disk == j) B += jac_A_.middleCols<6>(6 * i);
  }
}

void LumpedProblem::contact_column(int k, int c, const Mat3& Q, const Vec3& t, const Frame& fk, const Frame& base_k1,
                                   double h, Vec3& Fk, Vec3& Mk) {
  jac_Xi_.col(c).head<3>() = Vec3(Q(2, 1) - Q(1, 2), Q(0, 2) - Q(2, 0), Q(1, 0) - Q(0, 1)) / (2.0 * h);
  jac_Xi_.col(c).tail<3>() = t / h;
  for (const ContactCandidate& cand : contacts_) {
    const int d = cand.disk;
    if (d < k) continue;  // proximal of the perturbed subsegment: does not move
    // frames_[k + 1] holds the moved frame already; the others their unperturbed values.
    Frame moved = fk;
    if (d > k) {
      const Frame& base = d == k + 1 ? base_k1 : frames_[d];
      moved.R = Q * base.R;
      moved.p = Q * base.p + t;
    }
    const double radius = cand.body == ContactBody::Disk ? body_.disk_radius[d] : body_.backbone_radius;
    const ContactPoint cp = contact_point(obstacles_[cand.obstacle], moved, cand.body, radius);
    const double fs = cand.lambda * contact_force_scale_;
    const Vec3 f1 = fs * cp.normal;
    if (d == k) {  // the loads of disk k are recomputed: add its contact forces
      Fk += f1;
      Mk += (cp.point - fk.p).cross(f1);
      continue;
    }
    // Fk, Mk carry the force f0 at c0 moved rigidly (Q f0 at Q c0 + t): add the difference.
    const Vec3 qf0 = Q * (fs * cand.at.normal);
    Fk += f1 - qf0;
    Mk += (cp.point - fk.p).cross(f1) - (Q * cand.at.point + t - fk.p).cross(qf0);
  }
}

void LumpedProblem::contact_derivatives(std::size_t i, double& da, double& db) const {
  contact_law().derivatives(contacts_[i].at.gap, contacts_[i].lambda, da, db);
}

bool LumpedProblem::contact_jacobian(Eigen::Ref<Eigen::MatrixXd> Jm) {
  const int m = body_.per_subsegment, J = active(), nx = m * J;
  const Eigen::Index nc = static_cast<Eigen::Index>(contacts_.size());
  // The free-space structure (the contact forces are in its loads).
  switch (m) {
    case 3: offdiagonal_blocks<3>(Jm); break;
    case 5: offdiagonal_blocks<5>(Jm); break;
    default: offdiagonal_blocks<Eigen::Dynamic>(Jm); break;
  }
  for (int k = 1; k <= J; ++k) Jm.block(m * (k - 1), m * (k - 1), m, m) = jac_diag_.middleCols(m * (k - 1), m);
  // Rows distal of the perturbed subsegment: E_j B_j xi_c.
  int last = 0;  // the most distal candidate's disk
  for (const ContactCandidate& cand : contacts_) last = std::max(last, cand.disk);
  for (int k = 1; k < J; ++k)
    for (int c = m * (k - 1); c < m * k; ++c)
      for (int j = k + 1; j <= std::min(J, last); ++j) {
        const Vec6 S = jac_B_.middleCols<6>(6 * j) * jac_Xi_.col(c);
        Jm.block(m * (j - 1), c, m, 1).noalias() += jac_E_.middleRows(m * (j - 1), m) * S;
      }
  // The force columns and the complementarity rows.
  Jm.rightCols(nc).setZero();
  Jm.bottomRows(nc).setZero();
  for (Eigen::Index i = 0; i < nc; ++i) {
    const ContactCandidate& cand = contacts_[static_cast<std::size_t>(i)];
    Vec6 w;
    w.head<3>() = contact_force_scale_ * cand.at.normal;
    w.tail<3>() = cand.at.point.cross(w.head<3>());
    for (int j = 1; j <= std::min(cand.disk, J); ++j)
      Jm.block(m * (j - 1), nx + i, m, 1).noalias() = jac_E_.middleRows(m * (j - 1), m) * w;
    double da = 0.0, db = 1.0;
    contact_derivatives(static_cast<std::size_t>(i), da, db);
    const int cols = m * std::min(cand.disk, J);
    for (int c = 0; c < cols; ++c) Jm(nx + i, c) = da * jac_a_.col(i).dot(jac_Xi_.col(c));
    Jm(nx + i, nx + i) = db;
  }
  return Jm.allFinite();
}

template <class Put>
void LumpedProblem::contact_structured_entries(Put&& put) const {
  // Unknowns per subsegment j: d_j (m), s_j (6), tau_j (6); then the force unknowns b_i. Rows:
  //   G_j d_j + E_j s_j + H_j tau_j                       (H_j = E_j B_j + [D_j 0])
  //   s_j - s_{j+1} - W_{j+1} d_{j+1} - sum_{d_i = j} w_i b_i = 0
  //   tau_j - tau_{j-1} - Xi_{j-1} d_{j-1} = 0
  //   da_i a_i . (tau_{d_i} + Xi_{d_i} d_{d_i}) + db_i b_i  (gap rows)
  const int m = body_.per_subsegment, J = active(), K = m + 12, nx = m * J;
  const bool ext = jac_external_;
  const int nc = static_cast<int>(contacts_.size());
  Eigen::Matrix<double, Eigen::Dynamic, 6, 0, 8, 6> H(m, 6);
  for (int jj = 0; jj < J; ++jj) {
    const int d = K * jj, s = d + m, tau = d + m + 6;
    for (int c = 0; c < m; ++c)
      for (int r = 0; r < m; ++r) put(d + r, d + c, jac_diag_(r, m * jj + c));
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < m; ++r) put(d + r, s + c, jac_E_(m * jj + r, c));
    H.noalias() = jac_E_.middleRows(m * jj, m) * jac_B_.middleCols<6>(6 * (jj + 1));
    if (ext) H.leftCols<3>() += jac_D_.middleRows(m * jj, m);
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < m; ++r) put(d + r, tau + c, H(r, c));
    for (int q = 0; q < 6; ++q) put(s + q, s + q, 1.0);
    if (jj + 1 < J) {
      for (int q = 0; q < 6; ++q) put(s + q, s + K + q, -1.0);
      for (int c = 0; c < m; ++c)
        for (int q = 0; q < 6; ++q) put(s + q, d + K + c, -jac_dW_(q, m * (jj + 1) + c));
    }
    for (int i = 0; i < nc; ++i) {
      const ContactCandidate& cand = contacts_[static_cast<std::size_t>(i)];
      if (cand.disk != jj + 1) continue;
      const Vec3 fn = contact_force_scale_ * cand.at.normal, mn = cand.at.point.cross(fn);
      for (int q = 0; q < 6; ++q) put(s + q, K * J + i, -(q < 3 ? fn[q] : mn[q - 3]));
    }
    for (int q = 0; q < 6; ++q) put(tau + q, tau + q, 1.0);
    if (jj > 0) {
      for (int q = 0; q < 6; ++q) put(tau + q, tau - K + q, -1.0);
      for (int c = 0; c < m; ++c)
        for (int q = 0; q < 6; ++q) put(tau + q, d - K + c, -jac_Xi_(q, m * (jj - 1) + c));
    }
  }
  for (int i = 0; i < nc; ++i) {
    const ContactCandidate& cand = contacts_[static_cast<std::size_t>(i)];
    double da = 0.0, db = 1.0;
    contact_derivatives(static_cast<std::size_t>(i), da, db);
    const int jj = std::min(cand.disk, J) - 1, row = K * J + i;
    for (int q = 0; q < 6; ++q) put(row, K * jj + m + 6 + q, da * jac_a_(q, i));
    for (int c = 0; c < m; ++c) put(row, K * jj + c, da * jac_a_.col(i).dot(jac_Xi_.col(m * jj + c)));
    put(row, row, db);
  }
  (void)nx;
}

bool LumpedProblem::contact_setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                              const Eigen::Ref<const Eigen::VectorXd>& f) {
  if (!structured_jacobian(x, f)) return false;  // no damping in contact mode
  if (!(jac_A_.allFinite() && jac_a_.allFinite() && jac_Xi_.allFinite())) return false;
  const int J = active(), nc = static_cast<int>(contacts_.size()), n = (body_.per_subsegment + 12) * J + nc;
  bool same = cstruct_J_ == J && cstruct_external_ == jac_external_ &&
              cstruct_disks_.size() == contacts_.size();
  for (int i = 0; same && i < nc; ++i) same = cstruct_disks_[static_cast<std::size_t>(i)] == contacts_[static_cast<std::size_t>(i)].disk;
  if (!same) {  // a new candidate set: the pattern (allocates; once per set)
    std::vector<std::pair<int, int>> e;
    contact_structured_entries([&](int r, int c, double) { e.emplace_back(r, c); });
    cstruct_pattern_ = bvp::SparsityPattern::from_triplets(n, n, e);
    cstruct_pos_.resize(e.size());
    for (std::size_t i = 0; i < e.size(); ++i) cstruct_pos_[i] = cstruct_pattern_.index_of(e[i].first, e[i].second);
    cstruct_values_.assign(static_cast<std::size_t>(cstruct_pattern_.nnz()), 0.0);
    cstruct_rhs_.resize(n);
    cstruct_J_ = J;
    cstruct_external_ = jac_external_;
    cstruct_disks_.clear();
    for (const ContactCandidate& cand : contacts_) cstruct_disks_.push_back(cand.disk);
  }
  double* v = cstruct_values_.data();
  const int* pos = cstruct_pos_.data();
  std::size_t i = 0;
  contact_structured_entries([&](int, int, double value) { v[pos[i++]] = value; });
  return contact_lu_.factorize(cstruct_pattern_, v) == bvp::SparseLu::Status::Success;
}

bool LumpedProblem::contact_solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) {
  const int m = body_.per_subsegment, J = active(), K = m + 12, nx = m * J;
  const Eigen::Index nc = static_cast<Eigen::Index>(contacts_.size());
  cstruct_rhs_.setZero();
  for (int j = 0; j < J; ++j) cstruct_rhs_.segment(K * j, m) = b.segment(m * j, m);
  cstruct_rhs_.tail(nc) = b.tail(nc);
  if (!contact_lu_.solve(cstruct_rhs_.data())) return false;
  for (int j = 0; j < J; ++j) b.segment(m * j, m) = cstruct_rhs_.segment(K * j, m);
  b.tail(nc) = cstruct_rhs_.tail(nc);
  (void)nx;
  return b.allFinite();
}

}  // namespace tdcr::detail
