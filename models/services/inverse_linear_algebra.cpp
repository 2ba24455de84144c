// The inverse solve's linear algebra (inverse_solver.hpp): the bounded least-squares step and the
// target set's local structure, free of forward solves.
#include "services/inverse_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>
#include <Eigen/SVD>

namespace tdcr::detail::inverse {

namespace {

// Lawson-Hanson non-negative least squares: argmin |A y - b| over y >= 0. Every A used here
// holds a scaled identity block (full column rank), so the answer is unique.
VectorXd nnls(const MatrixXd& A, const VectorXd& b) {
  const int n = static_cast<int>(A.cols());
  VectorXd y = VectorXd::Zero(n), z(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  const double tol = 10.0 * std::numeric_limits<double>::epsilon() * n * A.cwiseAbs().maxCoeff() *
                     std::max(b.norm(), std::numeric_limits<double>::min());
  VectorXd w = A.transpose() * (b - A * y);
  for (int outer = 0; outer < 3 * n; ++outer) {
    int j = -1;
    double best = tol;
    for (int i = 0; i < n; ++i)
      if (!passive[static_cast<std::size_t>(i)] && w[i] > best) best = w[(j = i)];
    if (j < 0) break;
    passive[static_cast<std::size_t>(j)] = true;
    for (int inner = 0; inner < 3 * n; ++inner) {
      std::vector<int> P;
      for (int i = 0; i < n; ++i)
        if (passive[static_cast<std::size_t>(i)]) P.push_back(i);
      MatrixXd AP(A.rows(), static_cast<Eigen::Index>(P.size()));
      for (std::size_t k = 0; k < P.size(); ++k) AP.col(static_cast<Eigen::Index>(k)) = A.col(P[k]);
      const VectorXd zP = AP.colPivHouseholderQr().solve(b);
      z.setZero();
      for (std::size_t k = 0; k < P.size(); ++k) z[P[k]] = zP[static_cast<Eigen::Index>(k)];
      double alpha = 1.0;
      for (int i : P)
        if (z[i] <= 0.0) alpha = std::min(alpha, y[i] / (y[i] - z[i]));
      if (alpha >= 1.0) {
        y = z;
        break;
      }
      y += alpha * (z - y);
      const double zero = 1e-14 * y.cwiseAbs().maxCoeff();  // rounding of the blocking variable
      for (int i : P)
        if (y[i] <= zero) {
          passive[static_cast<std::size_t>(i)] = false;
          y[i] = 0.0;
        }
    }
    w = A.transpose() * (b - A * y);
  }
  return y.cwiseMax(0.0);
}

}  // namespace

VectorXd damped_step(const MatrixXd& J, const VectorXd& e, const VectorXd& T, double lambda,
                     const std::vector<int>& free, double beta) {
  const Eigen::Index k = J.rows(), f = static_cast<Eigen::Index>(free.size());
  VectorXd y = T;
  if (f == 0) return y;
  const Eigen::Index z = beta > 0.0 ? f : 0;
  MatrixXd A(k + f + z, f);
  VectorXd b(k + f + z), TF(f);
  const double s = std::sqrt(lambda);
  A.middleRows(k, f) = s * MatrixXd::Identity(f, f);
  if (z > 0) A.bottomRows(z) = std::sqrt(beta) * MatrixXd::Identity(f, f);
  for (Eigen::Index c = 0; c < f; ++c) {
    A.col(c).head(k) = J.col(free[static_cast<std::size_t>(c)]);
    TF[c] = T[free[static_cast<std::size_t>(c)]];
  }
  b.head(k) = A.topRows(k) * TF - e;
  b.segment(k, f) = s * TF;
  b.tail(z).setZero();
  const VectorXd yF = nnls(A, b);
  for (Eigen::Index c = 0; c < f; ++c) y[free[static_cast<std::size_t>(c)]] = yF[c];
  return y;
}

double lambda_floor(const MatrixXd& J) {
  return 1e-12 * std::max(J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
}

Structure structure(const MatrixXd& J, const VectorXd& T, const std::vector<int>& free) {
  Structure s;
  s.free = free;
  const Eigen::Index k = J.rows(), f = static_cast<Eigen::Index>(free.size()), m = T.size();
  s.JF.resize(k, f);
  VectorXd TF(f);
  for (Eigen::Index c = 0; c < f; ++c) {
    s.JF.col(c) = J.col(free[static_cast<std::size_t>(c)]);
    TF[c] = T[free[static_cast<std::size_t>(c)]];
  }
  s.lambda = VectorXd::Zero(k);
  Eigen::Index r = 0;
  MatrixXd V = MatrixXd::Identity(f, f);
  if (f > 0) {
    const Eigen::JacobiSVD<MatrixXd> svd(s.JF, Eigen::ComputeThinU | Eigen::ComputeFullV);
    const VectorXd& sv = svd.singularValues();
    while (r < sv.size() && sv[r] > kRankThreshold * sv[0]) ++r;
    if (r > 0) s.sigma_min = sv[r - 1];
    V = svd.matrixV();
    s.lambda = svd.matrixU().leftCols(r) * (V.leftCols(r).transpose() * TF).cwiseQuotient(sv.head(r));
  }
  s.Z = V.rightCols(f - r);
  s.g = s.Z.transpose() * TF;
  s.mu = -(J.transpose() * s.lambda);
  for (int i : free) s.mu[i] = 0.0;
  (void)m;
  return s;
}

}  // namespace tdcr::detail::inverse
