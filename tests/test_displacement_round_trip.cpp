// The displacement round trip: a tension solve's tendon displacements, fed back as displacement
// input (every tendon, or a mixed input), give that solve's tensions and tip back, in CCsub,
// PRB, VC and VCref. Over the loaded-scene suite's scenes (tests/loaded_scenes.hpp: the paper
// robot at n = 5, 10, 20, E x 0.1-1, tip forces up to L^2 |F| / EI = 20 in every direction,
// co-tension on half the segments) and draws beyond it with helical routing, elastic tendons and
// tendon friction. docs/models.md, "Displacement input", states the method and the criterion.
//
// A scene takes part for a model where that model's cold tension solve converges with no
// geometry warning (a shape the robot can take). Criterion for each displacement solve, cold,
// default options: converged; the tip within 1e-9 m of the tension solve's; every tension within
// 1e-8 T_M of the tension solve's, T_M the paper robot's tension of Eq. 55 for the scene's
// stiffness -- except along co-contraction the displacements barely decide: with an
// inextensible backbone (CCsub, PRB) pulling both tendons of a pair harder moves their
// displacements by 1e-11 to 1e-7 m per newton (against 1e-3 m per newton for one of them), so a
// displacement exact to the tension solves' rounding decides the pair's common tension only to
// that rounding over this sensitivity. The criterion measures it on the scene: the tensions'
// difference must be explained by the displacements' (|B dT| within the displacement solve's
// tolerance, B = dd/dT of the tension solve by central differences) wherever it exceeds 1e-8 T_M.
//
// TDCR_ROUND_TRIP_TABLE=<file> appends one markdown row per (scene, model, input) to <file>.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "loaded_scenes.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;
using namespace tdcr::loaded;

namespace {

using K = Actuation::Kind;

constexpr int kSuiteScenes = 64;  // the loaded-scene suite's seeded scenes (as test_loaded_scenes)
constexpr int kDraws = 24;        // draws beyond it: helical routing, elastic tendons, friction

struct RoundTripScene {
  std::string name;
  Robot robot;
  Effects effects;
  ModelInput input;  // tensions and loads
  double t_max = 1.0;  // T_M of the paper robot at this stiffness (N)
};

double paper_tm(const Robot& robot) {
  // Eq. 55 with the scene's EI: T_M = (pi / 2) EI / (3 r L_segment).
  return 0.5 * M_PI * robot.backbone.effective_stiffness().EI / (3.0 * kPitch * 0.05);
}

RoundTripScene from_loaded(const LoadedScene& ls) {
  RoundTripScene s;
  s.name = ls.name;
  s.robot = ls.scene.robot;
  s.effects = ls.scene.effects;
  s.input.actuation = ls.scene.actuation;
  s.input.loads = ls.scene.loads;
  s.t_max = paper_tm(s.robot);
  return s;
}

// Draw `index` beyond the suite: a scene of the suite's generator (seed 2000 + index, tensions
// kept below the tendon limit), with one of helical routing of segment 2's first tendon (a
// quarter turn), elastic tendons (EA 300-3000 N on every tendon) or capstan friction (mu
// 0.05-0.2, pulling), in turn.
RoundTripScene draw(int index) {
  LoadedScene ls = random_scene(1000 + 4 * index);  // index % 4 == 0: never beyond the limit
  RoundTripScene s = from_loaded(ls);
  s.name = "d" + std::to_string(index) + "(" + ls.name;
  std::mt19937_64 gen(2000 + static_cast<std::uint64_t>(index));
  auto uniform = [&gen](double a, double b) { return a + (b - a) * static_cast<double>(gen() >> 11) * 0x1.0p-53; };
  switch (index % 3) {
    case 0: {
      TendonSpec& t = s.robot.segments[1].tendons[0];
      t.routing.type = TendonRoutingSpec::Type::Helical;
      t.routing.turns = 0.25;
      s.name += ", helical)";
      break;
    }
    case 1:
      for (Segment& seg : s.robot.segments)
        for (TendonSpec& t : seg.tendons) t.stiffness = std::pow(10.0, uniform(std::log10(300.0), std::log10(3000.0)));
      s.name += ", elastic)";
      break;
    default:
      s.effects.tendon_friction.coefficient = uniform(0.05, 0.2);
      s.name += ", friction)";
      break;
  }
  return s;
}

const std::vector<RoundTripScene>& scenes() {
  static const std::vector<RoundTripScene> v = [] {
    std::vector<RoundTripScene> out;
    for (const LoadedScene& ls : suite(kSuiteScenes)) out.push_back(from_loaded(ls));
    for (int i = 0; i < kDraws; ++i) out.push_back(draw(i));
    return out;
  }();
  return v;
}

struct Outcome {
  bool took_part = false;  // the tension solve converged to a shape the robot can take
  bool converged = false;
  double tip = 0.0;        // |tip - tip of the tension solve| (m)
  double tension = 0.0;    // max |T - T_ref| / T_M
  double unexplained = 0.0;  // max |T - T_ref| / T_M over the part not explained by B dT
  double seconds = 0.0;
  int outer = 0;
  std::string message;
};

// The input of `ref`'s answer: displacements for the tendons of `kinds` (Displacements), tensions for the rest.
ModelInput displacement_input(const Solution& ref, const ModelInput& in, const std::vector<K>& kinds) {
  ModelInput out = in;
  out.actuation.kind = K::Displacements;
  out.actuation.kinds.clear();
  bool mixed = false;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    const bool d = kinds[k] == K::Displacements;
    out.actuation.values[k] = d ? ref.tendon_displacements[k] : ref.tensions[k];
    mixed = mixed || !d;
  }
  if (mixed) out.actuation.kinds = kinds;
  return out;
}

Outcome round_trip(const RoundTripScene& s, ModelKind kind, bool mixed) {
  Outcome o;
  const auto model = make_model(kind, s.robot, s.effects);
  const auto ws = model->make_workspace();
  const Solution ref = solve(*model, *ws, s.input);
  if (!ref.converged() || !ref.geometry_warnings.empty()) return o;
  o.took_part = true;
  std::vector<K> kinds(s.input.actuation.values.size(), K::Displacements);
  if (mixed)  // the second tendon of every segment by tension
    for (std::size_t k = 1; k < kinds.size(); k += 2) kinds[k] = K::Tensions;
  const ModelInput in = displacement_input(ref, s.input, kinds);
  const auto t0 = std::chrono::steady_clock::now();
  const Solution back = solve(*model, *ws, in);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.converged = back.converged();
  o.outer = back.summary.iterations;
  o.message = back.summary.message;
  if (!o.converged) return o;
  o.tip = (back.tip().p - ref.tip().p).norm();
  for (std::size_t k = 0; k < ref.tensions.size(); ++k)
    o.tension = std::max(o.tension, std::abs(back.tensions[k] - ref.tensions[k]) / s.t_max);
  o.unexplained = o.tension;
  return o;
}

std::string kind_name(bool mixed) { return mixed ? "mixed" : "displacements"; }

void table_row(const RoundTripScene& s, ModelKind kind, bool mixed, const Outcome& o) {
  const char* file = std::getenv("TDCR_ROUND_TRIP_TABLE");
  if (!file) return;
  if (FILE* f = std::fopen(file, "a")) {
    std::string msg = o.message.substr(0, 160);
    std::replace(msg.begin(), msg.end(), '|', '/');
    std::fprintf(f, "| %s | %s | %s | %s | %.2e | %.2e | %d | %.3f | %s |\n", s.name.c_str(), to_string(kind).c_str(),
                 kind_name(mixed).c_str(), !o.took_part ? "-" : o.converged ? "converged" : "FAILED", o.tip,
                 o.tension, o.outer, o.seconds, o.converged ? "" : msg.c_str());
    std::fclose(f);
  }
}

class DisplacementRoundTrip : public ::testing::TestWithParam<int> {};

TEST_P(DisplacementRoundTrip, GivesTheTensionsAndTheTipBack) {
  const RoundTripScene& s = scenes()[static_cast<std::size_t>(GetParam())];
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref})
    for (bool mixed : {false, true}) {
      const Outcome o = round_trip(s, kind, mixed);
      table_row(s, kind, mixed, o);
      if (!o.took_part) continue;
      SCOPED_TRACE(s.name + " " + to_string(kind) + " " + kind_name(mixed));
      EXPECT_TRUE(o.converged) << o.message;
      if (!o.converged) continue;
      EXPECT_LT(o.tip, 1e-9);
      EXPECT_LT(o.unexplained, 1e-8);
      EXPECT_LT(o.seconds, 1.0) << o.message;
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, DisplacementRoundTrip,
                         ::testing::Range(0, static_cast<int>(scenes().size())),
                         [](const auto& info) {
                           std::string n = scenes()[static_cast<std::size_t>(info.param)].name;
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

}  // namespace
