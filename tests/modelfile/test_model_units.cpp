// SPDX-License-Identifier: BSD-3-Clause
// units: of a model file (modelfile/reader.cpp, read_units): each coordinate's and output
// expression's unit for the plots' labels, the multibody defaults (m, rad, 1), the errors at
// file:line:column, and summary.json's `units` (io/json_summary.cpp).
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <ukdyn/io/provenance.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kSlider = R"(coordinates: [s, phi]
kinetic_energy: 0.5*s_dot^2 + 0.5*phi_dot^2
output: {expressions: {turns: phi/(2*pi), e: 0.5*s_dot^2}}
)";

// the ModelError of parsing `text`: its line, column and message
struct Failure {
  int line = 0, column = 0;
  std::string what;
};
Failure failure_of(const std::string& text) {
  try {
    parse_model(text, "units.yaml");
  } catch (const ModelError& e) {
    return {e.line(), e.column(), e.what()};
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return {};
}

TEST(ModelUnits, NoneGivenIsNoneKnown) {
  const Model m = parse_model(kSlider);
  EXPECT_EQ(m.coordinate_units, (std::vector<std::string>{"", ""}));
  EXPECT_EQ(m.output_units, (std::vector<std::string>{"", ""}));
}

TEST(ModelUnits, TheFileGivesCoordinatesAndOutputsTheirs) {
  const Model m = parse_model(kSlider + "units: {phi: rad, s: m, e: J}\n");
  EXPECT_EQ(m.coordinate_units, (std::vector<std::string>{"m", "rad"}));
  EXPECT_EQ(m.output_units, (std::vector<std::string>{"", "J"}));
}

TEST(ModelUnits, BodiesHaveMetresRadiansAndUnitlessQuaternions) {
  const std::string bodies = R"(
bodies:
  - {name: crank, type: planar, mass: 1, inertia: 0.1}
  - {name: rod, type: planar, mass: 1, inertia: 0.1, position: [1, 0]}
)";
  const Model planar = parse_model("units: {crank_theta: rad}" + bodies);
  EXPECT_EQ(planar.coordinate_units, (std::vector<std::string>{"m", "m", "rad", "m", "m", "rad"}));
  // an angle's values are radians: a label 'deg' would be wrong (u21 07), it is refused there
  try {
    parse_model("units: {crank_theta: deg}" + bodies);
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(e.column(), 22);
    EXPECT_NE(e.message().find("units: 'crank_theta' is an angle, in rad; it cannot be given "
                               "'deg' (a unit labels the values, it converts none)"),
              std::string::npos)
        << e.message();
    EXPECT_NE(e.hint().find("crank_theta: 90*pi/180"), std::string::npos) << e.hint();
  }
  // (a body's position takes the length unit: units: {length: mm}, not one coordinate's)
  const Model spatial = parse_model(R"(units: {length: mm}
bodies:
  - {name: top, type: rigid, mass: 1, inertia: [1, 1, 1]}
  - {name: bead, type: particle, mass: 1, position: [1, 0, 0]}
)");
  EXPECT_EQ(spatial.coordinate_units,
            (std::vector<std::string>{"mm", "mm", "mm", "1", "1", "1", "1", "mm", "mm", "mm"}));
}

// A robot's joints (u15 05): a revolute or continuous joint's angle in rad, a prismatic joint's
// displacement in the length unit, a floating base's x, y, z in the length unit and its
// quaternion's u0..u3 without unit; units: still relabels one (the joint's kind is the URDF's)
TEST(ModelUnits, RobotJointsHaveTheirKindsUnits) {
  const std::string data = UKDYN_TEST_DATA_DIR, robots = UKDYN_EXAMPLES_DIR "/../robots";
  // tests/data/rolling_wheel.urdf: prismatic x, prismatic z, continuous pitch
  const Model wheel = parse_model(
      "units: {length: mm, mass: g, time: ms}\n"
      "robot: {urdf: rolling_wheel.urdf}\n",
      data + "/wheel.yaml");
  const auto unit_of = [](const Model& m, const std::string& name) {
    const auto& names = m.system.coordinate_names();
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return m.coordinate_units[i];
    return std::string("(no coordinate ") + name + ")";
  };
  EXPECT_EQ(unit_of(wheel, "x"), "mm");
  EXPECT_EQ(unit_of(wheel, "z"), "mm");
  EXPECT_EQ(unit_of(wheel, "pitch"), "rad");
  // a joint's angle is in rad: 'deg' is refused (u21 07), 'rad' taken
  const Model relabelled =
      parse_model("units: {pitch: rad}\nrobot: {urdf: rolling_wheel.urdf}\n", data + "/wheel.yaml");
  EXPECT_EQ(unit_of(relabelled, "x"), "m");
  EXPECT_EQ(unit_of(relabelled, "pitch"), "rad");
  try {
    parse_model("units: {pitch: deg}\nrobot: {urdf: rolling_wheel.urdf}\n", data + "/wheel.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("units: 'pitch' is an angle, in rad; it cannot be given 'deg'"),
              std::string::npos)
        << e.message();
  }
  try {
    parse_model("units: {x: cm}\nrobot: {urdf: rolling_wheel.urdf}\n", data + "/wheel.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("units: 'x' is a joint's coordinate, in m"), std::string::npos)
        << e.message();
  }
  // examples/robots/humanoid.urdf: a floating pelvis and 26 revolute joints, no unit left ''
  const Model humanoid = parse_model("robot: {urdf: humanoid.urdf}\n", robots + "/h.yaml");
  for (const char* c : {"pelvis.x", "pelvis.y", "pelvis.z"}) EXPECT_EQ(unit_of(humanoid, c), "m");
  for (const char* c : {"pelvis.u0", "pelvis.u1", "pelvis.u2", "pelvis.u3"})
    EXPECT_EQ(unit_of(humanoid, c), "1");
  int rad = 0;
  for (const std::string& u : humanoid.coordinate_units) {
    EXPECT_FALSE(u.empty());
    rad += u == "rad";
  }
  EXPECT_EQ(rad, 26);
}

TEST(ModelUnits, ErrorsNameTheEntryAndWhereItIs) {
  Failure f = failure_of(kSlider + "units: {q: m}\n");
  EXPECT_EQ(f.line, 4);
  EXPECT_EQ(f.column, 9);
  EXPECT_NE(f.what.find("units: 'q' is neither a coordinate nor an output expression (hint: the "
                        "coordinates are s, phi, the output expressions turns, e)"),
            std::string::npos)
      << f.what;
  f = failure_of(kSlider + "units: {s: [m]}\n");
  EXPECT_EQ(f.line, 4);
  EXPECT_EQ(f.column, 12);
  EXPECT_NE(f.what.find("the unit of 's' must be a short text (at most 32 characters)"),
            std::string::npos)
      << f.what;
  // a control character is said to be one, not a length (u15 10)
  f = failure_of(kSlider + "units: {s: \"\\x1b[31m\"}\n");
  EXPECT_EQ(f.line, 4);
  EXPECT_NE(f.what.find("the unit of 's' contains a control character"), std::string::npos)
      << f.what;
  f = failure_of(kSlider + "units: {s: " + std::string(33, 'm') + "}\n");
  EXPECT_NE(f.what.find("the unit of 's' must be a short text"), std::string::npos) << f.what;
  // an empty unit is said to be empty, not too long (review 2026-11-27)
  f = failure_of(kSlider + "units: {s: ''}\n");
  EXPECT_EQ(f.line, 4);
  EXPECT_EQ(f.column, 12);
  EXPECT_NE(f.what.find("the unit of 's' is empty (hint: give its unit (units: {x: m, theta: "
                        "rad}; 1 for a number without a unit), or leave 's' out of units:)"),
            std::string::npos)
      << f.what;
  f = failure_of(kSlider + "units: {s: }\n");
  EXPECT_NE(f.what.find("the unit of 's' is empty"), std::string::npos) << f.what;
  f = failure_of(kSlider + "units: [m, rad]\n");
  EXPECT_EQ(f.line, 4);
  EXPECT_EQ(f.column, 8);
  EXPECT_NE(f.what.find("units must map coordinates (or output expressions) to their units"),
            std::string::npos)
      << f.what;
  f = failure_of(kSlider + "unit: {s: m}\n");  // a misspelt key is never ignored
  EXPECT_NE(f.what.find("unknown key 'unit'"), std::string::npos) << f.what;
}

TEST(ModelUnits, SummaryWritesTheUnitsByColumnName) {
  Model m = parse_model(kSlider + "units: {s: m, e: J}\n");
  m.options.t_end = 0.01;
  const ModelRun run = run_model(m, m.options);
  RunProvenance p;
  p.model_name = "slider";
  p.units = {{"s", "m"}, {"phi", ""}, {"e", "J"}};
  const auto j = nlohmann::json::parse(summary_json(run.trajectory, m.options, &p));
  EXPECT_EQ(j.at("units"), nlohmann::json({{"s", "m"}, {"phi", ""}, {"e", "J"}}));
  // without units (or without provenance): no key
  p.units.clear();
  EXPECT_FALSE(
      nlohmann::json::parse(summary_json(run.trajectory, m.options, &p)).contains("units"));
  EXPECT_FALSE(nlohmann::json::parse(summary_json(run.trajectory, m.options)).contains("units"));
}

// units: {length: mm, mass: g, time: ms} (the repro's ball): the bodies' coordinates in mm, and
// every derived label from the base units — never N, J, W outside SI (4.41e3 g·mm²/ms² is
// 4.41 J, not 4.41e3 J); a unit changes no number
const std::string kBallMm = R"(name: ball mm g ms
parameters: {m: 500, r: 100, g: 9.81e-3, h0: 1000, e: 0.7}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [0, 0, h0]}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: r, restitution: e}
)";

// the labels derived from u: velocity, acceleration, force, energy, torque, power, and the rates
// of an angle and of a number
std::vector<std::string> derived_labels(const UnitSystem& u) {
  return {u.velocity(), u.acceleration(), u.force(),     u.energy(),
          u.torque(),   u.power(),        u.rate("rad"), u.rate("1", 2)};
}

TEST(ModelUnits, BaseUnitsLabelEveryDerivedQuantity) {
  const Model si = parse_model(kBallMm);
  EXPECT_TRUE(si.unit_system.is_si());
  EXPECT_EQ(si.unit_system.time, "s");
  EXPECT_EQ(derived_labels(si.unit_system),
            (std::vector<std::string>{"m/s", "m/s²", "N", "J", "N·m", "W", "rad/s", "1/s²"}));
  EXPECT_EQ(si.coordinate_units.front(), "m");  // ball.x

  const Model mm = parse_model(kBallMm + "units: {length: mm, mass: g, time: ms, ball.z: mm}\n");
  EXPECT_FALSE(mm.unit_system.is_si());
  EXPECT_EQ(mm.unit_system.length, "mm");
  EXPECT_EQ(mm.unit_system.mass, "g");
  EXPECT_EQ(mm.unit_system.time, "ms");
  EXPECT_EQ(derived_labels(mm.unit_system),
            (std::vector<std::string>{"mm/ms", "mm/ms²", "g·mm/ms²", "g·mm²/ms²", "g·mm²/ms²",
                                      "g·mm²/ms³", "rad/ms", "1/ms²"}));
  // the body's centre in mm, its rotation's components without unit
  EXPECT_EQ(mm.coordinate_units, (std::vector<std::string>{"mm", "mm", "mm", "1", "1", "1", "1"}));
  // one base unit given: the others SI, and no N or J (kg·mm/s² is 1e-3 N)
  const Model km = parse_model(kBallMm + "units: {length: mm}\n");
  EXPECT_EQ(km.unit_system.force(), "kg·mm/s²");
  EXPECT_EQ(km.unit_system.energy(), "kg·mm²/s²");
  EXPECT_EQ(km.unit_system.velocity(), "mm/s");
  // no number changes: the same parameters and initial state, bit for bit
  EXPECT_EQ(mm.q0, si.q0);
  EXPECT_EQ(mm.parameters, si.parameters);
}

// the error of parsing `text`: at line:column, its text holding `message`
void expect_error(const std::string& text, int line, int column, const std::string& message) {
  const Failure f = failure_of(text);
  EXPECT_EQ(f.line, line) << f.what;
  EXPECT_EQ(f.column, column) << f.what;
  EXPECT_NE(f.what.find(message), std::string::npos) << f.what;
}

TEST(ModelUnits, UnknownBaseUnitsAreRefusedWithTheAcceptedList) {
  expect_error(kSlider + "units: {time: sec}\n", 4, 15,
               "units: unknown unit of time 'sec' (accepted: s, ms, us, min, h) (hint: units: "
               "{time: ms}");
  expect_error(kSlider + "units: {s: m, length: inch}\n", 4, 23,
               "unknown unit of length 'inch' (accepted: m, mm, cm, km, um, nm)");
  expect_error(kSlider + "units: {mass: [g]}\n", 4, 15,
               "unknown unit of mass '' (accepted: kg, g, mg, t)");
  // a coordinate named like a base unit: the key is the base unit's, said so
  expect_error("coordinates: [time]\nkinetic_energy: time_dot^2\nunits: {time: s}\n", 3, 15,
               "units: 'time' is the unit of time of the model, but a coordinate is also named "
               "'time' (hint: rename the coordinate");
}

// One body's coordinates are in one length unit: units: may not give one of them another
// (repro u14/06 c: {length: mm, time: ms, ball_x: m} labelled ball.x m and ball.y mm); the same
// unit again is accepted.
TEST(ModelUnits, ABodysCoordinateKeepsTheModelsLengthUnit) {
  const std::string body = R"(bodies:
  - {name: ball, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}
)";
  const Failure f = failure_of("units: {length: mm, time: ms, ball_x: m}\n" + body);
  EXPECT_EQ(f.line, 1);
  EXPECT_EQ(f.column, 39);
  EXPECT_NE(f.what.find("units: 'ball_x' is a body's coordinate, in mm (the model's length "
                        "unit); it cannot be given 'm'"),
            std::string::npos)
      << f.what;
  EXPECT_NE(f.what.find("change units: {length: m}"), std::string::npos) << f.what;
  const Failure si = failure_of("units: {ball.z: mm}\n" + body);
  EXPECT_NE(si.what.find("units: 'ball.z' is a body's coordinate, in m (the model's length "
                         "unit); it cannot be given 'mm'"),
            std::string::npos)
      << si.what;
  const Model same = parse_model("units: {length: mm, ball_x: mm}\n" + body, "units.yaml");
  EXPECT_EQ(same.coordinate_units[0], "mm");
}

// The defaults with a time dimension follow the model's time unit (u18 04: output every 0.01 ms
// wrote 1e6 samples of a 1e4 ms run): t_end 1 s, output_every 0.01 s, step 1e-3 s and Baumgarte's
// gains 10 per s, each in that unit; what the file gives is kept as written. A pendulum in ms
// run on its defaults samples as the same pendulum in s: 101 samples, at the same instants.
TEST(ModelUnits, TheTimeDefaultsFollowTheTimeUnit) {
  const std::string pendulum = R"(coordinates: [th]
kinetic_energy: 0.5*th_dot^2
potential_energy: -9.81e-6*cos(th)
initial: {q: {th: 0.5}}
)";
  const Model si = parse_model(kSlider);
  EXPECT_EQ(si.options.t_end, 1.0);
  EXPECT_EQ(si.options.output_every, 0.01);
  EXPECT_EQ(si.options.step, 1e-3);
  EXPECT_EQ(si.options.baumgarte_alpha, 10.0);
  const Model ms = parse_model(pendulum + "units: {time: ms}\n");
  EXPECT_EQ(ms.options.t_end, 1000.0);
  EXPECT_EQ(ms.options.output_every, 10.0);
  EXPECT_EQ(ms.options.step, 1.0);
  EXPECT_EQ(ms.options.baumgarte_alpha, 0.01);
  EXPECT_EQ(ms.options.baumgarte_beta, 0.01);
  const Model h = parse_model(kSlider + "units: {time: h}\n");
  EXPECT_DOUBLE_EQ(h.options.t_end, 1.0 / 3600.0);
  EXPECT_DOUBLE_EQ(h.options.output_every, 0.01 / 3600.0);
  EXPECT_DOUBLE_EQ(h.options.baumgarte_alpha, 36000.0);
  // given values are kept
  const Model given = parse_model(pendulum +
                                  "units: {time: ms}\nsimulate: {t_end: 50, step: 0.5}\noutput: "
                                  "{every: 5}\n");
  EXPECT_EQ(given.options.t_end, 50.0);
  EXPECT_EQ(given.options.step, 0.5);
  EXPECT_EQ(given.options.output_every, 5.0);
  // the run: θ'' = −(g/l) sin θ with g/l = 9.81 /s² = 9.81e-6 /ms², 101 samples 10 ms apart,
  // θ at 1000 ms as the SI pendulum's at 1 s (1e-8)
  const ModelRun run_ms = run_model(ms);
  const Model s_model = parse_model(
      "coordinates: [th]\nkinetic_energy: 0.5*th_dot^2\npotential_energy: -9.81*cos(th)\n"
      "initial: {q: {th: 0.5}}\n");
  const ModelRun run_s = run_model(s_model);
  ASSERT_EQ(run_ms.trajectory.samples(), 101);
  ASSERT_EQ(run_s.trajectory.samples(), 101);
  EXPECT_NEAR(run_ms.trajectory.t[50], 500.0, 1e-9);
  EXPECT_NEAR(run_ms.trajectory.q.back(), run_s.trajectory.q.back(), 1e-8);
}

// u24: a generalized model's contact columns had no unit in summary.json (gap.floor "", no
// lambda.stick.*), where a bodies model's had theirs. A block (m = 2000 g, coordinates x, y
// without a unit) in mm, g, s on a rough floor (yA >= 0, mu_s = 0.5), pushed along x by
// F = 0.3 m g < mu_s m g: it sticks, the floor holding −F; and a wheel's angle th (rad) against
// a stop (th >= 0.1): the floor's gap in mm and its forces in g·mm/s², the stop's gap in rad
// and its multipliers in the torque unit g·mm²/s² — every contact column of trajectory.csv
// labelled, each label a column.
TEST(ModelUnits, AGeneralizedModelsContactColumnsHaveTheModelsUnits) {
  const std::string text = R"(units: {length: mm, mass: g, time: s, x: mm, y: mm, th: rad}
parameters: {m: 2000, g: 9810, J: 5, F: 0.3*2000*9810}
coordinates: [x, y, th]
kinetic_energy: m/2*(x_dot^2 + y_dot^2) + J/2*th_dot^2
potential_energy: m*g*y
forces: [F, 0, 0]
constraints:
  - {name: floor, holonomic: y, unilateral: true}
  - {name: stop, holonomic: th - 0.1, unilateral: true}
nonideal:
  - {friction: coulomb, constraint: floor, mu: 0.4, mu_static: 0.5, coordinates: [x]}
initial: {q: {th: 0.1}}
simulate: {t_end: 0.1}
output: {every: 0.05}
)";
  const Model m = parse_model(text);
  const ModelRun run = run_model(m, m.options);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const RunProvenance p = model_provenance(m, "block.yaml", "", text, {}, {});
  const auto j = nlohmann::json::parse(summary_json(run.trajectory, m.options, &p));
  const nlohmann::json& units = j.at("units");
  const std::string force = "g·mm/s²", torque = "g·mm²/s²";
  EXPECT_EQ(units.value("gap.floor", "?"), "mm");
  EXPECT_EQ(units.value("lambda.floor", "?"), force);
  EXPECT_EQ(units.value("lambda_total.floor", "?"), force);
  EXPECT_EQ(units.value("lambda.stick.coulomb.floor", "?"), force);
  EXPECT_EQ(units.value("gap.stop", "?"), "rad");
  EXPECT_EQ(units.value("lambda.stop", "?"), torque);
  EXPECT_EQ(units.value("lambda_total.stop", "?"), torque);
  // every gap and multiplier column of the run has a label, and every label is a column
  std::vector<std::string> names;
  for (const CsvColumn& c : run.columns()) names.push_back(c.name);
  for (const std::string& name : names) {
    if (name.rfind("gap.", 0) == 0 || name.rfind("lambda", 0) == 0) {
      EXPECT_TRUE(units.contains(name)) << name;
    }
  }
  for (const auto& [name, unit] : units.items()) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
  // (the labels name the physics: the floor holds the push, −F = −0.3 m g = −5.886e6 g·mm/s²,
  // and bears m g = 1.962e7 g·mm/s²; the stop bears nothing)
  const std::size_t last = run.trajectory.t.size() - 1;
  const auto column = [&](const std::string& name) {
    for (const CsvColumn& c : run.columns())
      if (c.name == name) return c.values[last];
    ADD_FAILURE() << "no column " << name;
    return 0.0;
  };
  EXPECT_NEAR(column("lambda.stick.coulomb.floor"), -0.3 * 2000 * 9810, 1e-6 * 2000 * 9810);
  EXPECT_NEAR(column("lambda_total.floor"), 2000 * 9810, 1e-6 * 2000 * 9810);
  EXPECT_NEAR(column("lambda_total.stop"), 0.0, 1e-9);
  EXPECT_NEAR(column("x"), 0.0, 1e-9);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
