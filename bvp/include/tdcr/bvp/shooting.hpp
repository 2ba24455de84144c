/// @file shooting.hpp
/// @brief Generic multiple shooting: a boundary value problem on nodes s_0, ..., s_N becomes a
/// sparse ResidualSystem whose unknowns describe the states at the start of every interval.
///
/// Layout. With state dimension m and N intervals, the unknowns are
///   x = [x_0, x_1, ..., x_{N-1}]   (x_k: d_k unknowns of node k, d_k = unknown_dimension(k)),
/// mapped to the start states y_k^+ = start_state(k, x_k) (by default d_k = m and y_k^+ = x_k),
/// and the residuals are, block by block (block k has d_k rows),
///   block 0:            boundary(y_0^+, ..., y_{N-1}^-)      (boundary conditions),
///   block i = 1..N-1:   junction(i) at inner node i          (continuity, jumps).
/// y_k^- (state at the end of interval k) is y_k^+ integrated over [s_k, s_{k+1}].
///
/// Local unknowns. A node whose start state lies on a manifold (e.g. a rotation R in the state)
/// takes fewer unknowns through a chart around a reference, e.g. R = Rbar exp(w) with w in R^3;
/// rebase() folds the unknowns into the reference after an accepted Newton step so that they stay
/// small. A boundary node may hold fewer unknowns (e.g. only the unknown half of its state).
///
/// Locality. junction(i) may read intervals i-1-c .. i+c (start and end states), boundary may
/// read intervals 0..c and N-1-c..N-1, where c = ShootingProblem::coupling(). With c = 0 a
/// junction sees the nodes i-1, i and i+1, enough for point loads that depend on the
/// neighbouring nodes (e.g. a tendon running from the previous to the next node). The Jacobian
/// is then block-banded, its pattern is known, and KLU solves it in O(N). A problem may drop
/// structural zeros from that band (dependent_rows).
#pragma once

#include <memory>
#include <utility>
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
  /// @brief The d_0 (default m) boundary residuals. Must read only intervals 0..c and
  /// N-1-c..N-1 of `nodes`.
  virtual void boundary(const ShootingNodes& nodes, double* r) const = 0;
  /// @brief The d_i (default m) residuals at inner node i (1..N-1). Must read only intervals
  /// i-1-c .. i+c. Default: continuity, r = y_i^+ - y_{i-1}^- (for d_i = m).
  virtual void junction(int i, const ShootingNodes& nodes, double* r) const;
  /// @brief 1 / typical magnitude of each state component (m values), used as unknown scale
  /// and for finite-difference increments. Default: ones.
  virtual void state_scale(double* s) const;
  /// @brief 1 / typical magnitude of each residual component of a junction or boundary block
  /// (m values). Default: the state scale (continuity residuals are state differences).
  virtual void residual_scale(double* s) const { state_scale(s); }

  // Local unknowns and structure (optional; the defaults are the plain layout above).

  /// @brief Number of unknowns d_k of node k = 0..N-1; residual block k has as many rows.
  /// Default: m.
  virtual int unknown_dimension(int k) const { (void)k; return state_dimension(); }
  /// @brief The start state y_k^+ (m values) of the unknowns x_k (d_k values) of node k: the
  /// chart. Default: y = x (requires d_k = m).
  virtual void start_state(int k, const double* x, double* y) const;
  /// @brief Fold the unknowns x_k into the chart's reference so that they describe the same
  /// start state (e.g. Rbar <- Rbar exp(w), w <- 0). Called by ShootingSystem::rebase().
  /// Default: nothing.
  virtual void rebase(int k, double* x) { (void)k; (void)x; }
  /// @brief True if unknown j of node k moves the start state along a symmetry of interval k's
  /// flow such that the end state moves by the same amount: end(y + d) = end(y) + d (e.g. a
  /// translation of a rod with no position-dependent load). Such columns of the Jacobian need
  /// no integration. Default: false.
  virtual bool shifts_end(int k, int j) const { (void)k; (void)j; return false; }
  /// @brief Rows [first, second) of residual block `block` that depend on unknown j of node k,
  /// for a block whose window reads node k (see coupling()). Default: all rows of the block.
  /// Rows left out are structural zeros of the Jacobian.
  virtual std::pair<int, int> dependent_rows(int block, int k, int j) const;
  /// @brief 1 / typical magnitude of the d_k unknowns of node k (m-sized buffer, first d_k
  /// used). Default: state_scale().
  virtual void unknown_scale(int k, double* s) const { (void)k; state_scale(s); }
  /// @brief 1 / typical magnitude of the d_b residuals of block b (m-sized buffer, first d_b
  /// used). Default: residual_scale().
  virtual void block_scale(int block, double* s) const { (void)block; residual_scale(s); }
  /// @brief Forward-difference increment of unknown j of node k at `value` (`scale`: its unknown
  /// scale, `noise`: the integrator's relative noise). Default: finite_difference_step().
  virtual double increment(int k, int j, double value, double scale, double noise) const;

  // Exact shot derivatives (optional).

  /// @brief Linearise interval k's shot, the map `integrator` evaluates from the start state y0
  /// (m values) to the end state `end`, if the problem can do so more cheaply than by
  /// integrating once per unknown of node k (e.g. through a symmetry of the ODE): then the
  /// Jacobian takes the end-state change of each unknown of node k from shot_tangent().
  /// Default: false (not available).
  virtual bool linearize_shot(int k, Integrator& integrator, const double* y0, const double* end) const {
    (void)k, (void)integrator, (void)y0, (void)end;
    return false;
  }
  /// @brief The end-state change (m values) of interval k for the start-state change dy (m
  /// values), linear in dy, at the last linearize_shot(k) that returned true.
  virtual void shot_tangent(int k, const double* dy, double* dend) const { (void)k, (void)dy, (void)dend; }

  // Linearised residual terms (optional).

  /// @brief The Jacobian's finite differences are about to be taken around `nominal` (the
  /// trajectory of the unknowns it is evaluated at; valid until end_linearization()). Until then
  /// boundary() and junction() may evaluate a term through its exact linearisation about
  /// `nominal` instead of in full: the finite differences of a linear term are its exact
  /// derivative, for any increment. For terms that vary on a much shorter scale than the rest of
  /// a block (e.g. a point load whose direction is set by two nodes a small fraction of the
  /// problem's length apart, where forward differences lose digits in proportion to the number
  /// of intervals), so that the increments can follow the scale of the rest. Default: nothing.
  virtual void begin_linearization(const ShootingNodes& nominal) const { (void)nominal; }
  /// @brief The Jacobian's finite differences are done: evaluate every term in full again.
  virtual void end_linearization() const {}
};

/// @brief The layout and Jacobian structure of a ShootingProblem: they depend only on its
/// dimensions, coupling() and dependent_rows(), so a model can build them once and share them
/// between the ShootingSystems of its workspaces.
struct ShootingStructure {
  std::vector<int> offset;     ///< First unknown (and residual row) of node (block) k; N+1 values.
  std::vector<int> row_block;  ///< Block of every residual row.
  SparsityPattern pattern;     ///< Jacobian pattern (CSC).
  /// @brief Build the structure of `problem` (std::invalid_argument on invalid dimensions).
  static std::shared_ptr<const ShootingStructure> of(const ShootingProblem& problem);
};

/// @brief The ResidualSystem of a ShootingProblem, with a structured finite-difference
/// Jacobian: perturbing unknown j of node k re-integrates interval k only (or none, for
/// ShootingProblem::shifts_end, or when the problem linearises the shot) and re-evaluates only
/// the residual blocks that read it, so a Jacobian costs at most sum_k d_k single-interval
/// integrations (N*m by default), not N*m full residual evaluations. Allocation free after
/// construction.
class ShootingSystem : public ResidualSystem {
 public:
  /// @param problem,integrator Must outlive this object.
  ShootingSystem(const ShootingProblem& problem, Integrator& integrator);
  /// @brief As above, for a problem whose chart references rebase() may move, optionally with
  /// its structure built before (ShootingStructure::of of an identical problem).
  ShootingSystem(ShootingProblem& problem, Integrator& integrator,
                 std::shared_ptr<const ShootingStructure> structure = nullptr);

  int size() const override { return size_; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override;
  const SparsityPattern* sparsity() const override { return &structure_->pattern; }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& f, double* values) override;
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  /// @brief The integrator's relative_noise(): finite differences through CVODE need larger
  /// increments than through RK4.
  double relative_noise() const override;

  /// @brief Integrate every interval from the starts in x (e.g. after a solve) so that nodes()
  /// describes the trajectory of x (nothing is integrated when the last residual() or evaluate()
  /// was at x and nothing was invalidated since). Returns false if an integration failed.
  bool evaluate(const Eigen::Ref<const Eigen::VectorXd>& x);
  /// @brief Fold x into the problem's chart references (ShootingProblem::rebase for every node),
  /// e.g. after an accepted Newton step. Needs the non-const constructor (else std::logic_error).
  void rebase(Eigen::Ref<Eigen::VectorXd> x);
  /// @brief Forget the cached trajectory (call after changing the problem: its parameters, chart
  /// references or ODEs).
  void invalidate() { cached_ = false; }
  /// @brief Use another integrator from now on (must outlive this object).
  void set_integrator(Integrator& integrator) { integrator_ = &integrator; cached_ = false; }
  /// @brief Use another structure of the same layout from now on (e.g. a sparser pattern when
  /// the problem's dependent_rows() changed between solves; std::invalid_argument if its offsets
  /// differ). sparsity() then points to its pattern; not during a solve.
  void set_structure(std::shared_ptr<const ShootingStructure> structure);
  /// @brief The structure in use.
  const std::shared_ptr<const ShootingStructure>& structure() const { return structure_; }
  /// @brief First unknown (and residual row) of node (block) k; offset(N) = size().
  int offset(int k) const { return structure_->offset[k]; }
  /// @brief The trajectory of the last residual()/evaluate() call.
  ShootingNodes nodes() const { return ShootingNodes(starts_.data(), ends_.data(), m_, n_); }
  /// @brief Number of single-interval integrations so far (cost measure).
  long interval_integrations() const { return integrations_; }

 private:
  bool integrate_all(const Eigen::Ref<const Eigen::VectorXd>& x);
  void eval_block(int block, const ShootingNodes& nodes, double* r) const;
  void check_problem();
  void refresh_scale() const;

  const ShootingProblem& problem_;
  ShootingProblem* mutable_problem_ = nullptr;  // for rebase()
  Integrator* integrator_;
  int m_, n_, size_ = 0;
  std::shared_ptr<const ShootingStructure> structure_;
  const int* offset_ = nullptr;             // structure_->offset
  std::vector<double> x_;                   // unknowns of the cached trajectory
  bool cached_ = false;
  std::vector<double> starts_, ends_;       // trajectory at x_
  std::vector<double> pstarts_, pends_;     // perturbed copies for the Jacobian
  std::vector<double> xnode_;               // perturbed unknowns of one node
  std::vector<double> dy_;                  // start-state change of one perturbed unknown
  std::vector<double> rblock_;              // one residual block
  mutable std::vector<double> scale_;       // unknown scales (size()), refreshed by unknown_scale()
  mutable std::vector<double> sbuf_;        // one node's or block's scales (m)
  long integrations_ = 0;
};

}  // namespace tdcr::bvp
