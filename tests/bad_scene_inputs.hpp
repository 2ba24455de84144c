// The table of bad scene files shared by the scene-file tests (test_scene_io.cpp, through the C++
// API) and the command-line tests (test_cli.cpp, through `tdcr solve`): each entry is a scene
// file text, the field its InputError must name and the text (value) its message must contain.
// Every entry is rejected by tdcr::parse_scene, except an unknown model name, which the models
// layer rejects (tdcr::validate_scene): a program reading a scene file calls both.
#pragma once

#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bad_scenes {

using json = nlohmann::json;

/// A small valid scene: two segments of two tendons each, tension actuated.
inline json base_scene() {
  return json::parse(R"({
    "robot": {
      "backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
      "segments": [
        {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        {"length": 0.05, "disks": 10, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]}
      ]
    },
    "actuation": {"tensions": [1.0, 0.0, 0.0, 0.0]},
    "model": "vc"
  })");
}

/// The base scene with the value at JSON pointer `ptr` set to `v`.
inline std::string with(const std::string& ptr, const json& v) {
  json j = base_scene();
  j[json::json_pointer(ptr)] = v;
  return j.dump();
}

/// The base scene with the value at `ptr` replaced by raw JSON text (for 1e999 and friends).
inline std::string with_raw(const std::string& ptr, const std::string& raw) {
  const std::string marker = "@@RAW@@";
  std::string text = with(ptr, marker);
  text.replace(text.find("\"" + marker + "\""), marker.size() + 2, raw);
  return text;
}

/// The base scene without the value at `ptr`.
inline std::string without(const std::string& ptr) {
  json j = base_scene();
  const json::json_pointer p(ptr);
  j[p.parent_pointer()].erase(p.back());
  return j.dump();
}

/// The base scene changed by `edit`.
inline std::string edited(const std::function<void(json&)>& edit) {
  json j = base_scene();
  edit(j);
  return j.dump();
}

struct BadInput {
  std::string name;      ///< Test name suffix.
  std::string text;      ///< Scene file text.
  std::string field;     ///< Expected InputError::field().
  std::string in_what;   ///< Text what() must contain (the offending value, or a message part).
};

inline std::ostream& operator<<(std::ostream& os, const BadInput& b) { return os << b.name; }

inline std::vector<BadInput> bad_inputs() {
  return {
      // Malformed files
      {"MalformedTrailingComma", R"({"robot": {},})", "scene.json", "byte"},
      {"EmptyText", "", "scene.json", "byte 1"},
      {"RootIsArray", "[1, 2]", "scene.json", "[1,2]"},
      {"DuplicateKey",
       R"({"robot": {"segments": [{"length": 0.05, "length": 0.04, "disks": 1, "tendons": []}]},
           "actuation": {"tensions": []}})",
       "robot.segments[0].length", "duplicate"},
      {"NumberOverflow", with_raw("/robot/segments/1/length", "1e999"), "robot.segments[1].length", "1e999"},
      {"NumberOverflowInArray", with_raw("/actuation/tensions/2", "-1e999"), "actuation.tensions[2]", "-1e999"},
      // Missing required keys
      {"MissingRobot", without("/robot"), "robot", "is required"},
      {"MissingSegments", without("/robot/segments"), "robot.segments", "is required"},
      {"MissingLength", without("/robot/segments/1/length"), "robot.segments[1].length", "is required"},
      {"MissingDisks", without("/robot/segments/0/disks"), "robot.segments[0].disks", "is required"},
      {"MissingTendons", without("/robot/segments/0/tendons"), "robot.segments[0].tendons", "is required"},
      {"MissingTendonY", without("/robot/segments/0/tendons/1/y"), "robot.segments[0].tendons[1].y",
       "is required"},
      {"MissingActuation", without("/actuation"), "actuation", "is required"},
      {"ActuationEmpty", with("/actuation", json::object()), "actuation", "tensions"},
      // Wrong types
      {"RobotNotObject", with("/robot", 3), "robot", "3"},
      {"SegmentsNotArray", with("/robot/segments", json::object()), "robot.segments", "{}"},
      {"SegmentsEmpty", with("/robot/segments", json::array()), "robot.segments", "[]"},
      {"LengthString", with("/robot/segments/1/length", "0.05"), "robot.segments[1].length", "\"0.05\""},
      {"LengthBool", with("/robot/segments/0/length", true), "robot.segments[0].length", "true"},
      {"LengthNull", with("/robot/segments/0/length", nullptr), "robot.segments[0].length", "null"},
      {"DisksFloat", with("/robot/segments/0/disks", 2.5), "robot.segments[0].disks", "2.5"},
      {"DisksHuge", with_raw("/robot/segments/0/disks", "10000000000"), "robot.segments[0].disks",
       "10000000000"},
      {"TendonNotObject", with("/robot/segments/0/tendons/0", json::array({0, 0.008})),
       "robot.segments[0].tendons[0]", "[0,0.008]"},
      {"TendonXString", with("/robot/segments/1/tendons/0/x", "zero"), "robot.segments[1].tendons[0].x",
       "\"zero\""},
      {"TensionString", with("/actuation/tensions/0", "1"), "actuation.tensions[0]", "\"1\""},
      {"TensionsNotArray", with("/actuation/tensions", 1.0), "actuation.tensions", "1.0"},
      {"TipForceTwoValues", with("/loads", {{"tip_force", {0, 0.5}}}), "loads.tip_force", "[0,0.5]"},
      {"TipForceString", with("/loads", {{"tip_force", {"0", 0.5, 0}}}), "loads.tip_force[0]", "\"0\""},
      {"GravityNull", with("/loads", {{"gravity", {0, nullptr, -9.81}}}), "loads.gravity[1]", "null"},
      {"ShearExtensionString", with("/effects", {{"shear_extension", "yes"}}), "effects.shear_extension",
       "\"yes\""},
      {"KinkForcesNumber", with("/effects", {{"kink_forces", 0}}), "effects.kink_forces", "0"},
      {"DiskNormalForceUnknown", with("/effects", {{"disk_normal_force", "ignored"}}),
       "effects.disk_normal_force", "\"ignored\""},
      {"TendonPathUnknown", with("/effects", {{"tendon_path", "free"}}), "effects.tendon_path", "\"free\""},
      {"PrbGammaThreeValues", with("/effects", {{"prb", {{"gamma", {0.1, 0.3, 0.4}}}}}), "effects.prb.gamma",
       "[0.1,0.3,0.4]"},
      {"PrbKThetaNegative", with("/effects", {{"prb", {{"k_theta", {3.25, -2.84, 2.95}}}}}),
       "effects.prb.k_theta[1]", "-2.84"},
      {"FrictionNegative", with("/effects", {{"tendon_friction", {{"coefficient", -0.1}}}}),
       "effects.tendon_friction.coefficient", "-0.1"},
      {"FrictionNull", with("/effects", {{"tendon_friction", {{"coefficient", nullptr}}}}),
       "effects.tendon_friction.coefficient", "null"},
      {"FrictionPerTendonNegative",
       with("/effects", {{"tendon_friction", {{"coefficients", {0.1, -0.2, 0.1, 0.1}}}}}),
       "effects.tendon_friction.coefficients[1]", "-0.2"},
      {"FrictionPerTendonTooFew", with("/effects", {{"tendon_friction", {{"coefficients", {0.1, 0.2}}}}}),
       "effects.tendon_friction.coefficients", "2 values"},
      {"FrictionMotionUnknown", with("/effects", {{"tendon_friction", {{"motion", "sliding"}}}}),
       "effects.tendon_friction.motion", "\"sliding\""},
      {"ModelUnknown", with("/model", "cosserat"), "model", "\"cosserat\""},
      {"ModelNumber", with("/model", 3), "model", "3"},
      {"IntegratorUnknown", with("/solver", {{"integrator", "euler"}}), "solver.integrator", "\"euler\""},
      {"LinearSolverUnknown", with("/solver", {{"linear_solver", "lu"}}), "solver.linear_solver", "\"lu\""},
      {"MaxIterationsFloat", with("/solver", {{"max_iterations", 1.5}}), "solver.max_iterations", "1.5"},
      {"ContinuationNumber", with("/solver", {{"continuation", 1}}), "solver.continuation", "1"},
      {"StabilityWord", with("/solver", {{"stability", "always"}}), "solver.stability", "\"always\""},
      {"StabilityNumber", with("/solver", {{"stability", 1}}), "solver.stability", "1"},
      {"StabilityNull", with("/solver", {{"stability", nullptr}}), "solver.stability", "null"},
      // Unknown keys at every level, with a suggestion
      {"UnknownTopLevelKey", with("/modle", "vc"), "modle", "did you mean \"model\""},
      {"UnknownSegmentKey", with("/robot/segments/0/lenght", 0.05), "robot.segments[0].lenght",
       "did you mean \"length\""},
      {"UnknownBackboneKey", with("/robot/backbone/youngs_modulu", 2e11), "robot.backbone.youngs_modulu",
       "did you mean \"youngs_modulus\""},
      {"UnknownTendonKey", with("/robot/segments/1/tendons/1/z", 0.0), "robot.segments[1].tendons[1].z",
       "unknown key"},
      {"UnknownLoadsKey", with("/loads", {{"tip_forces", {0, 0, 0}}}), "loads.tip_forces",
       "did you mean \"tip_force\""},
      {"UnknownSolverKey", with("/solver", {{"max_iteration", 10}}), "solver.max_iteration",
       "did you mean \"max_iterations\""},
      {"UnknownPrbKey", with("/effects", {{"prb", {{"gama", {1, 1, 1, 1}}}}}), "effects.prb.gama",
       "did you mean \"gamma\""},
      {"UnknownStiffnessKey", with("/robot/backbone", {{"stiffness", {{"EI", 1}, {"GJ", 1}, {"EA", 1}, {"GA", 1}, {"EB", 1}}}}),
       "robot.backbone.stiffness.EB", "unknown key"},
      // Values the robot cannot have
      {"LengthNegative", with("/robot/segments/1/length", -0.05), "robot.segments[1].length", "-0.05"},
      {"LengthZero", with("/robot/segments/0/length", 0), "robot.segments[0].length", "0"},
      {"DisksZero", with("/robot/segments/0/disks", 0), "robot.segments[0].disks", "0"},
      {"DisksNegative", with("/robot/segments/1/disks", -3), "robot.segments[1].disks", "-3"},
      {"TendonOnAxis", with("/robot/segments/0/tendons/1", {{"x", 0}, {"y", 0}}), "robot.segments[0].tendons[1]",
       "(0, 0)"},
      // Tendon routing (segment 0 passes 10 disks after the base)
      {"RoutingTypeUnknown", with("/robot/segments/0/tendons/0/routing", {{"type", "spiral"}}),
       "robot.segments[0].tendons[0].routing.type", "\"spiral\""},
      {"RoutingTurnsMissing", with("/robot/segments/0/tendons/0/routing", {{"type", "helical"}}),
       "robot.segments[0].tendons[0].routing.turns", "is required"},
      {"RoutingTurnsOverflow",
       [] {
         std::string t = with("/robot/segments/0/tendons/0/routing", {{"type", "helical"}, {"turns", "@@RAW@@"}});
         return t.replace(t.find("\"@@RAW@@\""), 9, "1e999");
       }(),
       "robot.segments[0].tendons[0].routing.turns", "1e999"},
      {"RoutingTurnsWithPoints", with("/robot/segments/0/tendons/0/routing", {{"type", "points"}, {"turns", 1.0}}),
       "robot.segments[0].tendons[0].routing.turns", "applies to \"helical\" routing only"},
      {"RoutingPointsTooFew",
       with("/robot/segments/1/tendons/1/routing", {{"type", "points"}, {"positions", json::array({{0, 0.008}, {0, 0.008}})}}),
       "robot.segments[1].tendons[1].routing.positions", "2 positions"},
      {"RoutingPointNotPair",
       with("/robot/segments/0/tendons/0/routing", {{"type", "points"}, {"positions", json::array({json::array({0.0, 0.008, 0.0})})}}),
       "robot.segments[0].tendons[0].routing.positions[0]", "[0.0,0.008,0.0]"},
      {"RoutingPointOnAxis",
       edited([](json& j) {
         json p = json::array();
         for (int i = 0; i < 10; ++i) p.push_back(i == 4 ? json::array({0.0, 0.0}) : json::array({0.0, 0.008}));
         j["robot"]["segments"][0]["tendons"][0]["routing"] = {{"type", "points"}, {"positions", p}};
       }),
       "robot.segments[0].tendons[0].routing.positions[4]", "(0, 0)"},
      {"DiskMassNegative", with("/robot/segments/0/disk_mass", -0.001), "robot.segments[0].disk_mass",
       "-0.001"},
      {"YoungsModulusNegative", with("/robot/backbone/youngs_modulus", -1e9), "robot.backbone.youngs_modulus",
       "-1e+09"},
      {"InnerRadiusTooLarge", with("/robot/backbone/inner_radius", 0.0005), "robot.backbone.inner_radius",
       "0.0005"},
      {"PoissonAndShearModulus", with("/robot/backbone/shear_modulus", 8e10), "robot.backbone.shear_modulus",
       "80000000000"},
      {"StiffnessIncomplete", with("/robot/backbone", {{"stiffness", {{"EI", 1}, {"GJ", 1}, {"EA", 1}}}}),
       "robot.backbone.stiffness.GA", "is required"},
      {"StiffnessAndMaterial",
       with("/robot/backbone", {{"youngs_modulus", 2e11}, {"stiffness", {{"EI", 1}, {"GJ", 1}, {"EA", 1}, {"GA", 1}}}}),
       "robot.backbone.youngs_modulus", "200000000000"},
      // Actuation
      {"TensionNegative", with("/actuation/tensions/2", -1.0), "actuation.tensions[2]", "-1"},
      {"TensionsTooFew", with("/actuation/tensions", {1.0, 0.0, 0.0}), "actuation.tensions", "3 values"},
      {"TensionsAndDisplacements", with("/actuation/displacements", {0, 0, 0, 0}), "actuation.displacements",
       "[0,0,0,0]"},
      {"ConventionWithTensions", with("/actuation/displacement_convention", "at_base"),
       "actuation.displacement_convention", "\"at_base\""},
      {"ConventionUnknown",
       edited([](json& j) { j["actuation"] = {{"displacements", {0, 0, 0, 0}}, {"displacement_convention", "at_tip"}}; }),
       "actuation.displacement_convention", "\"at_tip\""},
      {"DisplacementsTooMany", edited([](json& j) { j["actuation"] = {{"displacements", {0, 0, 0, 0, 0}}}; }),
       "actuation.displacements", "5 values"},
      {"DisplacementOverflow",
       [] {
         std::string t = edited([](json& j) { j["actuation"] = {{"displacements", {0, "@@RAW@@", 0, 0}}}; });
         return t.replace(t.find("\"@@RAW@@\""), 9, "1e999");
       }(),
       "actuation.displacements[1]", "1e999"},
      {"DisplacementNullAlone", edited([](json& j) { j["actuation"] = {{"displacements", {0, nullptr, 0, 0}}}; }),
       "actuation.displacements[1]", "null"},
      {"TensionNullAlone", with("/actuation/tensions/1", nullptr), "actuation.tensions[1]", "null"},
      {"MixedTendonGivenTwice",
       edited([](json& j) {
         j["actuation"] = {{"tensions", {1, nullptr, 0, 0}}, {"displacements", {nullptr, 0.001, 0.002, nullptr}}};
       }),
       "actuation.displacements", "tendon 2 is given both"},
      {"MixedTendonGivenNowhere",
       edited([](json& j) {
         j["actuation"] = {{"tensions", {1, nullptr, 0, nullptr}}, {"displacements", {nullptr, 0.001, nullptr, nullptr}}};
       }),
       "actuation.displacements", "tendon 3 is given neither"},
      {"MixedListLengths",
       edited([](json& j) { j["actuation"] = {{"tensions", {1, nullptr, 0, 0}}, {"displacements", {nullptr, 0.001}}}; }),
       "actuation.displacements", "one entry per tendon"},
      {"MixedInputForCc",
       edited([](json& j) {
         j["model"] = "cc";
         j["actuation"] = {{"tensions", {1, nullptr, 0, 0}}, {"displacements", {nullptr, 0.001, nullptr, nullptr}}};
       }),
       "actuation", "kinematic"},
      // Elastic tendons
      {"TendonStiffnessZero", with("/robot/segments/0/tendons/1/stiffness", 0), "robot.segments[0].tendons[1].stiffness",
       "0"},
      {"TendonStiffnessNegative", with("/robot/segments/1/tendons/0/stiffness", -250.0),
       "robot.segments[1].tendons[0].stiffness", "-2.5e+02"},
      {"TendonStiffnessOverflow", with_raw("/robot/segments/1/tendons/1/stiffness", "1e999"),
       "robot.segments[1].tendons[1].stiffness", "1e999"},
      {"TendonStiffnessString", with("/robot/segments/0/tendons/0/stiffness", "stiff"),
       "robot.segments[0].tendons[0].stiffness", "\"stiff\""},
      {"ElasticTendonForCc",
       edited([](json& j) {
         j["model"] = "cc";
         j["robot"]["segments"][1]["tendons"][0]["stiffness"] = 300.0;
         j["actuation"] = {{"displacements", {0.001, 0, 0, 0}}};
       }),
       "robot.segments[1].tendons[0].stiffness", "3e+02"},
      // Solver values
      {"Rk4StepsZero", with("/solver", {{"rk4_steps", 0}}), "solver.rk4_steps", "0"},
      {"FunctionToleranceNegative", with("/solver", {{"function_tolerance", -1e-10}}), "solver.function_tolerance",
       "-1e-10"},
  };
}

}  // namespace bad_scenes
