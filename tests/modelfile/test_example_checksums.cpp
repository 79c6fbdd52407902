// SPDX-License-Identifier: BSD-3-Clause
// Every example model's trajectory is bitwise what it was (issue #15 item 7): a reorganization,
// a rename or a refactoring must not change a single bit of what users get. Each model of
// examples/models/ runs with its own `simulate:` settings as `ukdyn run` runs it (run_model),
// and a 64-bit FNV-1a hash of every column of trajectory.csv (names, then the values' bits) and
// of the run's status is compared with tests/data/example_checksums.txt.
//
// A change that is meant to change results (a speed-up that reorders a sum, a bug fix) updates
// the stored hashes on purpose, saying why in the commit:
//   UKDYN_UPDATE_CHECKSUMS=1 build/tests/ukdyn_test_example_checksums
// rewrites tests/data/example_checksums.txt (and the test then fails once, as a reminder).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "ukdyn/core/status.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kExamples = UKDYN_EXAMPLES_DIR;
const std::string kStored = std::string(UKDYN_TEST_DATA_DIR) + "/example_checksums.txt";

// FNV-1a, 64 bit, over bytes
struct Fnv {
  std::uint64_t h = 14695981039346656037ull;
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= b[i];
      h *= 1099511628211ull;
    }
  }
  void text(const std::string& s) { bytes(s.data(), s.size() + 1); }  // with its terminator
  void number(double v) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    bytes(&bits, sizeof bits);
  }
};

struct Checksum {
  std::size_t samples = 0;
  std::string hash;  // 16 hex digits
};

Checksum checksum_of(const std::string& file) {
  const Model model = load_model(kExamples + "/" + file);
  const ModelRun run = run_model(model, model.options);
  Fnv f;
  f.text(to_string(run.trajectory.stats.status));
  for (const CsvColumn& c : run.columns()) {
    f.text(c.name);
    for (const double v : c.values) f.number(v);
  }
  std::ostringstream hex;
  hex << std::hex;
  hex.width(16);
  hex.fill('0');
  hex << f.h;
  return {run.trajectory.t.size(), hex.str()};
}

std::vector<std::string> example_files() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kExamples))
    if (e.path().extension() == ".yaml") files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

// file → checksum, from tests/data/example_checksums.txt ("file samples hash" per line, '#'
// comments)
std::map<std::string, Checksum> stored() {
  std::map<std::string, Checksum> m;
  std::ifstream in(kStored);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string file;
    Checksum c;
    if (s >> file >> c.samples >> c.hash) m[file] = c;
  }
  return m;
}

TEST(ExampleChecksums, EveryExampleIsListed) {
  const auto m = stored();
  const auto files = example_files();
  ASSERT_EQ(files.size(), 48u) << "an example was added or removed: update the checksums";
  for (const auto& f : files) EXPECT_TRUE(m.count(f)) << f << " has no stored checksum";
  EXPECT_EQ(m.size(), files.size());
}

class ExampleChecksum : public ::testing::TestWithParam<std::string> {};

TEST_P(ExampleChecksum, TrajectoryIsBitwiseTheStoredOne) {
  const std::string file = GetParam();
  const Checksum now = checksum_of(file);
  const auto m = stored();
  ASSERT_TRUE(m.count(file)) << file << " has no stored checksum";
  EXPECT_EQ(now.samples, m.at(file).samples) << file;
  EXPECT_EQ(now.hash, m.at(file).hash) << file << ": the trajectory changed";
}

INSTANTIATE_TEST_SUITE_P(Examples, ExampleChecksum, ::testing::ValuesIn(example_files()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param.substr(0, p.param.size() - 5);
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

// UKDYN_UPDATE_CHECKSUMS=1: rewrite the stored file (then fail, so that it is never silent)
TEST(ExampleChecksums, UpdateWhenAsked) {
  if (!std::getenv("UKDYN_UPDATE_CHECKSUMS")) GTEST_SKIP() << "UKDYN_UPDATE_CHECKSUMS not set";
  std::ofstream out(kStored);
  out << "# example model → samples and FNV-1a hash of trajectory.csv's columns "
         "(tests/modelfile/test_example_checksums.cpp)\n";
  for (const auto& f : example_files()) {
    const Checksum c = checksum_of(f);
    out << f << ' ' << c.samples << ' ' << c.hash << '\n';
  }
  ADD_FAILURE() << "rewrote " << kStored;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
