// SPDX-License-Identifier: BSD-3-Clause
// The columns of trajectory.csv (issue #14, item 9; reliability report D13): every example
// model's columns have distinct names — so `ukdyn run` prints no duplicate-column warning —
// and a body's coordinate is found by both of its spellings, crank.x (the CSV, C++ and Python
// names) and crank_x (model-file expressions), with the same values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

namespace fs = std::filesystem;

std::vector<fs::path> example_files() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(UKDYN_EXAMPLES_DIR)) {
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// the column called name in run.columns()
std::vector<double> column(const ModelRun& run, const std::string& name) {
  for (const CsvColumn& c : run.columns()) {
    if (c.name == name) return c.values;
  }
  ADD_FAILURE() << "no column '" << name << "'";
  return {};
}

TEST(Columns, EveryExampleWritesEachColumnOnce) {
  const auto files = example_files();
  ASSERT_GE(files.size(), 30u);  // the gallery (examples/models)
  int multibody = 0;
  for (const fs::path& f : files) {
    SCOPED_TRACE(f.filename().string());
    const Model model = load_model(f.string());
    // (the names do not depend on the length of the run)
    SimulationOptions o = model.options;
    o.t_end = o.t_start + 0.02;
    o.output_at.clear();
    const ModelRun run = run_model(model, o);
    const auto standard = csv_columns(run.trajectory);
    std::set<std::string> seen;
    for (const CsvColumn& c : run.columns()) {
      EXPECT_TRUE(seen.insert(c.name).second) << "column '" << c.name << "' is written twice";
      EXPECT_EQ(c.values.size(), run.trajectory.t.size()) << c.name;
    }
    // what `ukdyn run` warns about: an extra column named like a standard one
    for (const CsvColumn& c : run.extra_columns) {
      EXPECT_EQ(std::count(standard.begin(), standard.end(), c.name), 0) << c.name;
    }
    if (model.multibody) ++multibody;
  }
  // slider_crank, double_four_bar_bodies(_redundant), heavy_top, pendulum_loop,
  // rolling_disk_bodies, bricard, …: the models of the report are among them
  EXPECT_GE(multibody, 6);
}

TEST(Columns, MultibodyPoseColumnsKeepWhatIsNotACoordinate) {
  // slider_crank: planar bodies crank, rod, slider — coordinates <b>.x, <b>.y, <b>.theta; the
  // pose adds <b>.z and the quaternion, not a second <b>.x, <b>.y
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/slider_crank.yaml");
  ASSERT_TRUE(model.multibody);
  SimulationOptions o = model.options;
  o.t_end = 0.25;
  const ModelRun run = run_model(model, o);
  std::map<std::string, int> count;
  for (const CsvColumn& c : run.columns()) ++count[c.name];
  for (const char* b : {"crank", "rod", "slider"}) {
    for (const char* s : {".x", ".y", ".theta", ".z", ".qw", ".qz"}) {
      EXPECT_EQ(count[std::string(b) + s], 1) << b << s;
    }
  }
  // the planar rotation about z as a quaternion: qw = cos(theta/2), qz = sin(theta/2)
  const auto theta = column(run, "crank.theta"), qw = column(run, "crank.qw"),
             qz = column(run, "crank.qz"), z = column(run, "crank.z");
  ASSERT_EQ(theta.size(), qw.size());
  for (std::size_t i = 0; i < theta.size(); ++i) {
    EXPECT_NEAR(qw[i], std::cos(theta[i] / 2), 1e-12);
    EXPECT_NEAR(qz[i], std::sin(theta[i] / 2), 1e-12);
    EXPECT_EQ(z[i], 0.0);
  }
}

// a particle falling from (0, 0, 1) with initial velocity (0, 2, 0), its coordinates named in
// both spellings in the file
constexpr const char* kFalling = R"(
name: falling particle
parameters: {g: 9.81}
bodies:
  - {name: b, type: particle, mass: 2, position: [0, 0, 1]}
forces:
  - {type: gravity, g: [0, 0, -g]}
initial:
  q: {b.x: 0.5}
  q_dot: {b_y: 2}
simulate: {t_end: 0.4}
output:
  every: 0.1
  expressions:
    height: b_z
)";

TEST(Columns, BodyCoordinatesAreFoundByBothSpellings) {
  const Model model = parse_model(kFalling, "falling.yaml");
  const System& sys = model.system;
  // C++ lookups
  const Index x = sys.coordinate_index("b.x");
  EXPECT_EQ(sys.coordinate_index("b_x"), x);
  EXPECT_EQ(sys.coordinate_index("b_z"), sys.coordinate_index("b.z"));
  EXPECT_THROW(sys.coordinate_index("b_w"), std::invalid_argument);
  // the file's initial: q: {b.x: …} and q_dot: {b_y: …}
  EXPECT_EQ(model.q0[x], 0.5);
  EXPECT_EQ(model.qd0[sys.coordinate_index("b.y")], 2.0);
  // the run: z = 1 − g t²/2, y = 2 t; the output expression b_z is the column b.z
  const ModelRun run = run_model(model);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const auto t = column(run, "t"), z = column(run, "b.z"), y = column(run, "b.y"),
             height = column(run, "height");
  ASSERT_EQ(t.size(), 5u);
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(z[i], 1.0 - 9.81 * t[i] * t[i] / 2, 1e-9);
    EXPECT_NEAR(y[i], 2.0 * t[i], 1e-9);
    EXPECT_EQ(height[i], z[i]);
  }
  std::set<std::string> names;
  for (const CsvColumn& c : run.columns()) {
    EXPECT_TRUE(names.insert(c.name).second) << c.name;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
