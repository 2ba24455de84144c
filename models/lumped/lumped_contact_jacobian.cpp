// The Jacobian of the contact system of CCsub and PRB (docs/contact.md): the structured
// differences of lumped_jacobian.cpp with the contact forces in the disk loads, plus
//  - the rows distal of a perturbed subsegment k: a contact force distal of disk k does not move
//    rigidly with the frames (its normal follows the obstacle's surface, a rim point turns in its
//    disk), and its change beyond the rigid motion, pulled back to the unperturbed frames, acts
//    on row j > k through E_j (the response to a change of the distal wrench), summed over the
//    contacts at disks >= j;
//  - the columns of the force unknowns b_i: a unit force F_s n_i at the contact point c_i of disk
//    d_i changes the distal wrench of every subsegment j <= d_i by (F_s n_i, c_i x F_s n_i), exact
//    through E_j;
//  - the complementarity rows: phi(a, b) with a = g / r_o, its derivatives in closed form, the
//    gap's change per column n . dc from the contact point c of the moved frame (the gaps depend
//    on the kinematics alone: one contact point per candidate and column).
// A column costs the structured one plus one contact point per candidate distal of it, so the
// Jacobian costs about one residual evaluation instead of one per unknown.
// tests/test_contact_lumped.cpp compares it with central differences of the contact residual.
#include <cmath>

#include "lumped/lumped_problem.hpp"

namespace tdcr::detail {

void LumpedProblem::contact_loads() {
  const std::size_t nc = contacts_.size();
  const int n = size();
  jac_cf_.assign(static_cast<std::size_t>(body_.N) + 2, Vec3::Zero());  // allocates once per N
  jac_cm_.assign(static_cast<std::size_t>(body_.N) + 2, Vec3::Zero());
  for (const ContactCandidate& c : contacts_) {
    const Vec3 f = (c.lambda * contact_force_scale_) * c.at.normal;
    jac_cf_[c.disk] += f;
    jac_cm_[c.disk] += (c.at.point - frames_[c.disk].p).cross(f);
  }
  jac_cd_.resize(6 * static_cast<Eigen::Index>(nc), n);
  jac_cg_.resize(static_cast<Eigen::Index>(nc), n);
}

void LumpedProblem::contact_column(int k, int c, const Mat3& Q, const Vec3& t, const Frame& fk, const Frame& base_k1,
                                   double h, Vec3& Fk, Vec3& Mk) {
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const ContactCandidate& cand = contacts_[i];
    const int d = cand.disk;
    auto delta = jac_cd_.col(c).segment<6>(6 * static_cast<Eigen::Index>(i));
    if (d < k) {  // proximal of the perturbed subsegment: does not move
      delta.setZero();
      jac_cg_(static_cast<Eigen::Index>(i), c) = 0.0;
      continue;
    }
    // frames_[k + 1] holds the moved frame already; the others their unperturbed values.
    Frame moved = fk;
    if (d > k) {
      const Frame& base = d == k + 1 ? base_k1 : frames_[d];
      moved.R = Q * base.R;
      moved.p = Q * base.p + t;
    }
    const double radius = cand.body == ContactBody::Disk ? body_.disk_radius[d] : body_.backbone_radius;
    const ContactPoint cp = contact_point(obstacles_[cand.obstacle], moved, cand.body, radius);
    // dg = n . dc (n = grad d at c; the backbone's c = p - r_o n(p) moves along n as p does):
    // free of the obstacle's curvature, which the difference of the gaps carries at first order.
    jac_cg_(static_cast<Eigen::Index>(i), c) = cand.at.normal.dot(cp.point - cand.at.point) / h;
    const double fs = cand.lambda * contact_force_scale_;
    const Vec3 f1 = fs * cp.normal;
    if (d == k) {  // the loads of disk k are recomputed: add its contact forces
      delta.setZero();
      Fk += f1;
      Mk += (cp.point - fk.p).cross(f1);
      continue;
    }
    // Fk, Mk carry the force f0 at c0 moved rigidly (Q f0 at Q c0 + t): add the difference.
    const Vec3 f0 = fs * cand.at.normal, c0 = cand.at.point;
    const Vec3 qf0 = Q * f0;
    Fk += f1 - qf0;
    Mk += (cp.point - fk.p).cross(f1) - (Q * c0 + t - fk.p).cross(qf0);
    // Pulled back by the rigid motion: force Q^T f1 at Q^T (c1 - t), against f0 at c0.
    const Vec3 g = Q.transpose() * f1, u = Q.transpose() * (cp.point - t);
    delta.head<3>() = (g - f0) / h;
    delta.tail<3>() = (u.cross(g) - c0.cross(f0)) / h;
  }
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
  // Rows distal of the perturbed subsegment: E_j times the pulled-back change of the contact
  // forces at disks >= j.
  for (int k = 1; k < J; ++k)
    for (int c = m * (k - 1); c < m * k; ++c) {
      Eigen::Matrix<double, 6, 1> S = Eigen::Matrix<double, 6, 1>::Zero();
      for (int j = J; j > k; --j) {
        bool any = false;
        for (Eigen::Index i = 0; i < nc; ++i)
          if (contacts_[static_cast<std::size_t>(i)].disk == j) {
            S += jac_cd_.col(c).segment<6>(6 * i);
            any = true;
          }
        if (!any && S.isZero(0.0)) continue;
        Jm.block(m * (j - 1), c, m, 1).noalias() += jac_E_.middleRows(m * (j - 1), m) * S;
      }
    }
  // The force columns and the complementarity rows.
  const double rs = contact_length_scale_, fsc = contact_force_scale_;
  Jm.rightCols(nc).setZero();
  Jm.bottomRows(nc).setZero();
  for (Eigen::Index i = 0; i < nc; ++i) {
    const ContactCandidate& cand = contacts_[static_cast<std::size_t>(i)];
    Eigen::Matrix<double, 6, 1> w;
    w.head<3>() = fsc * cand.at.normal;
    w.tail<3>() = cand.at.point.cross(w.head<3>());
    for (int j = 1; j <= std::min(cand.disk, J); ++j)
      Jm.block(m * (j - 1), nx + i, m, 1).noalias() = jac_E_.middleRows(m * (j - 1), m) * w;
    double da = 0.0, db = 1.0;  // d residual / d gap, d residual / d b
    if (contact_stiffness_ > 0.0) {
      da = cand.at.gap < 0.0 ? contact_stiffness_ / fsc : 0.0;
    } else {
      const double a = cand.at.gap / rs, b = cand.lambda, r = std::sqrt(a * a + b * b);
      // At the corner a = b = 0 an element of the generalised gradient.
      const double ca = r > 0.0 ? a / r : M_SQRT1_2, cb = r > 0.0 ? b / r : M_SQRT1_2;
      da = (1.0 - ca) / rs;
      db = 1.0 - cb;
    }
    Jm.row(nx + i).head(nx) = da * jac_cg_.row(i).head(nx);
    Jm(nx + i, nx + i) = db;
  }
  return Jm.allFinite();
}

}  // namespace tdcr::detail
