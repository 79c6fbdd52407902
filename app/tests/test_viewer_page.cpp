// SPDX-License-Identifier: BSD-3-Clause
// The command's viewer page (app/viewer_page.hpp): Python's rounding, JSON and template rules,
// with the values Python gives (round(), "%.*g", json.dumps: the expected values below are
// Python 3.11's), and the page data's decimation, pruning and arrow scales from analysis.
// python/tests/test_viewer_page.py compares whole pages with python/ukdyn/viewer.py's.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "viewer_page.hpp"

namespace ukdyn::cli {
namespace {

using json = nlohmann::ordered_json;

TEST(ViewerPage, RoundFixedIsPythonsRoundHalfToEven) {
  // (value, decimals, Python's round(value, decimals))
  const struct {
    double v;
    int decimals;
    double expected;
  } cases[] = {{0.125, 2, 0.12},
               {0.375, 2, 0.38},
               {2.5, 0, 2},
               {3.5, 0, 4},
               {25, -1, 20},
               {35, -1, 40},
               {25.5, -1, 30},
               {149, -2, 100},
               {150, -2, 200},
               {250, -2, 200},
               {999.9, -1, 1000},
               {-35, -1, -40},
               {4, -1, 0},
               {5, -1, 0},
               {5.0001, -1, 10},
               {1e-5, -400, 0},
               {123.456, 500, 123.456},
               {1.234e-5, 7, 1.23e-5}};
  for (const auto& c : cases) {
    const json r = round_fixed(c.v, c.decimals);
    ASSERT_TRUE(r.is_number()) << c.v;
    EXPECT_DOUBLE_EQ(r.get<double>(), c.expected) << c.v << " to " << c.decimals;
  }
  // whole values below 1e15 are JSON integers, the rest doubles; what is not finite is null
  EXPECT_TRUE(round_fixed(2.5, 0).is_number_integer());
  EXPECT_TRUE(round_fixed(0.125, 2).is_number_float());
  EXPECT_TRUE(round_fixed(std::nan(""), 2).is_null());
  EXPECT_TRUE(round_fixed(-std::numeric_limits<double>::infinity(), 2).is_null());
}

TEST(ViewerPage, RoundSignificantIsPythonsPercentG) {
  const json a = round_significant(1234.5678, 4);
  EXPECT_TRUE(a.is_number_integer());
  EXPECT_EQ(a.get<std::int64_t>(), 1235);
  EXPECT_DOUBLE_EQ(round_significant(0.000123456, 4).get<double>(), 0.0001235);
  EXPECT_DOUBLE_EQ(round_significant(-9.87654321, 7).get<double>(), -9.876543);
  EXPECT_TRUE(round_significant(0.0, 4).is_number_integer());
  EXPECT_TRUE(round_significant(std::nan(""), 4).is_null());
}

TEST(ViewerPage, NumbersAndStringsAreWrittenAsJsonDumps) {
  // json.dumps([1e-05, 0.0001, 1e16, 1e15, -0.0, 0.1, 123456789.123, 1.7976931348623157e308,
  // 5e-324, 12345678901234567.0], separators=(",", ":"))
  const json numbers = {1e-05,         0.0001,
                        1e16,          1e15,
                        -0.0,          0.1,
                        123456789.123, 1.7976931348623157e308,
                        5e-324,        12345678901234567.0};
  EXPECT_EQ(python_json(numbers),
            "[1e-05,0.0001,1e+16,1000000000000000.0,-0.0,0.1,123456789.123,"
            "1.7976931348623157e+308,5e-324,1.2345678901234568e+16]");
  // keys in insertion order; ensure_ascii: beyond ASCII (U+2028 among it) and DEL as \u escapes
  json object;
  object["b"] = 1;
  object["a"] = {true, nullptr, "\xc3\xa9\xe2\x80\xa8\x7f\"\\\n"};
  EXPECT_EQ(python_json(object), R"({"b":1,"a":[true,null,"\u00e9\u2028\u007f\"\\\n"]})");
  EXPECT_THROW(python_json(json(std::nan(""))), std::invalid_argument);
  // in the page: <, > and & as \u escapes, so no name ends the script element
  EXPECT_EQ(json_for_html(json("</script><!--&")), R"("\u003c/script\u003e\u003c!--\u0026")");
}

TEST(ViewerPage, TheTemplateIsFilledInOnePass) {
  // a name that spells a placeholder is only a name; three.js keeps no "</script"
  json data;
  data["model"] = "a<b> /*UKDYN_DATA*/null <!--UKDYN_TITLE-->";
  const std::string page = fill_viewer_template(
      "<title><!--UKDYN_TITLE--></title><script>/*UKDYN_THREE*/</script>"
      "<script type=\"application/json\">/*UKDYN_DATA*/null</script>",
      "x='</script>'", data);
  EXPECT_EQ(page,
            "<title>ukdyn: a&lt;b&gt; /*UKDYN_DATA*/null &lt;!--UKDYN_TITLE--&gt;</title>"
            "<script>x='<\\/script>'</script><script type=\"application/json\">"
            R"({"model":"a\u003cb\u003e /*UKDYN_DATA*/null \u003c!--UKDYN_TITLE--\u003e"})"
            "</script>");
}

TEST(ViewerPage, FramesAreThirtyPerSimulatedSecondWithBothEnds) {
  // 1 s sampled every ms: 31 frames, the first and the last sample among them, frame i the
  // last sample at or before i/30 s
  std::vector<double> t;
  for (int k = 0; k <= 1000; ++k) t.push_back(k / 1000.0);
  const std::vector<std::size_t> frames = shown_frames(t, {});
  ASSERT_EQ(frames.size(), 31u);
  EXPECT_EQ(frames.front(), 0u);
  EXPECT_EQ(frames.back(), 1000u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_NEAR(double(frames[i]), 1000.0 * double(i) / 30.0, 1.0) << i;
  }
  // sparser samples are all shown; a long run is capped at max_frames
  EXPECT_EQ(shown_frames({0.0, 2.5, 5.0, 7.5, 10.0}, {}).size(), 5u);
  std::vector<double> long_run;
  for (int k = 0; k <= 100000; ++k) long_run.push_back(k / 100.0);
  EXPECT_EQ(shown_frames(long_run, {}).size(), 3000u);
}

TEST(ViewerPage, ThePageDataPrunesZeroForcesAndScalesTheArrows) {
  // a planar body on a pin: reaction (3, 4) N throughout (|F| = 5), no friction, a torque about
  // z at round-off (1e-14 N m): the ideal force is drawn at scale 5, the rest not at all
  const json scene = json::parse(R"({"bodies": [{"kind": "planar", "mass": 1.0, "name": "bar"}],
    "joints": [{"child": "bar", "name": "pin", "parent": "ground"}], "model": "m",
    "planar": true, "points": [], "frames": [], "links": [], "trails": []})");
  ViewerColumns run;
  run.names = {"t",
               "bar.x",
               "bar.y",
               "bar.theta",
               "reaction.pin.fx",
               "reaction.pin.fy",
               "reaction.pin.tz",
               "reaction.pin.friction_fx",
               "reaction.pin.friction_fy"};
  run.columns.assign(run.names.size(), {});
  for (int k = 0; k <= 10; ++k) {
    const double values[] = {k / 10.0, 2.0 * k / 10.0, 0.123456789, 0.5, 3, 4, 1e-14, 0, 0};
    for (std::size_t c = 0; c < run.names.size(); ++c) run.columns[c].push_back(values[c]);
  }
  const json data = viewer_page_data(scene, run);
  const json& joint = data["joints"][0];
  EXPECT_TRUE(joint.contains("ideal"));
  EXPECT_FALSE(joint.contains("ideal_torque"));
  EXPECT_FALSE(joint.contains("nonideal"));
  EXPECT_DOUBLE_EQ(data["force_scale"]["ideal"].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(data["force_scale"]["nonideal"].get<double>(), 1.0);
  // positions spread over 2 m: kept to 1e-4 m (4 − floor(log10 2) = 4 decimals)
  EXPECT_DOUBLE_EQ(data["bodies"][0]["q"][1][0].get<double>(), 0.1235);
  EXPECT_EQ(data["t"].size(), 11u);
  // a column the scene needs and the run lacks is named
  run.names[3] = "bar.phi";
  try {
    (void)viewer_page_data(scene, run);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the trajectory has no column 'bar.theta', which the viewer draws");
  }
}

TEST(ViewerPage, ABodysControlTorqueIsDrawnAndARigidBodysDoesTheQuaternionForcesWork) {
  // a planar body's control torque is Qc_control.<b>.theta about z; a rigid body's the torque
  // tau whose power tau . omega equals the quaternion forces' Q . u' for every angular velocity
  // omega (u' = 1/2 (0, omega) u, the quaternion product: an independent formula), checked for
  // the three axes, which pins tau; the page's 4 significant digits allowed
  const json scene = json::parse(R"({"bodies": [{"kind": "planar", "mass": 1.0, "name": "bar"},
    {"kind": "rigid", "mass": 1.0, "name": "top"}], "model": "m", "planar": false,
    "coordinates": ["bar.x", "bar.theta"], "coordinate_units": ["m", "rad"]})");
  const double n = std::sqrt(0.3 * 0.3 + 0.5 * 0.5 + 0.7 * 0.7 + 0.4 * 0.4);
  const double u[4] = {0.3 / n, -0.5 / n, 0.7 / n, 0.4 / n}, Q[4] = {1.3, -0.4, 2.2, 0.9};
  ViewerColumns run;
  run.names = {"t",
               "bar.x",
               "bar.y",
               "bar.theta",
               "Qc_control.bar.theta",
               "top.x",
               "top.y",
               "top.z",
               "top.u0",
               "top.u1",
               "top.u2",
               "top.u3",
               "Qc_control.top.u0",
               "Qc_control.top.u1",
               "Qc_control.top.u2",
               "Qc_control.top.u3"};
  for (int k = 0; k <= 1; ++k) {
    const double values[] = {double(k), 0,    0,    0,    -10.4368, 0,    0,    0,
                             u[0],      u[1], u[2], u[3], Q[0],     Q[1], Q[2], Q[3]};
    run.columns.resize(run.names.size());
    for (std::size_t c = 0; c < run.names.size(); ++c) run.columns[c].push_back(values[c]);
  }
  const json data = viewer_page_data(scene, run);
  const json& bar = data["bodies"][0]["control_torque"];
  ASSERT_EQ(bar.size(), 3u);
  EXPECT_TRUE(bar[0].is_null() && bar[1].is_null());
  EXPECT_DOUBLE_EQ(bar[2][1].get<double>(), -10.44);  // 4 significant digits
  EXPECT_FALSE(data["bodies"][0].contains("control"));
  EXPECT_EQ(data["units"], json::parse(R"({"bar.x": "m", "bar.theta": "rad"})"));
  const json& top = data["bodies"][1]["control_torque"];
  ASSERT_EQ(top.size(), 3u);
  for (int axis = 0; axis < 3; ++axis) {
    // omega along the axis: u' = 1/2 (0, omega) u = 1/2 (-omega . v, w omega + omega x v)
    double omega[3] = {0, 0, 0};
    omega[axis] = 1.0;
    const double w = u[0], v[3] = {u[1], u[2], u[3]};
    const double cross[3] = {omega[1] * v[2] - omega[2] * v[1], omega[2] * v[0] - omega[0] * v[2],
                             omega[0] * v[1] - omega[1] * v[0]};
    const double ud[4] = {-0.5 * (omega[0] * v[0] + omega[1] * v[1] + omega[2] * v[2]),
                          0.5 * (w * omega[0] + cross[0]), 0.5 * (w * omega[1] + cross[1]),
                          0.5 * (w * omega[2] + cross[2])};
    const double power = Q[0] * ud[0] + Q[1] * ud[1] + Q[2] * ud[2] + Q[3] * ud[3];
    EXPECT_NEAR(top[axis][0].get<double>(), power, 5e-4 * std::fabs(power)) << axis;
  }
  EXPECT_GT(data["force_scale"]["control_torque"].get<double>(), 1.0);
}

TEST(ViewerPage, TheCsvIsReadWithItsQuotedNamesAndFirstNonFiniteTimes) {
  const std::filesystem::path csv =
      std::filesystem::temp_directory_path() / "ukdyn_test_viewer_page.csv";
  std::ofstream(csv) << "t,\"visual.a,b.x\",visual.p.x\n0,1,2\n0.5,nan,3\n1,inf,-inf\n";
  std::map<std::string, double> first;
  const ViewerColumns run = read_viewer_csv(csv, {}, {"visual.a,b.x", "visual.p.x"}, first);
  EXPECT_EQ(run.names, (std::vector<std::string>{"t", "visual.a,b.x", "visual.p.x"}));
  ASSERT_EQ(run.columns.size(), 3u);
  EXPECT_EQ(run.columns[0], (std::vector<double>{0, 0.5, 1}));
  EXPECT_DOUBLE_EQ(first.at("visual.a,b.x"), 0.5);
  EXPECT_DOUBLE_EQ(first.at("visual.p.x"), 1.0);
  // the warning names the point, the first time and the expression
  const json scene = json::parse(
      R"j({"points": [{"name": "p", "dimensions": 2, "expressions": ["log(x)", "y"]}]})j");
  EXPECT_EQ(nonfinite_warnings(scene, {{"visual.p.y", 0.5}, {"visual.p.x", 0.25}}),
            (std::vector<std::string>{"warning: visual point 'p' is not finite from t = 0.25 "
                                      "(its expression x: log(x)); the viewer hides it while so"}));
  // a field that is not a number is located
  std::ofstream(csv) << "t,x\n0,1\n0.5,abc\n";
  try {
    (void)read_viewer_csv(csv, {}, {}, first);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), csv.string() + ":3: 'abc' is not a number");
  }
  std::filesystem::remove(csv);
}

}  // namespace
}  // namespace ukdyn::cli
