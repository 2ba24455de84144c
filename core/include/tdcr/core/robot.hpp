/// @file robot.hpp
/// @brief The immutable description of a tendon-driven continuum robot: backbone material and
/// cross section, segments with their spacer disks, and the tendon routing.
///
/// Conventions (docs/conventions.md): SI units; the base frame has z along the straight
/// backbone; a tendon is given by the segment where it terminates and its (x, y) position in
/// the disk frame; it runs through every disk from the base to the end of its segment. Tendons
/// are numbered segment by segment in input order.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "tdcr/core/types.hpp"

namespace tdcr {

/// @brief Cross-section stiffnesses of the backbone (paper Eq. 36-37), isotropic in bending.
struct BackboneStiffness {
  double EI = 0.0;  ///< Bending stiffness (N m^2), both bending axes.
  double GJ = 0.0;  ///< Torsional stiffness (N m^2).
  double EA = 0.0;  ///< Axial stiffness (N).
  double GA = 0.0;  ///< Shear stiffness (N), both shear axes.
};

/// @brief Backbone material and geometry. Either give the material (Young's modulus, Poisson
/// ratio or shear modulus) and the tube radii, or give the stiffnesses directly.
///
/// Defaults follow the paper's Table 3: a 0.8 mm NiTi/steel rod with E = 2.11e11 Pa, nu = 0.3
/// (G = E / 2.6), solid circular section, J = 2 I.
struct Backbone {
  double youngs_modulus = 2.11e11;       ///< E (Pa).
  double poisson_ratio = 0.3;            ///< nu; G = E / (2 (1 + nu)) unless shear_modulus set.
  std::optional<double> shear_modulus;   ///< G (Pa); overrides poisson_ratio when set.
  double outer_radius = 0.0004;          ///< r_o (m).
  double inner_radius = 0.0;             ///< r_i (m), 0 for a solid rod.
  std::optional<BackboneStiffness> stiffness;  ///< Direct stiffnesses; override the material.
  double density = 0.0;                  ///< kg/m^3, used for gravity only.
  std::optional<double> mass_per_length; ///< kg/m; overrides density * area when set.

  /// @brief Effective stiffnesses: direct ones if given, else from material and section
  /// (I = pi/4 (ro^4 - ri^4), J = 2 I, A = pi (ro^2 - ri^2)).
  BackboneStiffness effective_stiffness() const;
  /// @brief Mass per unit length (kg/m) for gravity.
  double linear_mass() const;
};

/// @brief How a tendon runs from the base to its end disk (docs/models.md, "Tendon routing").
struct TendonRoutingSpec {
  /// @brief The kind of path.
  enum class Type {
    Straight,  ///< Parallel to the backbone at (x, y) in every disk.
    Helical,   ///< Radius |(x, y)| kept, angle advancing linearly by `turns` from the base to the end disk.
    Points,    ///< Given hole positions, one per disk after the base disk (the base hole is (x, y)).
  };
  Type type = Type::Straight;                    ///< The kind of path.
  double turns = 0.0;                            ///< Helical: turns over the tendon's length (sign: direction).
  std::vector<std::array<double, 2>> positions;  ///< Points: (x, y) in disks 1..end disk (m).
};

/// @brief A tendon: its position (x, y) in the disk frame (m) at the base; the z component is 0.
struct TendonSpec {
  TendonSpec() = default;
  TendonSpec(double x_, double y_) : x(x_), y(y_) {}  ///< Straight routing at (x, y).
  double x = 0.0;  ///< x coordinate of the tendon hole in the disk frame (m).
  double y = 0.0;  ///< y coordinate of the tendon hole in the disk frame (m).
  /// Axial stiffness EA of the tendon (N) for displacement input: the tension is EA / L_free
  /// times the stretch (L_free: base to end disk of the straight robot). Absent: inextensible.
  std::optional<double> stiffness;
  TendonRoutingSpec routing;  ///< Straight unless given.
};

/// @brief One segment: a length of backbone with equally spaced spacer disks; the tendons
/// listed here terminate at its last disk.
struct Segment {
  double length = 0.05;              ///< m.
  int disks = 10;                    ///< Spacer disks in the segment, the last one at its end.
  std::vector<TendonSpec> tendons;   ///< Tendons terminating at this segment's end.
  double disk_mass = 0.0;            ///< kg per disk, used for gravity only.
  /// Outer radius of the spacer disks (m), their contact surface; 0: only the backbone touches.
  double disk_radius = 0.0;
};

/// @brief The robot: a backbone and its segments, base to tip.
struct Robot {
  Backbone backbone;              ///< Material and cross section, the same along the robot.
  std::vector<Segment> segments;  ///< Segments from the base (index 0) to the tip.

  /// @brief Throws InputError naming the field (e.g. `robot.segments[0].length`) if any value is
  /// unusable: a non-finite number; a non-positive Young's modulus, outer radius, shear modulus,
  /// direct stiffness or segment length; an inner radius outside [0, outer radius); a Poisson
  /// ratio outside (-1, 0.5); a negative density, mass per length or disk mass; no segment; a
  /// segment with fewer than 1 disk; a tendon within 1e-9 m of the backbone axis; a non-finite
  /// helix `turns`; a points routing whose count is not the number of disks the tendon passes
  /// (base disk excluded), or with a non-finite point or one on the axis. A segment without
  /// tendons is allowed (a passive segment).
  void validate() const;

  double total_length() const;  ///< Sum of segment lengths (m).
  int total_disks() const;      ///< Sum of disks over segments (not counting the base disk).
  int tendon_count() const;     ///< Number of tendons over all segments.
};

/// @brief One tendon as the models see it: global index, the segment where it terminates and
/// its position vector in the disk frame (z = 0) at the base; for non-straight routing the data
/// of its offset r(s), evaluated by the models (models/physics/tendon_path.hpp).
struct RoutedTendon {
  int index = 0;                 ///< Global tendon number (0-based, input order).
  int segment = 0;               ///< Segment (0-based) at whose last disk it terminates.
  Vec3 r = Vec3::Zero();         ///< Position in the disk frame at the base (m).
  int end_disk = 0;              ///< Index of its terminating disk in the disk list (1-based;
                                 ///< 0 is the base disk).
  TendonRoutingSpec::Type routing = TendonRoutingSpec::Type::Straight;  ///< How r varies with s.
  double helix_radius = 0.0;     ///< Helical: |r| (m).
  double helix_phase = 0.0;      ///< Helical: angle of r at s = 0 (rad).
  double helix_rate = 0.0;       ///< Helical: angle rate 2 pi turns / s_end (rad/m).
  /// Points: a natural C2 cubic spline per coordinate through the holes of disks 0..end_disk
  /// over their arc lengths; these are its knots (the disks' arc lengths).
  std::vector<double> knots;
  /// Points: per spline interval the Taylor coefficients at its start (x, dx, d2x / 2, d3x / 6,
  /// then the same for y).
  std::vector<std::array<double, 8>> spline;
  std::vector<Vec3> holes;       ///< Points: the hole of every disk 0..end_disk (exact).
  /// @brief True for straight routing (a constant offset r).
  bool straight() const { return routing == TendonRoutingSpec::Type::Straight; }
};

/// @brief The discretisation of a robot into disks and the tendon routing through them.
///
/// Disk list: index 0 is the base disk at s = 0, then every spacer disk, segment by segment;
/// the last disk is the tip. Disk j of segment i sits at s = s_i + j L_i / n_i.
struct TendonRouting {
  std::vector<RoutedTendon> tendons;     ///< All tendons, in global order.
  std::vector<double> disk_s;            ///< Arc length of every disk (size total_disks + 1).
  std::vector<int> disk_segment;         ///< Segment of every disk (base disk: 0).
  std::vector<int> segment_end_disk;     ///< Index of each segment's last disk.
  std::vector<double> segment_start_s;   ///< Arc length where each segment starts.
  std::vector<double> segment_end_s;     ///< Arc length where each segment ends.

  /// @brief Build from a validated robot.
  static TendonRouting from(const Robot& robot);
  int disk_count() const { return static_cast<int>(disk_s.size()); }  ///< Including base disk.
  /// @brief True if tendon k runs through (or ends at) disk j (j >= 1).
  bool passes(int k, int disk) const { return disk >= 1 && disk <= tendons[k].end_disk; }
};

}  // namespace tdcr
