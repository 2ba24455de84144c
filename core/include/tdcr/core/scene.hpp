/// @file scene.hpp
/// @brief A scene: a robot, its actuation, the external loads, the effects to simulate, and the
/// model to solve it with. A scene names what it simulates; models assemble and evaluate only
/// that (see SceneEffects).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr {

/// @brief How the tendons are actuated.
struct Actuation {
  /// @brief What Actuation::values hold.
  enum class Kind {
    Tensions,      ///< Tendon tensions (N), >= 0, pulling each tendon's end towards the base.
    Displacements  ///< Tendon displacements (m) at the base, positive when the tendon is pulled.
  };
  /// @brief Reference of a displacement for tendons that run through several segments.
  enum class DisplacementConvention {
    AtBase,      ///< What the actuator at the base sees: every segment the tendon runs through
                 ///< contributes (Jones & Walker 2006). Default.
    PerSegment   ///< Only the tendon's own segment (the paper's code convention).
  };
  Kind kind = Kind::Tensions;  ///< What every value is (unless `kinds` is given).
  std::vector<double> values;  ///< One value per tendon, in global tendon order.
  /// How displacements are referenced: for displacement input and for the
  /// Solution::tendon_displacements that every model reports.
  DisplacementConvention convention = DisplacementConvention::AtBase;
  /// Mixed input: what values[k] is, per tendon (then `kind` is Displacements: the input is not
  /// tensions alone). Empty: every value is `kind`.
  std::vector<Kind> kinds;

  /// @brief What values[k] is.
  Kind kind_of(std::size_t k) const { return kinds.empty() ? kind : kinds[k]; }
  /// @brief True if some tendons are given by tension and others by displacement.
  bool mixed() const { return !kinds.empty(); }
};

/// @brief External loads. Tip force and moment act at the backbone centre of the tip disk and
/// are given in the base frame. Gravity is a vector in the base frame (m/s^2).
struct Loads {
  Vec3 tip_force = Vec3::Zero();   ///< N, base frame.
  Vec3 tip_moment = Vec3::Zero();  ///< N m, base frame.
  Vec3 gravity = Vec3::Zero();     ///< m/s^2, base frame; zero means no gravity.
};

/// @brief Disk reaction model at disks a tendon only passes through.
enum class DiskNormalForce {
  Removed,  ///< The tendon force component along the disk normal is removed (paper Eq. 58, its
            ///< case study's setting). Not an equilibrium of a frictionless hole: the dropped
            ///< force acts on neither robot nor tendon (docs/models.md, "The tendon force at a disk").
  Kept      ///< The full force of Eq. 32-33: a frictionless hole, one tension on both sides. Default.
};

/// @brief Tendon path assumption for the CC model.
enum class TendonPath {
  FullyConstrained,     ///< Tendons parallel to the backbone (Eq. 14-18).
  PartiallyConstrained  ///< Straight chords between disks (Eq. 20-23).
};

/// @brief Characteristic parameters of the 3R pseudo-rigid-body model (paper Table 1).
struct PrbParameters {
  /// Link length factors gamma_0..3. Default: Table 1 divided by their sum 0.999 so that the
  /// links add up to the subsegment length (as the paper's code does).
  double gamma[4] = {0.125 / 0.999, 0.35 / 0.999, 0.388 / 0.999, 0.136 / 0.999};
  /// Spring stiffness factors K_Theta_1..3: k_q = K_Theta_q EI / l (Eq. 49).
  double k_theta[3] = {3.25, 2.84, 2.95};
};

/// @brief Capstan friction between the tendons and the disk holes (or the lumen), with the
/// direction of tendon motion that sets its sign (hysteresis). Off (coefficient 0) by default.
///
/// The tension input is the tension at the actuator (base). Walking from the base along the
/// tendon, its tension changes by exp(-/+ mu theta) where the tendon turns by the angle theta
/// (discrete models: at each hole; VC: dT/ds = -/+ mu |f_k|). Pulling: the tendon slides
/// towards the actuator and friction opposes, so the tension drops away from the base (-);
/// releasing: it rises (+). Quasi-static, one known direction of motion per solve, no
/// stick-slip transition inside a solve (docs/models.md).
struct TendonFriction {
  /// @brief Direction in which the tendons slide during the step that this solve models.
  enum class Motion {
    Pulling,   ///< Tendons pulled (tension rising): tension decreases away from the base.
    Releasing  ///< Tendons released (tension falling): tension increases away from the base.
  };
  double coefficient = 0.0;          ///< Friction coefficient mu (>= 0) of every tendon.
  std::vector<double> coefficients;  ///< Optional, one per tendon (global order), overriding `coefficient`.
  Motion motion = Motion::Pulling;   ///< Direction of tendon motion.

  /// @brief mu of tendon k (global index).
  double of(int k) const { return coefficients.empty() ? coefficient : coefficients[k]; }
  /// @brief True if some tendon has a nonzero coefficient.
  bool on() const;
  /// @brief +1 when releasing, -1 when pulling: the sign of dT/d(turning angle).
  double sign() const { return motion == Motion::Releasing ? 1.0 : -1.0; }
};

/// @brief What the scene asks to simulate. Part of a model's description (a model is built from
/// a Robot and its Effects); defaults are the paper's code.
struct Effects {
  bool shear_extension = true;  ///< Cosserat rod with shear and extension (VC, VCref); CC, CCsub
                                ///< and PRB shorten under the tendons' compression (axial strain
                                ///< -sum T / EA per segment or subsegment); else inextensible,
                                ///< unshearable Kirchhoff rod (the paper's CCsub and PRB).
  DiskNormalForce disk_normal_force = DiskNormalForce::Kept;  ///< Eq. 32-33 or Eq. 58 (VCref, CCsub, PRB).
  /// VC: the point force T_k R (t_k+ - t_k-) of a tensioned tendon passing a disk where the
  /// strains jump (VcOptions::kink_forces). False: the paper code's formulation, which omits it.
  bool kink_forces = true;
  TendonPath tendon_path = TendonPath::FullyConstrained;         ///< CC only.
  PrbParameters prb;                                             ///< PRB only.
  TendonFriction tendon_friction;  ///< Capstan friction (CCsub, PRB, VC, VCref); off by default.

  /// @brief Throws InputError (field `effects.prb.gamma[i]` or `effects.prb.k_theta[i]`) on a
  /// PRB parameter that is not a positive finite number, and (field
  /// `effects.tendon_friction.coefficient` or `...coefficients[k]`) on a friction coefficient that
  /// is negative or not finite.
  void validate() const;
  /// @brief validate() and the checks that need the robot: one friction coefficient per tendon
  /// (`effects.tendon_friction.coefficients`) when the list is given.
  void validate(const Robot& robot) const;
};

/// @brief A rigid obstacle in the base frame (docs/contact.md). Its signed distance is positive
/// in free space (where the robot may be) and negative inside the obstacle; for a `Lumen` the
/// free space is the inside of the tube, so the robot must stay inside.
struct Obstacle {
  /// @brief The primitive.
  enum class Type {
    Plane,     ///< Half space {x : (x - point) . normal < 0} is solid; `normal` points to free space.
    Sphere,    ///< Solid ball (`center`, `radius`).
    Cylinder,  ///< Solid cylinder with flat caps, axis from `ends[0]` to `ends[1]`, `radius`.
    Capsule,   ///< Solid capsule: the points within `radius` of the segment `ends[0]`-`ends[1]`.
    Lumen      ///< A tube of inner `radius` around the polyline `centreline`; the robot is inside.
  };
  Type type = Type::Plane;               ///< The primitive.
  Vec3 point = Vec3::Zero();             ///< Plane: a point on it (m).
  Vec3 normal = Vec3::UnitZ();           ///< Plane: normal towards free space (need not be unit).
  Vec3 center = Vec3::Zero();            ///< Sphere: centre (m).
  double radius = 0.0;                   ///< Sphere, cylinder, capsule: radius; lumen: inner radius (m).
  Vec3 ends[2] = {Vec3::Zero(), Vec3::UnitZ()};  ///< Cylinder, capsule: the axis end points (m).
  std::vector<Vec3> centreline;          ///< Lumen: at least 2 points (m), straight or curved.
};

/// @brief How contact forces arise. Frictionless; rigid unless a stiffness is given.
struct ContactSettings {
  /// Compliant contact: the normal force is stiffness times the penetration (N/m); 0: rigid
  /// (force >= 0, gap >= 0, force gap = 0, solved exactly).
  double stiffness = 0.0;
};

/// @brief The robot's surroundings: obstacles the backbone and the disks may touch.
struct Environment {
  std::vector<Obstacle> obstacles;  ///< In the base frame; none: free space.
  ContactSettings contact;          ///< Rigid or compliant contact.

  /// @brief Throws InputError naming the field (`environment.obstacles[i].radius`, ...) and value:
  /// a non-finite number, a non-positive radius, a zero plane normal or cylinder axis, a lumen
  /// centreline with fewer than 2 points or a repeated point, a negative stiffness, and an
  /// obstacle that intersects the robot's base (its backbone or base disk at s = 0).
  void validate(const Robot& robot) const;
};

/// @brief The per-call input of a model: how the tendons are actuated and the external loads.
/// A model is built once from a robot and its effects; a trajectory is a sequence of inputs.
struct ModelInput {
  Actuation actuation;  ///< Tendon tensions or displacements, one value per tendon.
  Loads loads;          ///< Tip wrench and gravity (base frame).
  Environment environment;  ///< Obstacles the robot may touch (none: free space).

  /// @brief Throws InputError naming the field and value: a list of the wrong length for
  /// `robot`, a non-finite value, a negative tension, a non-finite load, an unusable obstacle
  /// (Environment::validate).
  void validate(const Robot& robot) const;
};

/// @brief Which physical effects a solve turns on, decided once before it so that inner loops
/// carry no branch for effects that are off.
struct SceneEffects {
  bool tip_wrench = false;       ///< Nonzero tip force or moment.
  bool gravity = false;          ///< Nonzero gravity and nonzero backbone or disk mass.
  bool backbone_weight = false;  ///< Gravity and nonzero backbone mass per length.
  bool disk_weight = false;      ///< Gravity and nonzero disk mass.
  bool shear_extension = true;            ///< Effects::shear_extension (every model).
  bool disk_normal_force_removed = false;  ///< Effects::disk_normal_force is Removed (Eq. 58).
  bool tendon_friction = false;           ///< Effects::tendon_friction is on (some mu > 0).
  bool contact = false;                   ///< The environment has obstacles (CCsub, PRB, VC, VCref).
};

/// @brief The effects a solve of `robot` with `effects` under `input` turns on.
SceneEffects active_effects(const Robot& robot, const Effects& effects, const ModelInput& input);

// --- Robots that move (tdcr/models/dynamics.hpp): the scene-file keys `dynamics` and `timeline`.

/// @brief The implicit time scheme of the Cosserat models (the lumped models use CVODE's BDF).
enum class TimeScheme {
  BdfAlpha,        ///< BDF-alpha (Till et al. 2019): alpha in [-0.5, 0]; alpha = 0 is BDF2.
  ImplicitMidpoint ///< Second order, conserves energy without damping (a check, not a default).
};

/// @brief Scene-file key `dynamics`: what the equations of motion add to the statics.
/// Mass comes from the robot (`robot.backbone.density` / `mass_per_length`, the disks'
/// `disk_mass`); a dynamic scene without mass is an input error.
struct DynamicsSettings {
  /// Kelvin-Voigt damping of bending and torsion, as a retardation time tau_bt (s): the damping
  /// moment is tau_bt K_bt du/dt. 0: undamped.
  double bending_damping_time = 0.0;
  /// Kelvin-Voigt damping of shear and extension, tau_se (s): tau_se K_se dv/dt. 0: undamped.
  /// (CCsub and PRB are inextensible: they have no such strain to damp.)
  double shear_damping_time = 0.0;
  /// Quadratic air drag per unit length, f = -air_drag |v| v (N s^2 / m^3). 0: none.
  double air_drag = 0.0;
  TimeScheme scheme = TimeScheme::BdfAlpha;  ///< Cosserat models only.
  double alpha = -0.2;                       ///< BDF-alpha parameter, in [-0.5, 0].

  /// @brief Throws InputError naming the field (`dynamics.<key>`) and value: a negative or
  /// non-finite damping time or drag, alpha outside [-0.5, 0].
  void validate() const;
};

/// @brief One entry of a scene's `timeline`: the input from time t on. Inputs between entries
/// are interpolated linearly (tensions or displacements, loads); an entry without actuation or
/// loads keeps the previous entry's.
struct TimelineEntry {
  double t = 0.0;        ///< s, strictly increasing along the timeline.
  ModelInput input;      ///< The actuation and loads at t.
};

/// @brief Scene-file key `timeline`.
struct Timeline {
  std::vector<TimelineEntry> entries;  ///< In order of t (strictly increasing).
  /// @brief The input at time t: linear between entries, the first before the first entry, the
  /// last after the last. An empty timeline has no input (InputError naming `timeline`).
  ModelInput at(double t) const;
  /// @brief at(t) into `out`, reusing its storage (no allocation once `out` has the size).
  void at(double t, ModelInput& out) const;
  /// @brief Throws InputError naming `timeline[i].t` (not increasing, not finite) or an input of
  /// the wrong length for `robot` (`timeline[i].actuation.values`), or entries whose actuation
  /// kinds differ (`timeline[i].actuation`: tensions cannot be interpolated with displacements).
  void validate(const Robot& robot) const;
};

// --- end of the dynamics keys.

/// @brief A complete problem: robot, actuation, loads, effects, model and solver settings.
struct Scene {
  Robot robot;          ///< The robot (scene-file key `robot`).
  Actuation actuation;  ///< Tendon tensions or displacements (`actuation`).
  Loads loads;          ///< Tip wrench and gravity (`loads`); none by default.
  Effects effects;      ///< Physical effects to simulate (`effects`).
  Environment environment;  ///< Obstacles and contact settings (`environment`); none by default.
  std::string model = "vc";  ///< "cc", "ccsub", "prb", "vc", "vcref" (or "auto").
  SolverOptions solver;  ///< Numerical settings (`solver`).
  std::optional<DynamicsSettings> dynamics;  ///< `dynamics`: absent in a static scene.
  Timeline timeline;                         ///< `timeline`: empty in a static scene.

  /// @brief Throws InputError naming the field and value for any unusable entry: the robot's
  /// (Robot::validate), the input's (ModelInput::validate), the effects' (Effects::validate(robot)), an
  /// invalid solver option (SolverOptions::validate). The model name is checked against the
  /// model registry by the models layer (tdcr::validate_scene, models/static_model.hpp).
  void validate() const;
  /// @brief The per-call part of the scene: actuation and loads.
  ModelInput input() const { return ModelInput{actuation, loads, environment}; }
  /// @brief The effects this scene enables (see SceneEffects).
  SceneEffects active_effects() const { return tdcr::active_effects(robot, effects, input()); }
};

}  // namespace tdcr
