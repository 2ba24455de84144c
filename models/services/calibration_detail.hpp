// Private pieces of the calibration service (calibration.hpp): the resolved parameters and how
// they change a scene (calibration_parameters.cpp), and the evaluator of all measurements' model
// solves, residuals and Jacobian (calibration_evaluator.cpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/answer_linearisation.hpp"
#include "tdcr/models/calibration.hpp"

namespace tdcr::calibration_detail {

/// One scalar parameter of the fit.
struct Parameter {
  std::string name;  // e.g. "segment_offset_scale[1]"
  std::string unit;
  CalibrationParameterKind kind = CalibrationParameterKind::YoungsModulus;
  int index = 0;        // segment, tendon or component
  double initial = 0.0; // start (parameter units)
  double lower = 0.0, upper = 0.0;  // bounds (parameter units; +-inf if none)
  double scale = 1.0;   // typical size: the fit works on value / scale
};

/// True for the base-frame parameters (applied to the answers, no model rebuild).
bool is_base_parameter(CalibrationParameterKind kind);

/// The scalar parameters of `specs` for `scene`, with their starting values, bounds and scales.
/// Throws InputError (field `--fit`) on a parameter the scene cannot take.
std::vector<Parameter> resolve_parameters(const Scene& scene, const std::vector<CalibrationParameterSpec>& specs);

/// `scene` with the model parameters set to `values` (parameter units, one per parameter; the
/// base-frame ones are ignored here).
Scene apply_parameters(const Scene& scene, const std::vector<Parameter>& params, const Eigen::VectorXd& values);

/// The base frame of `values` (identity unless base parameters are fitted).
Frame base_frame(const std::vector<Parameter>& params, const Eigen::VectorXd& values);

/// The model's frames a measurement needs: the tip, then each measured point's frame.
struct Prediction {
  bool solved = false;
  std::vector<Frame> frames;
  Solution solution;  // the converged answer (a warm start at nearby parameters)
};

/// Newton's tolerance of the residual points' solves (scaled residual max-norm): a hundred times
/// SolverOptions::kMinFunctionTolerance, above the residual's rounding floor, and far below
/// CalibrationOptions::solve_function_tolerance's default.
constexpr double kPolishTolerance = 1e-13;

/// All measurements' solves, residuals and the structured-difference Jacobian.
class Evaluator {
 public:
  Evaluator(const Scene& scene, const CalibrationData& data, std::vector<Parameter> params,
            const CalibrationOptions& options);

  int samples() const { return static_cast<int>(data_.samples.size()); }
  int parameters() const { return static_cast<int>(params_.size()); }
  const std::vector<Parameter>& parameter_list() const { return params_; }
  /// Offset of measurement i's residuals in the stacked vector, and their count.
  int offset(int i) const { return offsets_[static_cast<std::size_t>(i)]; }
  int size(int i) const { return offsets_[static_cast<std::size_t>(i) + 1] - offsets_[static_cast<std::size_t>(i)]; }
  int residual_count() const { return offsets_.back(); }
  int forward_solves() const { return solves_; }
  int failed_solves() const { return failed_; }
  int linearised() const { return linearised_; }

  /// Every measurement solved with the model parameters of `values` (parameter units), each
  /// warm-started from its answer in `warm` (at other parameters) where there is one, else cold.
  /// With `polish`, each solve goes on to Newton's tolerance kPolishTolerance (a residual point:
  /// its answer must not depend on where it started); without, to the options' tolerance (the
  /// differences, started from the polished answers).
  /// With `linear` (one per measurement, of the answers in `warm`), a measurement whose
  /// linearisation holds is predicted from it to first order, without a solve.
  std::vector<Prediction> predict(const Eigen::VectorXd& values, const std::vector<Prediction>* warm = nullptr,
                                  bool polish = false, const std::vector<AnswerLinearisation>* linear = nullptr);
  /// The standardised residuals of the predictions with the base frame of `values` (a failed
  /// measurement's entries are 0 and `ok[i]` is false).
  Eigen::VectorXd residuals(const std::vector<Prediction>& p, const Eigen::VectorXd& values, std::vector<bool>* ok) const;
  /// Given the predictions `p` and residuals `r` at `values`, the residuals' derivative with respect to the scaled
  /// parameters (values / scale), by forward differences: one model rebuild per model parameter,
  /// each measurement's answer there linearised from its answer in `p` (options.jacobian
  /// ImplicitFunction: F_x factorised once per measurement here) or solved warm; base-frame
  /// parameters by central differences of the transform. `ok[i]` false where measurement i could
  /// not be solved (also in a difference).
  void jacobian_at(const Eigen::VectorXd& values, const std::vector<Prediction>& p, const Eigen::VectorXd& r,
                   std::vector<bool>& ok, Eigen::MatrixXd* jacobian);
  /// Per-measurement errors of predictions with the base frame of `values`.
  std::vector<SampleResidual> sample_residuals(const std::vector<Prediction>& p, const Eigen::VectorXd& values) const;

 private:
  Scene scene_;
  const CalibrationData& data_;
  std::vector<Parameter> params_;
  CalibrationOptions options_;
  SolverOptions solver_;
  SolverOptions polish_;  // solver_ with Newton's tolerance kPolishTolerance (residual points)
  std::vector<int> offsets_;  // residual offsets, size samples + 1
  int solves_ = 0;
  int failed_ = 0;
  int linearised_ = 0;  // difference columns' answers by the implicit function theorem
};

/// The robust loss's weight rho'(s) of a measurement whose standardised residual has squared
/// norm s (1 without a loss, and for Huber up to loss_scale^2).
double loss_weight(const CalibrationOptions& options, double s);

/// The statistics of per-measurement residuals.
ResidualStatistics statistics(const std::vector<SampleResidual>& r, const Eigen::VectorXd& standardised);

}  // namespace tdcr::calibration_detail
