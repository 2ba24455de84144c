/// @file metrics.hpp
/// @brief Error metrics of paper Eq. 57 between a model's tip poses and a reference.
#pragma once

#include <vector>

#include "tdcr/core/types.hpp"

namespace tdcr {

/// @brief Tip error of one configuration against a reference.
struct TipError {
  double position = 0.0;  ///< ||p - p_ref|| (m).
  double angle = 0.0;     ///< Angle of R R_ref^T (rad), on the nearest rotations of both.
};

/// @brief Tip position and orientation error of `tip` against `reference`.
TipError tip_error(const Frame& tip, const Frame& reference);

/// @brief Mean errors over configurations (paper Eq. 57).
struct MeanTipError {
  double e_p_percent = 0.0;  ///< Mean ||p - p_ref|| / length, in % of `length`.
  double e_R_deg = 0.0;      ///< Mean rotation angle (deg).
  double max_p_percent = 0.0;  ///< Largest ||p - p_ref|| / length over the configurations (%).
  double max_R_deg = 0.0;      ///< Largest rotation angle over the configurations (deg).
};

/// @brief Eq. 57 over paired lists of tip frames; `length` is the robot length (2L in the paper).
/// Throws std::invalid_argument if the lists are empty or differ in size.
MeanTipError mean_tip_error(const std::vector<Frame>& tips, const std::vector<Frame>& references,
                            double length);

}  // namespace tdcr
