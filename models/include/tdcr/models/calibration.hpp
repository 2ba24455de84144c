/// @file calibration.hpp
/// @brief Calibration: fit a model's parameters (stiffness, tendon offsets, lengths, masses,
/// tendon stiffness, friction, a base-frame offset) to measured shapes by robust least squares.
///
/// The data are a CSV file in the sweep CSV's column names, so that the output of `tdcr sweep`
/// is valid data (docs/calibration.md): the inputs of each measurement as scene-file paths
/// (`actuation.tensions[0]`, `actuation.displacements[2]`, `loads.tip_force[1]`, ...) and the
/// measurements as `tip_x`, `tip_y`, `tip_z` (m, base frame), optionally `rot_x`, `rot_y`, `rot_z`
/// (rotation vector of the tip frame, rad) and backbone points `point_x@S`, `point_y@S`,
/// `point_z@S` at arc length S (m), each optionally with a standard deviation column
/// (`tip_x_std`, ...).
///
/// The fit is a Ceres Solver problem with one residual block per measurement (its model solve,
/// each standardised by its standard deviation) under a robust loss. All measurements are solved
/// by one model per parameter vector, warm-started from the last iterate's answers and taken to
/// a Newton tolerance near the residual's rounding floor, so that the cost is one function of the
/// parameters (the first point cold, along the model's own loading path). The Jacobian's model
/// columns are by the implicit function theorem (AnswerLinearisation: F_x once per answer, per
/// parameter one residual evaluation of the model rebuilt at the shifted parameter), or by
/// structured forward differences (every measurement solved again, warm-started from its answer
/// at the unshifted parameters); a base-frame offset is applied to the answers and costs no
/// solve.
///
/// @code
/// tdcr::Scene scene = tdcr::load_scene("robot.json");
/// tdcr::CalibrationData data = tdcr::read_calibration_data("shapes.csv", scene);
/// tdcr::CalibrationOptions options;
/// options.model = tdcr::ModelKind::CCsub;
/// options.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale");
/// tdcr::CalibrationResult r = tdcr::calibrate(scene, data, options);
/// std::cout << r.summary.brief_report() << "\n";
/// std::ofstream("calibrated.json") << tdcr::scene_to_json(r.scene);  // the calibrated scene
/// @endcode
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/types.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief A measured backbone point: its arc length and position.
struct MeasuredPoint {
  double s = 0.0;                      ///< Arc length along the backbone (m), in (0, length].
  Vec3 position = Vec3::Zero();        ///< Measured position (m), base frame.
  /// Standard deviation per coordinate (m); NaN where the data give none
  /// (CalibrationOptions::position_std is used).
  Vec3 std = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// @brief One measurement: the input the robot was given and what was measured.
struct CalibrationSample {
  ModelInput input;  ///< The scene's input with the row's input columns set.
  int line = 0;      ///< Line of the data file (1-based); 0 when not read from a file.
  std::optional<Vec3> tip;  ///< Measured tip position (m), base frame.
  /// Measured tip orientation as a rotation vector (rad, base frame: R = exp([rotation])).
  std::optional<Vec3> rotation;
  /// Standard deviation of the tip position (m) per coordinate; NaN: the options' default.
  Vec3 tip_std = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  /// Standard deviation of the rotation (rad) per coordinate; NaN: the options' default.
  Vec3 rotation_std = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<MeasuredPoint> points;  ///< Measured backbone points.
};

/// @brief Measurements of one robot.
struct CalibrationData {
  std::string source;                     ///< File name (messages).
  std::vector<CalibrationSample> samples; ///< One per data row.
  /// True if some row gives a standard deviation (then the covariance is taken as it is, not
  /// scaled by the residuals; CalibrationOptions::covariance).
  bool has_std = false;
};

/// @brief Parse calibration data (CSV text) for the robot of `scene`. Lines starting with `#` are
/// comments (a sweep's first line); the first other line is the header. Columns: the inputs
/// (`actuation.tensions[k]`, `actuation.displacements[k]`, `loads.tip_force[i]`,
/// `loads.tip_moment[i]`, `loads.gravity[i]`; the others keep the scene's value), the
/// measurements (`tip_x/y/z`, `rot_x/y/z`, `point_x/y/z@S`, each group complete or absent, in a
/// row all given or all empty), standard deviations (a measurement column's name + `_std`,
/// positive), and a sweep's bookkeeping columns `sample`, `model`, `reason`, `iterations`,
/// `solve_time_s` (ignored) and `status` (must be `converged`).
///
/// Throws InputError naming the line and column (field `SOURCE line L, column C`) and the value
/// for any bad row: a number that is not finite or not a number, a negative tension, a wrong
/// number of fields, a row without a measurement, a status other than converged; and for a bad
/// header: an unknown column, a robot/effects/solver column (a sweep over the robot is not the
/// data of one robot), an incomplete group, a duplicate, no measurement column. No row is
/// skipped.
CalibrationData parse_calibration_data(const std::string& csv_text, const Scene& scene,
                                       const std::string& source = "<string>");

/// @brief Read and parse a calibration data file (parse_calibration_data). A missing or
/// unreadable file is an InputError whose field is the path.
CalibrationData read_calibration_data(const std::string& path, const Scene& scene);

/// @brief What a fitted parameter changes.
enum class CalibrationParameterKind {
  YoungsModulus,       ///< robot.backbone.youngs_modulus (Pa).
  ShearModulus,        ///< robot.backbone.shear_modulus (Pa; starts at E / (2 (1 + nu)) if unset).
  SegmentOffsetScale,  ///< Factor on the (x, y) positions of the tendons ending in segment i.
  TendonOffsetScale,   ///< Factor on the (x, y) position of tendon k.
  SegmentLength,       ///< robot.segments[i].length (m).
  DiskMass,            ///< robot.segments[i].disk_mass (kg).
  TendonStiffness,     ///< robot.segments[i].tendons[j].stiffness (N) of tendon k (must be set).
  FrictionCoefficient, ///< effects.tendon_friction.coefficient.
  BaseOffset,          ///< Translation of the base frame (m), component i.
  BaseRotation         ///< Rotation of the base frame (rotation vector, rad), component i.
};

/// @brief A parameter group to fit, as `--fit` names it: `youngs_modulus`, `shear_modulus`,
/// `segment_offset_scale`, `tendon_offset_scale`, `segment_length`, `disk_mass`,
/// `tendon_stiffness`, `friction_coefficient`, `base_offset`, `base_rotation`; a group with
/// an index (`segment_length[1]`) is one of its parameters, without it every one (one per
/// segment, tendon or component).
struct CalibrationParameterSpec {
  std::string name;  ///< The group name.
  CalibrationParameterKind kind = CalibrationParameterKind::YoungsModulus;  ///< The group.
  int index = -1;    ///< One member (segment, tendon or component), or -1: all.
  std::optional<double> lower;  ///< Lower bound (the parameter's unit); none: physical limit.
  std::optional<double> upper;  ///< Upper bound; none: unbounded.
};

/// @brief Parse a `--fit` list: names separated by commas, each optionally with bounds as
/// `name:LOWER:UPPER` (either may be empty), e.g. `youngs_modulus:1e10:1e12,base_offset`.
/// Throws InputError (field `--fit`) naming the entry on an unknown name (with the known names),
/// a malformed index or bound, a negative bound of a positive quantity, LOWER >= UPPER, or a
/// name given twice.
std::vector<CalibrationParameterSpec> parse_calibration_parameters(const std::string& list);

/// @brief How the standard errors are scaled.
enum class CovarianceScaling {
  Automatic,  ///< By the residuals (reduced chi-square) unless the data give standard deviations.
  Measured,   ///< The standard deviations are taken as true: covariance (J^T J)^-1.
  Residuals   ///< Always scaled by the reduced chi-square 2 cost / (m - p).
};

/// @brief The robust loss on each measurement's standardised squared residual.
enum class CalibrationLoss {
  None,    ///< Plain least squares.
  Huber,   ///< Quadratic up to loss_scale standard deviations, linear beyond (default).
  Cauchy   ///< log(1 + s / scale^2): large residuals count little.
};

/// @brief Text name ("none", "huber", "cauchy").
std::string to_string(CalibrationLoss loss);

/// @brief How the model parameters' columns of the Jacobian are computed.
enum class CalibrationJacobian {
  /// The implicit function theorem: each answer's F_x once per Jacobian, then per parameter one
  /// residual evaluation of the model rebuilt at the shifted parameter and one output pass
  /// (AnswerLinearisation); a measurement it cannot take (CC, displacement input) is solved.
  ImplicitFunction,
  /// Structured forward differences: per parameter every measurement solved again (warm).
  Differences
};

/// @brief Settings of a calibration, in the spirit of ceres::Solver::Options.
struct CalibrationOptions {
  ModelKind model = ModelKind::VC;                    ///< The model whose parameters are fitted.
  std::vector<CalibrationParameterSpec> parameters;   ///< What to fit (at least one).
  CalibrationLoss loss = CalibrationLoss::Huber;      ///< Robust loss per measurement.
  /// Scale of the loss in standard deviations: residuals (standardised, per measurement) beyond
  /// it are down-weighted.
  double loss_scale = 3.0;
  double position_std = 1e-4;  ///< Standard deviation of a position where the data give none (m).
  double rotation_std = 1e-3;  ///< Standard deviation of a rotation where the data give none (rad).
  int max_iterations = 100;    ///< Levenberg-Marquardt iterations (Ceres).
  double function_tolerance = 1e-10;   ///< Ceres: relative decrease of the cost below which it stops.
  double parameter_tolerance = 1e-8;   ///< Ceres: relative step (of the scaled parameters) below which it stops.
  double gradient_tolerance = 1e-12;   ///< Ceres: gradient max-norm below which it stops.
  /// Forward-difference step relative to each parameter's scale (its starting magnitude, or a
  /// typical size for a start at 0: 1 % of the robot's length for base_offset, 0.01 rad for
  /// base_rotation, 0.1 for friction, 1 g for a disk mass).
  double difference_step = 1e-6;
  /// Singular values of the scaled Jacobian below this times the largest are zero: their
  /// directions are not identifiable from the data.
  double rank_tolerance = 1e-7;
  /// A direction of the scaled parameters (relative changes) is not identifiable either if its
  /// standard error from the data's standard deviations, 1 / singular value of the standardised
  /// scaled Jacobian, exceeds this: with 1 (default), a 100 % change of that combination of
  /// parameters moves the fit by less than one standard deviation of the measurements.
  double max_relative_std = 1.0;
  CovarianceScaling covariance = CovarianceScaling::Automatic;  ///< How standard errors are scaled.
  /// Newton tolerance of the forward solves (scaled residual): tight, as the differences need it.
  double solve_function_tolerance = 1e-12;
  /// Warm-start the solves: the residual points' from the last iterate's answers, each then taken
  /// to Newton's tolerance 1e-13 so that its answer does not depend on the start; the
  /// differences' from the unperturbed answers. False: every solve cold, to
  /// solve_function_tolerance (for comparison; bench_calibration measures both). The
  /// implicit-function columns solve nothing either way.
  bool warm_start = true;
  /// The model parameters' Jacobian columns (bench_calibration measures both).
  CalibrationJacobian jacobian = CalibrationJacobian::ImplicitFunction;

  /// @brief Throws InputError (field `calibration.<name>`) naming the value: no parameter, a
  /// tolerance, step or standard deviation that is not a positive finite number, fewer than 1
  /// iteration, a Newton tolerance outside SolverOptions' range.
  void validate() const;
};

/// @brief A fitted parameter.
struct FittedParameter {
  std::string name;   ///< E.g. `youngs_modulus`, `segment_offset_scale[1]`, `base_offset[2]`.
  std::string unit;   ///< "Pa", "m", "kg", "N", "rad" or "" (a factor).
  double initial = 0.0;  ///< Starting value (the scene's, or the identity for a scale or offset).
  double value = 0.0;    ///< Fitted value.
  /// Standard error from the covariance; +infinity if the parameter is not identifiable.
  double std_error = 0.0;
  double lower = -std::numeric_limits<double>::infinity();  ///< Lower bound used.
  double upper = std::numeric_limits<double>::infinity();   ///< Upper bound used.
  bool identifiable = true;  ///< False if it has a share in a null direction of the Jacobian.
  bool at_bound = false;     ///< True if the fit ended on a bound.
};

/// @brief The residual of one measurement.
struct SampleResidual {
  int line = 0;                 ///< Data line (0 if not from a file).
  double tip_error = 0.0;       ///< |tip - measured tip| (m); 0 without a tip measurement.
  double rotation_error = 0.0;  ///< Angle of R R_measured^T (rad); 0 without one.
  double point_error = 0.0;     ///< Largest |point - measured point| (m); 0 without points.
  double standardised = 0.0;    ///< Norm of its standardised residual vector.
  bool solved = true;           ///< False if the model did not converge for it.
};

/// @brief Errors of a fit over all measurements (positions in m, rotations in rad).
struct ResidualStatistics {
  /// Root mean square over the measurements of each one's position error (m): the root of its
  /// tip error squared plus its largest point error squared.
  double rms_position = 0.0;
  double max_position = 0.0;  ///< Largest tip or point error (m).
  double rms_rotation = 0.0;  ///< RMS of the rotation errors (rad), 0 without rotations.
  double max_rotation = 0.0;  ///< Largest rotation error (rad).
  double rms_standardised = 0.0;  ///< RMS of the standardised residual components.
};

/// @brief Diagnostics of a calibration, in the spirit of ceres::Solver::Summary.
struct CalibrationSummary {
  bool converged = false;    ///< Ceres ended by a tolerance (not by iterations or failure).
  std::string termination;   ///< Ceres's termination ("CONVERGENCE", "NO_CONVERGENCE", "FAILURE").
  std::string message;       ///< Ceres's message.
  int iterations = 0;        ///< Ceres iterations.
  int forward_solves = 0;    ///< Model solves, the differences' included.
  int failed_solves = 0;     ///< Solves that did not converge (their measurement's step rejected).
  /// Answers of the Jacobian's model-parameter columns linearised instead of solved
  /// (CalibrationJacobian::ImplicitFunction).
  int linearised_answers = 0;
  double initial_cost = 0.0; ///< Ceres cost at the start.
  double final_cost = 0.0;   ///< Ceres cost at the end.
  ResidualStatistics before; ///< At the start.
  ResidualStatistics after;  ///< At the fitted parameters.
  double time_s = 0.0;       ///< Wall time (s).
  /// @brief One line: "converged: 5 iterations, 3200 solves, position RMS 0.00652 -> 0.00018 m
  /// (max 0.0151 -> 0.000367 m), 0.367 s".
  std::string brief_report() const;
};

/// @brief The answer of a calibration.
struct CalibrationResult {
  Scene scene;  ///< The scene with the fitted values (its `model` is the fitted model).
  /// The fitted base frame in the scene's base frame (identity unless base_offset/base_rotation
  /// are fitted): a point x of the model is measured at base.R x + base.p. A scene file has no
  /// base frame: it is reported here (and by the CLI), not in `scene`.
  Frame base;
  std::vector<FittedParameter> parameters;  ///< In fit order.
  /// Of the parameters (their units); non-identifiable rows: inf. From the Jacobian weighted by
  /// the robust loss at the solution (each measurement by rho'(s) of its squared standardised
  /// residual, normalised by the mean weight) and, when scaled by the residuals, the weighted
  /// residuals: a measurement the loss down-weights (an outlier) does not inflate the standard
  /// errors; without down-weighting it is the plain covariance.
  Eigen::MatrixXd covariance;
  Eigen::MatrixXd correlation;  ///< Correlation matrix (NaN where not identifiable).
  /// Singular values of the Jacobian scaled by the parameters' scales (and weighted as for the
  /// covariance), largest first.
  Eigen::VectorXd singular_values;
  std::vector<std::string> non_identifiable;  ///< Names of the parameters not identifiable.
  /// Empty, or one sentence naming the non-identifiable parameters and the null direction.
  std::string warning;
  std::vector<SampleResidual> residuals_before;  ///< Per measurement, at the start.
  std::vector<SampleResidual> residuals_after;   ///< Per measurement, at the fitted values.
  CalibrationSummary summary;  ///< Diagnostics.
  /// @brief summary.converged.
  bool converged() const { return summary.converged; }
};

/// @brief Fit the parameters of options.model of `scene`'s robot to `data`.
///
/// Starts from the scene's values (scales from 1, base offsets from 0). Forward solves use
/// scene.solver with Newton's tolerance options.solve_function_tolerance, exact Newton from a
/// fresh Jacobian (SolverOptions::reuse_jacobian off: no workspace history in the answers), RK4
/// on a fixed mesh (VC, VCref with the accuracy-driven integrator: the finest mesh it chooses for
/// the measurements at the start; a mesh that changed with the parameters would break the
/// differences), no stability test and no differential kinematics. Throws InputError on invalid options, a
/// parameter the scene cannot take (a tendon stiffness that is not set, E with direct
/// stiffnesses, an index out of range, bounds that exclude the start), or a model that fails at
/// the starting parameters for some measurement (named by its line).
CalibrationResult calibrate(const Scene& scene, const CalibrationData& data, const CalibrationOptions& options);

}  // namespace tdcr
