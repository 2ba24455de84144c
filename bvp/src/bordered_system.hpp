/// @file bordered_system.hpp
/// @brief Private to bvp: the bordered system of pseudo-arclength continuation and the
/// augmented-Jacobian factorisation that gives tangents and determinant signs.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>

#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/bvp/sparse_lu.hpp"

namespace tdcr::bvp::detail {

/// G(y) = [F(x; lambda); t^T W (y - y_pred)] for y = (x, lambda), W = diag(unknown_scale of F,
/// 1 / lambda_scale): the scaled unknowns are z = W y and t is a scaled unit tangent.
///
/// Jacobian: the inner system's block (analytic when it has one, else finite differences,
/// grouped by its pattern if any), dF/dlambda by one forward difference, the border row exact.
/// An inner pattern gives a bordered pattern (full last row and column). All buffers are sized
/// in the constructor; residuals and Jacobians allocate nothing (except what the inner does).
class BorderedSystem final : public ResidualSystem {
 public:
  /// @param tangent_lu the sparse factorisation tangent() uses (borrowed, e.g. the Newton
  /// workspace's NewtonSolver::tangent_lu(), so that paths after the first re-analyse nothing).
  BorderedSystem(ParameterizedSystem& inner, double lambda_scale, SparseLu& tangent_lu);

  int size() const override { return n_ + 1; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> g) override;
  const SparsityPattern* sparsity() const override { return sparse_ ? &pattern_ : nullptr; }
  bool has_jacobian() const override { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& g,
                Eigen::Ref<Eigen::MatrixXd> J) override;
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& g, double* values) override;
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  // KINSOL's uscale of y: the inner system's for x (W itself), 1 / lambda_scale for lambda.
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { s = w_; }
  double relative_noise() const override { return inner_.relative_noise(); }

  /// The border: scaled unit tangent t and unscaled predictor y_pred.
  void set_border(const Eigen::VectorXd& t, const Eigen::VectorXd& y_pred);
  /// Scale factors W (length n + 1): z = W y.
  const Eigen::VectorXd& weights() const { return w_; }

  /// Factorise the augmented Jacobian [dF/dz; border^T] (rows scaled by the residual scale)
  /// at y, a solution of F: a dense LU, or a sparse LU (KLU on the bordered pattern, analysed
  /// once per path and refactorised in the last pivot order while that stays accurate) when the
  /// inner system declares a pattern, so large sparse systems stay O(nnz). Outputs the unit tangent t (M t = e_{n+1}, normalised, so that
  /// border^T t > 0), the sign and log|.| of det M. False if F or its Jacobian cannot be
  /// evaluated or t is not finite (M singular).
  bool tangent(const Eigen::VectorXd& y, const Eigen::VectorXd& border, Eigen::VectorXd& t,
               int& det_sign, double& det_log);

  int inner_evaluations = 0;    ///< Inner residual evaluations, finite differences included.
  int jacobian_evaluations = 0; ///< Bordered Jacobian evaluations (corrector and tangents).

 private:
  bool inner_block(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& g);
  bool lambda_column(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& g);

  ParameterizedSystem& inner_;
  int n_;
  bool sparse_;                  // the inner system declares a sparsity pattern
  const SparsityPattern* inner_pattern_;
  SparsityPattern pattern_;      // bordered pattern (sparse_ only)
  std::vector<int> inner_pos_;   // bordered CSC position of every inner entry
  std::vector<double> inner_values_;
  std::vector<double> values_;   // bordered values for tangent() in the sparse case
  std::vector<char> visited_;    // permutation parity in tangent()
  FiniteDifferenceWorkspace fd_;
  Eigen::VectorXd w_, w_inv_, tw_, tw_saved_, y_pred_, fs_;
  Eigen::VectorXd f_, f_pert_, col_, rhs_;
  Eigen::MatrixXd M_;                       // dense case only
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;  // dense case only
  // Sparse case: the scaled augmented matrix on pattern_, factorised by KLU (the determinant
  // sign comes from its factors and permutations). KLU, not Eigen::SparseLU: the supernodal
  // factorisation was a quarter of VCref's loading-path time on soft robots.
  SparseLu& klu_;
  bool dense_tangent(Eigen::VectorXd& t, int& det_sign, double& det_log);
  bool sparse_tangent(Eigen::VectorXd& t, int& det_sign, double& det_log);
};

}  // namespace tdcr::bvp::detail
