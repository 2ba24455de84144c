// Calibration data files: CSV in the sweep CSV's column names (calibration.hpp). Every bad row or
// column is an InputError naming the line and the column; no row is skipped.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "tdcr/core/error.hpp"
#include "tdcr/models/calibration.hpp"

namespace tdcr {

namespace {

// One column of the header and what it feeds.
struct Column {
  enum class Role { Ignored, Status, Input, Tip, Rotation, Point, TipStd, RotationStd, PointStd };
  std::string name;
  Role role = Role::Ignored;
  int component = 0;  // x, y, z or the input's index
  int group = 0;      // Input: 0 tension/displacement, 1 tip force, 2 tip moment, 3 gravity; Point: point number
};

// Splits one CSV line (RFC 4180 quoting: "a, ""b""" is one field).
std::vector<std::string> split_csv(const std::string& line, bool* bad_quote) {
  std::vector<std::string> out(1);
  bool quoted = false;
  *bad_quote = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') out.back() += '"', ++i;
      else if (c == '"') quoted = false;
      else out.back() += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  *bad_quote = quoted;
  return out;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

const std::vector<std::string> kIgnored = {"sample", "model", "reason", "iterations", "solve_time_s"};

struct Parser {
  const Scene& scene;
  std::string source;
  std::vector<Column> columns;
  std::vector<double> point_s;  // arc length of each measured point
  bool has_tip = false, has_rot = false;

  std::string where(int line, const std::string& column) const {
    return source + " line " + std::to_string(line) + ", column " + column;
  }

  void header(const std::vector<std::string>& names, int line) {
    static const std::regex input_re(R"(^(actuation|loads)\.(tensions|displacements|tip_force|tip_moment|gravity)\[(\d+)\]$)");
    static const std::regex meas_re(R"(^(tip|rot)_([xyz])(_std)?$)");
    static const std::regex point_re(R"(^point_([xyz])@([^_]+)(_std)?$)");
    std::map<std::string, int> seen;
    const double length = scene.robot.total_length();
    for (const std::string& raw : names) {
      Column c;
      c.name = trim(raw);
      const std::string at = where(line, c.name.empty() ? "(empty)" : c.name);
      if (c.name.empty()) throw InputError(at, "", "a column without a name");
      if (seen[c.name]++) throw InputError(at, c.name, "column given twice");
      std::smatch m;
      if (std::find(kIgnored.begin(), kIgnored.end(), c.name) != kIgnored.end()) {
        c.role = Column::Role::Ignored;
      } else if (c.name == "status") {
        c.role = Column::Role::Status;
      } else if (std::regex_match(c.name, m, input_re)) {
        c.role = Column::Role::Input;
        const std::string name = m[2];
        const long k = std::strtol(m[3].str().c_str(), nullptr, 10);
        if (name == "tensions" || name == "displacements") {
          if (k >= static_cast<long>(scene.actuation.values.size()))
            throw InputError(at, c.name, "does not exist: the scene's robot has " +
                                             std::to_string(scene.actuation.values.size()) + " tendons");
          const bool tension = name == "tensions";
          if ((scene.actuation.kind_of(static_cast<std::size_t>(k)) == Actuation::Kind::Tensions) != tension)
            throw InputError(at, c.name, "the scene's actuation gives tendon " + std::to_string(k) + " by " +
                                             (tension ? "displacement" : "tension"));
          c.group = 0;
        } else {
          if (k > 2) throw InputError(at, c.name, "does not exist: a load vector has components [0], [1], [2]");
          c.group = name == "tip_force" ? 1 : name == "tip_moment" ? 2 : 3;
        }
        c.component = static_cast<int>(k);
      } else if (std::regex_match(c.name, m, meas_re)) {
        const bool tip = m[1] == "tip", std_col = m[3].matched;
        c.role = tip ? (std_col ? Column::Role::TipStd : Column::Role::Tip)
                     : (std_col ? Column::Role::RotationStd : Column::Role::Rotation);
        c.component = m[2].str()[0] - 'x';
        (tip ? has_tip : has_rot) |= !std_col;
      } else if (std::regex_match(c.name, m, point_re)) {
        char* end = nullptr;
        const std::string st = m[2];
        const double s = std::strtod(st.c_str(), &end);
        if (*end != '\0' || !std::isfinite(s) || s <= 0.0 || s > length * (1.0 + 1e-12))
          throw InputError(at, st, "a point's arc length (after @) must be a number in (0, " + format_value(length) + "] m");
        c.role = m[3].matched ? Column::Role::PointStd : Column::Role::Point;
        c.component = m[1].str()[0] - 'x';
        auto it = std::find(point_s.begin(), point_s.end(), s);
        if (it == point_s.end()) point_s.push_back(s), it = point_s.end() - 1;
        c.group = static_cast<int>(it - point_s.begin());
      } else if (c.name.rfind("robot.", 0) == 0 || c.name.rfind("effects.", 0) == 0 || c.name.rfind("solver.", 0) == 0) {
        throw InputError(at, c.name,
                         "calibration data are measurements of one robot: a column may give its inputs "
                         "(actuation., loads.), not robot, effects or solver fields (sweep one robot)");
      } else {
        throw InputError(at, c.name,
                         "unknown column; known: actuation.tensions[k], actuation.displacements[k], loads.tip_force[i], "
                         "loads.tip_moment[i], loads.gravity[i], tip_x/y/z, rot_x/y/z, point_x/y/z@S (S: arc length "
                         "in m), each measurement with _std, and a sweep's sample, model, status, reason, iterations, "
                         "solve_time_s");
      }
      columns.push_back(c);
    }
    // Each measurement group complete (x, y, z), and a std column only beside its measurement.
    auto count = [&](Column::Role role, int group) {
      int n = 0;
      for (const Column& c : columns) n += c.role == role && (role != Column::Role::Point && role != Column::Role::PointStd ? true : c.group == group);
      return n;
    };
    auto require_complete = [&](Column::Role role, int group, const std::string& what, bool needed) {
      const int n = count(role, group);
      if (n != 0 && n != 3) throw InputError(where(line, what), "", "needs all three columns x, y, z (got " + std::to_string(n) + ")");
      if (n != 0 && !needed) throw InputError(where(line, what + "_std"), "", "a standard deviation without its measurement columns");
    };
    require_complete(Column::Role::Tip, 0, "tip", true);
    require_complete(Column::Role::Rotation, 0, "rot", true);
    require_complete(Column::Role::TipStd, 0, "tip_std", has_tip);
    require_complete(Column::Role::RotationStd, 0, "rot_std", has_rot);
    for (std::size_t g = 0; g < point_s.size(); ++g) {
      const std::string name = "point@" + format_value(point_s[g]);
      require_complete(Column::Role::Point, static_cast<int>(g), name, true);
      require_complete(Column::Role::PointStd, static_cast<int>(g), name + "_std",
                       count(Column::Role::Point, static_cast<int>(g)) == 3);
    }
    if (!has_tip && !has_rot && point_s.empty())
      throw InputError(where(line, "(header)"), "", "no measurement column: give tip_x, tip_y, tip_z (and/or rot_x/y/z, point_x/y/z@S)");
  }

  double number(const std::string& text, int line, const Column& c) const {
    const std::string t = trim(text);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || *end != '\0') throw InputError(where(line, c.name), t.empty() ? "(empty)" : t, "not a number");
    if (!std::isfinite(v)) throw InputError(where(line, c.name), t, "must be a finite number");
    return v;
  }

  CalibrationSample row(const std::vector<std::string>& fields, int line) const {
    CalibrationSample s;
    s.line = line;
    s.input = scene.input();
    Vec3 tip = Vec3::Zero(), rot = Vec3::Zero(), tip_std, rot_std;
    tip_std = rot_std = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    std::vector<MeasuredPoint> pts(point_s.size());
    for (std::size_t g = 0; g < pts.size(); ++g) pts[g].s = point_s[g];
    // Per measurement group: how many of its fields are empty (all or none may be).
    std::map<std::string, std::pair<int, std::string>> empties;
    auto group_key = [](const Column& c) {
      switch (c.role) {
        case Column::Role::Tip: return std::string("tip");
        case Column::Role::Rotation: return std::string("rot");
        case Column::Role::Point: return "point" + std::to_string(c.group);
        default: return std::string();
      }
    };
    for (std::size_t i = 0; i < columns.size(); ++i) {
      const Column& c = columns[i];
      const std::string text = trim(fields[i]);
      switch (c.role) {
        case Column::Role::Ignored: break;
        case Column::Role::Status:
          if (text != "converged")
            throw InputError(where(line, c.name), text.empty() ? "(empty)" : text,
                             "a measurement must come from a converged solve (status converged); remove or fix the row");
          break;
        case Column::Role::Input: {
          const double v = number(text, line, c);
          if (c.group == 0) {
            if (s.input.actuation.kind_of(static_cast<std::size_t>(c.component)) == Actuation::Kind::Tensions && v < 0.0)
              throw InputError(where(line, c.name), format_value(v), "a tension must not be negative (tendons can only pull)");
            s.input.actuation.values[static_cast<std::size_t>(c.component)] = v;
          } else {
            Vec3& l = c.group == 1 ? s.input.loads.tip_force : c.group == 2 ? s.input.loads.tip_moment : s.input.loads.gravity;
            l[c.component] = v;
          }
          break;
        }
        case Column::Role::Tip:
        case Column::Role::Rotation:
        case Column::Role::Point: {
          auto& e = empties[group_key(c)];
          if (text.empty()) {
            ++e.first;
            e.second = c.name;
            break;
          }
          const double v = number(text, line, c);
          if (c.role == Column::Role::Tip) tip[c.component] = v;
          else if (c.role == Column::Role::Rotation) rot[c.component] = v;
          else pts[static_cast<std::size_t>(c.group)].position[c.component] = v;
          break;
        }
        case Column::Role::TipStd:
        case Column::Role::RotationStd:
        case Column::Role::PointStd: {
          if (text.empty()) break;  // the default standard deviation
          const double v = number(text, line, c);
          if (!(v > 0.0)) throw InputError(where(line, c.name), format_value(v), "a standard deviation must be positive");
          if (c.role == Column::Role::TipStd) tip_std[c.component] = v;
          else if (c.role == Column::Role::RotationStd) rot_std[c.component] = v;
          else pts[static_cast<std::size_t>(c.group)].std[c.component] = v;
          break;
        }
      }
    }
    for (const auto& [key, e] : empties)
      if (e.first != 0 && e.first != 3)
        throw InputError(where(line, e.second), "(empty)", "a measurement is given by all of x, y, z or by none");
    auto given = [&](const std::string& key) { return empties.count(key) && empties.at(key).first == 0; };
    if (has_tip && given("tip")) s.tip = tip, s.tip_std = tip_std;
    if (has_rot && given("rot")) s.rotation = rot, s.rotation_std = rot_std;
    for (std::size_t g = 0; g < pts.size(); ++g)
      if (given("point" + std::to_string(g))) s.points.push_back(pts[g]);
    if (!s.tip && !s.rotation && s.points.empty())
      throw InputError(where(line, has_tip ? "tip_x" : has_rot ? "rot_x" : "point_x"), "(empty)", "the row measures nothing");
    return s;
  }
};

}  // namespace

CalibrationData parse_calibration_data(const std::string& csv_text, const Scene& scene, const std::string& source) {
  scene.validate();
  Parser p{scene, source, {}, {}};
  CalibrationData data;
  data.source = source;
  std::istringstream in(csv_text);
  std::string line;
  int number = 0;
  bool have_header = false;
  // A sweep of several models writes one row per model and sample: measurements of one robot are
  // the rows of one model, so a second model in the `model` column is an error, not more data.
  std::size_t model_column = std::string::npos;
  std::string first_model;
  int first_model_line = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty() || line[0] == '#') continue;
    bool bad_quote = false;
    const std::vector<std::string> fields = split_csv(line, &bad_quote);
    if (bad_quote) throw InputError(source + " line " + std::to_string(number), "", "a quoted field is not closed");
    if (!have_header) {
      p.header(fields, number);
      have_header = true;
      for (std::size_t i = 0; i < p.columns.size(); ++i)
        if (p.columns[i].name == "model") model_column = i;
      continue;
    }
    if (fields.size() != p.columns.size())
      throw InputError(source + " line " + std::to_string(number), std::to_string(fields.size()) + " fields",
                       "expected " + std::to_string(p.columns.size()) + " fields, one per header column");
    if (model_column != std::string::npos) {
      const std::string m = trim(fields[model_column]);
      if (first_model_line == 0) {
        first_model = m, first_model_line = number;
      } else if (m != first_model) {
        throw InputError(p.where(number, "model"), m,
                         "the data mix models (line " + std::to_string(first_model_line) + " is " + first_model +
                             "): keep the rows of one model (a sweep of several models writes a row for each)");
      }
    }
    CalibrationSample s = p.row(fields, number);
    try {
      s.input.validate(scene.robot);
    } catch (const InputError& e) {
      throw InputError(p.where(number, e.field()), e.value(), e.what());
    }
    data.has_std = data.has_std || s.tip_std.array().isFinite().any() || s.rotation_std.array().isFinite().any();
    for (const MeasuredPoint& m : s.points) data.has_std = data.has_std || m.std.array().isFinite().any();
    data.samples.push_back(std::move(s));
  }
  if (!have_header) throw InputError(source, "", "no header line: the data file is empty");
  if (data.samples.empty()) throw InputError(source, "", "no data rows after the header");
  return data;
}

CalibrationData read_calibration_data(const std::string& path, const Scene& scene) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot read the data file (does it exist?)");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_calibration_data(ss.str(), scene, path);
}

}  // namespace tdcr
