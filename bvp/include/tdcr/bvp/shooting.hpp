/// @file shooting.hpp
/// @brief Generic multiple shooting: a boundary value problem on nodes s_0, ..., s_N becomes a
/// sparse ResidualSystem whose unknowns are the states at the start of every interval.
///
/// Layout. With state dimension m and N intervals, the unknowns are
///   x = [y_0^+, y_1^+, ..., y_{N-1}^+]   (y_k^+ = state at the start of interval k, m each),
/// and the N*m residuals are
///   rows 0 .. m-1:        boundary(y_0^+, ..., y_{N-1}^-)      (boundary conditions),
///   rows i*m .. i*m+m-1:  junction(i) at inner node i = 1..N-1  (continuity, jumps).
/// y_k^- (state at the end of interval k) is y_k^+ integrated over [s_k, s_{k+1}].
///
/// Locality. junction(i) may read intervals i-1-c .. i+c (start and end states), boundary may
/// read intervals 0..c and N-1-c..N-1, where c = ShootingProblem::coupling(). With c = 0 a
/// junction sees the nodes i-1, i and i+1, enough for point loads that depend on the
/// neighbouring nodes (e.g. a tendon running from the previous to the next node). The Jacobian
/// is then block-banded, its pattern is known, and KLU solves it in O(N).
#pragma once

#include <vector>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/residual_system.hpp"

namespace tdcr::bvp {

/// @brief Read-only view of a shooting trajectory: start and end states of every interval.
class ShootingNodes {
 public:
  /// @brief View of N*m start states and N*m end states (interval-major, m per interval).
  ShootingNodes(const double* starts, const double* ends, int m, int n)
      : starts_(starts), ends_(ends), m_(m), n_(n) {}
  /// @brief State at the start of interval k (node s_k), m values.
  const double* start(int k) const { return starts_ + static_cast<long>(k) * m_; }
  /// @brief State at the end of interval k (node s_{k+1}), m values.
  const double* end(int k) const { return ends_ + static_cast<long>(k) * m_; }
  int state_dimension() const { return m_; }  ///< m.
  int intervals() const { return n_; }         ///< N.

 private:
  const double* starts_;
  const double* ends_;
  int m_, n_;
};

/// @brief A boundary value problem split into shooting intervals. Implemented by a model.
class ShootingProblem {
 public:
  virtual ~ShootingProblem() = default;
  /// @brief State dimension m (the same on every interval).
  virtual int state_dimension() const = 0;
  /// @brief Number of intervals N >= 1.
  virtual int intervals() const = 0;
  /// @brief Node k = 0..N (strictly monotone; the independent variable, e.g. arc length in m).
  virtual double node(int k) const = 0;
  /// @brief The ODE on interval k (dimension m). The reference must stay valid for the solve.
  virtual const OdeSystem& ode(int k) const = 0;
  /// @brief Half-width c of the coupling window (see the file comment). Default 0.
  virtual int coupling() const { return 0; }
  /// @brief m boundary residuals. Must read only intervals 0..c and N-1-c..N-1 of `nodes`.
  virtual void boundary(const ShootingNodes& nodes, double* r) const = 0;
  /// @brief m residuals at inner node i (1..N-1). Must read only intervals i-1-c .. i+c.
  /// Default: continuity, r = y_i^+ - y_{i-1}^-.
  virtual void junction(int i, const ShootingNodes& nodes, double* r) const;
  /// @brief 1 / typical magnitude of each state component (m values), used as unknown scale
  /// and for finite-difference increments. Default: ones.
  virtual void state_scale(double* s) const;
  /// @brief 1 / typical magnitude of each residual component of a junction or boundary block
  /// (m values). Default: the state scale (continuity residuals are state differences).
  virtual void residual_scale(double* s) const { state_scale(s); }
};

/// @brief The ResidualSystem of a ShootingProblem, with a structured finite-difference
/// Jacobian: perturbing unknown j of interval k re-integrates interval k only and re-evaluates
/// only the residual blocks that read it, so a Jacobian costs N*m single-interval integrations
/// (the same as one residual evaluation per unknown of one interval, times N), not N*m full
/// residual evaluations. Allocation free after construction.
class ShootingSystem : public ResidualSystem {
 public:
  /// @param problem,integrator Must outlive this object.
  ShootingSystem(const ShootingProblem& problem, Integrator& integrator);

  int size() const override { return n_ * m_; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override;
  const SparsityPattern* sparsity() const override { return &pattern_; }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& f, double* values) override;
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  /// @brief The integrator's relative_noise(): finite differences through CVODE need larger
  /// increments than through RK4.
  double relative_noise() const override;

  /// @brief Integrate every interval from the starts in x (e.g. after a solve) so that nodes()
  /// describes the trajectory of x. Returns false if an integration failed.
  bool evaluate(const Eigen::Ref<const Eigen::VectorXd>& x);
  /// @brief The trajectory of the last residual()/evaluate() call.
  ShootingNodes nodes() const { return ShootingNodes(starts_.data(), ends_.data(), m_, n_); }
  /// @brief Number of single-interval integrations so far (cost measure).
  long interval_integrations() const { return integrations_; }

 private:
  bool integrate_all(const Eigen::Ref<const Eigen::VectorXd>& x);
  void eval_block(int block, const ShootingNodes& nodes, double* r) const;

  const ShootingProblem& problem_;
  Integrator& integrator_;
  int m_, n_, c_;
  SparsityPattern pattern_;
  std::vector<double> starts_, ends_;     // trajectory at the last evaluated x
  std::vector<double> pstarts_, pends_;   // perturbed copies for the Jacobian
  std::vector<double> rblock_;            // one residual block
  mutable std::vector<double> scale_;     // state scale (m), refreshed by unknown_scale()
  mutable std::vector<double> rscale_;    // residual block scale (m)
  long integrations_ = 0;
};

}  // namespace tdcr::bvp
