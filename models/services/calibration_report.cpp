// The calibration report: covariance and standard errors, correlation, and the parameters the data
// cannot identify, all from the SVD of the final Jacobian scaled by the parameters' scales and
// weighted by the robust loss at the solution.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/SVD>

#include "calibration_detail.hpp"

namespace tdcr::calibration_detail {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A parameter whose unit vector has a component this large along a null direction of the scaled
// Jacobian is not identifiable (its value moves along that direction without changing the fit).
constexpr double kNullShare = 1e-2;
}  // namespace

double loss_weight(const CalibrationOptions& options, double s) {
  const double b = options.loss_scale * options.loss_scale;
  switch (options.loss) {
    case CalibrationLoss::Huber: return s <= b ? 1.0 : std::sqrt(b / s);  // ceres::HuberLoss
    case CalibrationLoss::Cauchy: return 1.0 / (1.0 + s / b);              // ceres::CauchyLoss
    case CalibrationLoss::None: break;
  }
  return 1.0;
}

void fill_report(const Evaluator& evaluator, const Eigen::VectorXd& values, const Eigen::VectorXd& r,
                 const Eigen::MatrixXd& J, bool has_std, const CalibrationOptions& options, CalibrationResult& out) {
  const std::vector<Parameter>& params = evaluator.parameter_list();
  const int np = static_cast<int>(params.size());
  const Eigen::Index m = J.rows();
  // The robust loss's weights at the solution (iteratively reweighted least squares: w_i =
  // rho'(s_i) of measurement i's squared standardised residual s_i), normalised by their mean
  // over the residual components: a measurement the loss down-weights counts that much less in
  // the covariance, and uniform weights (no outliers) give the plain covariance.
  Eigen::VectorXd w = Eigen::VectorXd::Ones(m);
  for (int i = 0; i < evaluator.samples(); ++i)
    w.segment(evaluator.offset(i), evaluator.size(i)).setConstant(
        loss_weight(options, r.segment(evaluator.offset(i), evaluator.size(i)).squaredNorm()));
  const double mean_w = m > 0 ? w.mean() : 1.0;
  const Eigen::VectorXd root_w = (w / mean_w).cwiseSqrt();
  const Eigen::MatrixXd Jw = root_w.asDiagonal() * J;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jw, Eigen::ComputeThinU | Eigen::ComputeFullV);
  const Eigen::VectorXd S = svd.singularValues();
  const Eigen::MatrixXd& V = svd.matrixV();
  out.singular_values = Eigen::VectorXd::Zero(np);
  out.singular_values.head(S.size()) = S;
  const double smax = S.size() ? S[0] : 0.0;
  int rank = 0;
  // Numerically zero, or too weak for the measurements' standard deviations.
  const double floor = std::max(options.rank_tolerance * smax, 1.0 / options.max_relative_std);
  for (Eigen::Index i = 0; i < S.size(); ++i) rank += S[i] > floor && S[i] > 0.0;

  // Null directions: the columns of V past the rank (a Jacobian with fewer rows than parameters
  // has them too).
  std::vector<bool> identifiable(static_cast<std::size_t>(np), true);
  for (int q = 0; q < np; ++q)
    for (int k = rank; k < np; ++k)
      if (std::abs(V(q, k)) > kNullShare) identifiable[static_cast<std::size_t>(q)] = false;

  // Covariance of the scaled parameters on the identifiable subspace, times the residual
  // variance unless the data's standard deviations are taken as true.
  const bool scaled = options.covariance == CovarianceScaling::Residuals ||
                      (options.covariance == CovarianceScaling::Automatic && !has_std);
  double s2 = 1.0;
  // The residual variance from the weighted residuals (w_i r_i: a down-weighted outlier adds
  // at most its bounded influence, loss_scale^2 for Huber), over the mean weight squared.
  if (scaled) s2 = m > rank ? (w.cwiseProduct(r) / mean_w).squaredNorm() / static_cast<double>(m - rank) : kNaN;
  Eigen::MatrixXd Cz = Eigen::MatrixXd::Zero(np, np);
  for (int k = 0; k < rank; ++k) Cz += V.col(k) * V.col(k).transpose() / (S[k] * S[k]);
  Cz *= s2;
  out.covariance.resize(np, np);
  out.correlation.resize(np, np);
  for (int a = 0; a < np; ++a)
    for (int b = 0; b < np; ++b) {
      const bool ok = identifiable[static_cast<std::size_t>(a)] && identifiable[static_cast<std::size_t>(b)];
      out.covariance(a, b) = ok ? Cz(a, b) * params[static_cast<std::size_t>(a)].scale * params[static_cast<std::size_t>(b)].scale : kInf;
      out.correlation(a, b) = ok ? Cz(a, b) / std::sqrt(Cz(a, a) * Cz(b, b)) : kNaN;
    }

  out.parameters.clear();
  out.non_identifiable.clear();
  for (int q = 0; q < np; ++q) {
    const Parameter& p = params[static_cast<std::size_t>(q)];
    FittedParameter f;
    f.name = p.name;
    f.unit = p.unit;
    f.initial = p.initial;
    f.value = values[q];
    f.lower = p.lower;
    f.upper = p.upper;
    f.identifiable = identifiable[static_cast<std::size_t>(q)];
    f.std_error = f.identifiable ? std::sqrt(out.covariance(q, q)) : kInf;
    const double tol = 1e-9 * p.scale;
    f.at_bound = (std::isfinite(p.lower) && f.value <= p.lower + tol) || (std::isfinite(p.upper) && f.value >= p.upper - tol);
    if (!f.identifiable) out.non_identifiable.push_back(f.name);
    out.parameters.push_back(f);
  }

  out.warning.clear();
  if (!out.non_identifiable.empty()) {
    std::string names;
    for (const std::string& n : out.non_identifiable) names += (names.empty() ? "" : ", ") + n;
    // The weakest null direction, in scaled parameters (relative changes), as a combination.
    std::string dir;
    const Eigen::VectorXd v = V.col(np - 1);
    for (int q = 0; q < np; ++q) {
      if (std::abs(v[q]) <= kNullShare) continue;
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s%+.3g %s", dir.empty() ? "" : " ", v[q], params[static_cast<std::size_t>(q)].name.c_str());
      dir += buf;
    }
    char weakest[96];
    const double sk = S.size() == np ? S[np - 1] : 0.0;
    std::snprintf(weakest, sizeof weakest, "%.2g of the largest, relative standard error %.2g", smax > 0.0 ? sk / smax : 0.0,
                  sk > 0.0 ? 1.0 / sk : kInf);
    out.warning = "not identifiable from these data: " + names + " (the standardised Jacobian in relative parameter "
                  "changes has " + std::to_string(np - rank) + " of " + std::to_string(np) +
                  " directions without support: its smallest singular value is " + weakest + "; the fit barely "
                  "changes along " + dir + ", so their values are not determined by the data: fix some of them or "
                  "add measurements that separate them)";
  }
}

}  // namespace tdcr::calibration_detail
