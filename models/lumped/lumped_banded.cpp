// The banded formulation of the lumped models (lumped_problem.hpp): per loaded subsegment j the
// unknowns y_j = (x_j, p_j, th_j, F_j, M_j) (m + 12 values: the subsegment's own unknowns, the
// centre and rotation vector of disk j, the distal wrench of Eq. 44-47 with M_j about O_j), and
// the residuals (same order): constitutive law, position and rotation continuity with disk j-1,
// force and moment balance of disk j. Residual j involves the unknowns of j-1, j, j+1 only.
#include <algorithm>
#include <utility>

#include <Eigen/Geometry>

#include "lumped/lumped_problem.hpp"

namespace tdcr::detail {

namespace {

// Offsets inside a node (unknowns and residuals alike).
struct Node {
  int m;
  int P() const { return m; }
  int T() const { return m + 3; }
  int F() const { return m + 6; }
  int M() const { return m + 9; }
  int size() const { return m + 12; }
};

Mat3 skew(const Vec3& v) {
  Mat3 S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

// exp([th]) by Rodrigues' formula, with series where it cancels.
Mat3 rotation_exp(const Vec3& th) {
  const double t2 = th.squaredNorm();
  double s1, c2;
  if (t2 < 1e-8) {
    s1 = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
    c2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
  } else {
    const double t = std::sqrt(t2);
    s1 = std::sin(t) / t;
    c2 = (1.0 - std::cos(t)) / t2;
  }
  const Mat3 K = skew(th);
  return Mat3::Identity() + s1 * K + c2 * K * K;
}

Vec3 rotation_log(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace

bool LumpedProblem::banded_residual(const double* y, double* f) {
  const Node n{body_.per_subsegment};
  const int K = n.size(), J = active();
  const bool bb = backbone_weight_on();
  const double L = body_.length, EI = body_.EI;
  frames_[0] = Frame{};
  for (int j = 1; j <= J; ++j) {
    const double* yj = y + K * (j - 1);
    frames_[j].p = Eigen::Map<const Vec3>(yj + n.P());
    frames_[j].R = rotation_exp(Eigen::Map<const Vec3>(yj + n.T()));
    body_.pose(j, yj, loads_.stretch_of(j), poses_[j]);
  }
  body_.statics.disk_loads(loads_, frames_.data(), disk_f_.data(), disk_m_.data());
  for (int j = 1; j <= J; ++j) {
    const double* yj = y + K * (j - 1);
    double* fj = f + K * (j - 1);
    const Frame& a = frames_[j - 1];
    const Frame& b = frames_[j];
    const SubsegmentPose& g = poses_[j];
    const Mat3 Rt = a.R.transpose();
    const Eigen::Map<const Vec3> F(yj + n.F()), M(yj + n.M());
    const Vec3 W = bb ? Vec3(Rt * backbone_weight(j)) : Vec3::Zero();
    constitutive(j, yj, g, Rt * F, Rt * M, W, fj);
    const double l = body_.statics.length(j);
    // Continuity: disk j sits where subsegment j ends.
    Eigen::Map<Vec3>(fj + n.P()) = (b.p - a.p - a.R * g.p) / l;
    const Mat3 A = (a.R * g.R).transpose() * b.R;
    Eigen::Map<Vec3>(fj + n.T()) = 0.5 * Vec3(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
    // Balance of disk j with the distal wrench of disk j+1 (Eq. 44-47).
    Vec3 fb = disk_f_[j], mb = disk_m_[j];
    if (j < J) {
      const double* yn = y + K * j;
      const Eigen::Map<const Vec3> Fn(yn + n.F()), Mn(yn + n.M());
      fb += Fn;
      mb += Mn + (frames_[j + 1].p - b.p).cross(Fn);
      if (bb) {
        const Vec3 Wn = backbone_weight(j + 1);
        fb += Wn;
        mb += (b.R * poses_[j + 1].c).cross(Wn);
      }
    }
    Eigen::Map<Vec3>(fj + n.F()) = (F - fb) * (l * L / EI);
    Eigen::Map<Vec3>(fj + n.M()) = (M - mb) * (l / EI);
  }
  return true;
}

void LumpedProblem::banded_scale(double* s) const {
  const Node n{body_.per_subsegment};
  const double L = body_.length, EI = body_.EI;
  // Internal wrenches: the larger of the bending scales and the loads' own (tendon tensions
  // compress the backbone by up to ~(L / r)^2 EI / L^2; an underestimate caps Newton steps and
  // stretches the loading path's scaled arclength).
  const double f_scale = 1.0 / std::max(EI / (L * L), loads_.loads.force_scale());
  const double m_scale = 1.0 / std::max(EI / L, loads_.loads.moment_scale());
  for (int j = 0; j < active(); ++j) {
    double* sj = s + n.size() * j;
    x_scale(sj);
    for (int i = 0; i < 3; ++i) {
      sj[n.P() + i] = 1.0 / L;
      sj[n.T() + i] = 1.0;
      sj[n.F() + i] = f_scale;
      sj[n.M() + i] = m_scale;
    }
  }
}

void LumpedProblem::lift(const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  if (!banded_) {
    y = x;
    return;
  }
  lift_banded(x, y);
}

void LumpedProblem::lift_banded(const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  const Node n{body_.per_subsegment};
  evaluate(x.data());
  y.resize(n.size() * active());
  for (int j = 1; j <= active(); ++j) {
    double* yj = y.data() + n.size() * (j - 1);
    for (int i = 0; i < n.m; ++i) yj[i] = x[n.m * (j - 1) + i];
    Eigen::Map<Vec3>(yj + n.P()) = frames_[j].p;
    Eigen::Map<Vec3>(yj + n.T()) = rotation_log(frames_[j].R);
    Eigen::Map<Vec3>(yj + n.F()) = F_[j];
    Eigen::Map<Vec3>(yj + n.M()) = M_[j];
  }
}

void LumpedProblem::gather_x(const Eigen::VectorXd& y, Eigen::VectorXd& x) const {
  if (!banded_) {
    x = y.head(body_.per_subsegment * active());  // without the contact forces
    return;
  }
  const int m = body_.per_subsegment, K = m + 12;
  x.resize(m * active());
  for (int j = 0; j < active(); ++j) x.segment(m * j, m) = y.segment(K * j, m);
}

void LumpedProblem::build_pattern() {
  const Node n{body_.per_subsegment};
  const int K = n.size(), J = active();
  // The entries of a chain of `nodes` nodes; `cyclic`: node indices wrap around (node 0 is node
  // `nodes`), for the colouring below.
  auto entries = [&](int nodes, bool cyclic) {
    std::vector<std::pair<int, int>> e;
    // Rows [r0, r0 + nr) of node i depend on columns [c0, c0 + nc) of node k (1-based nodes;
    // node 0, the base disk, is no unknown).
    auto add = [&](int i, int r0, int nr, int k, int c0, int nc) {
      if (cyclic) k = (k - 1 + nodes) % nodes + 1;
      else if (k < 1 || k > nodes) return;
      for (int r = 0; r < nr; ++r)
        for (int c = 0; c < nc; ++c) e.emplace_back(K * (i - 1) + r0 + r, K * (k - 1) + c0 + c);
    };
    for (int i = 1; i <= nodes; ++i) {
      // Constitutive: x_i, R_{i-1}, F_i, M_i.
      add(i, 0, n.m, i, 0, n.m);
      add(i, 0, n.m, i - 1, n.T(), 3);
      add(i, 0, n.m, i, n.F(), 6);
      // Continuity: x_i, pose i, pose i-1.
      add(i, n.P(), 6, i, 0, n.m);
      add(i, n.P(), 6, i, n.P(), 6);
      add(i, n.P(), 6, i - 1, n.P(), 6);
      // Balance: F_i, M_i; tendon forces of poses i-1, i, i+1; F_{i+1}, M_{i+1}; x_{i+1} (centroid).
      add(i, n.F(), 6, i, n.F(), 6);
      for (int k = i - 1; k <= i + 1; ++k) add(i, n.F(), 6, k, n.P(), 6);
      add(i, n.F(), 6, i + 1, n.F(), 6);
      add(i, n.F(), 6, i + 1, 0, n.m);
    }
    return e;
  };
  pattern_ = bvp::SparsityPattern::from_triplets(K * J, K * J, entries(J, false));
  // Column colouring for the grouped differences without a greedy search over the whole chain
  // (which cost more than a Newton iteration at J = 100): the greedy colouring of a cyclic chain
  // of P nodes, repeated with period P. Two columns that share a row of the chain (nodes at most
  // 2 apart) share a row of the cyclic chain too, so any P >= 3 gives a valid colouring; P from
  // 3 to 8 are tried (a few hundred columns each) and the one with the fewest groups is kept (P =
  // 5: 33 groups for CCsub, 35 for PRB, as the greedy colouring of the whole chain; P = 6: 39
  // and 41; test LumpedJacobian.BandedColouringIsValidAndAsSmallAsGreedy).
  std::vector<int> proto;
  int period = J, best = 0;
  if (J > 8) {
    for (int P = 3; P <= 8; ++P) {
      int groups = 0;
      std::vector<int> g =
          bvp::column_groups(bvp::SparsityPattern::from_triplets(K * P, K * P, entries(P, true)), &groups);
      if (proto.empty() || groups < best) {
        proto = std::move(g);
        best = groups;
        period = P;
      }
    }
  } else {
    proto = bvp::column_groups(pattern_);
  }
  groups_.resize(static_cast<size_t>(K) * J);
  for (int k = 1; k <= J; ++k)
    for (int c = 0; c < K; ++c) groups_[K * (k - 1) + c] = proto[K * ((k - 1) % period) + c];
  pattern_J_ = J;
}

}  // namespace tdcr::detail
