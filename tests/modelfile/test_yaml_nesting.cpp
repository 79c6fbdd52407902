// SPDX-License-Identifier: BSD-3-Clause
// The YAML reader's nesting on a small stack (modelfile/yaml_structure.cpp; reproducers
// 2026-11-28, limits_signals.sh: under `ulimit -s 64` 490 levels of brackets, below yaml-cpp's
// own limit of 500, overflowed the stack). The model is read on a thread whose whole stack is
// 64 kB: deep nesting is refused, located, instead of a crash; shallow nesting reads on.
#include <gtest/gtest.h>

#include <string>

#include <ukdyn/modelfile/model.hpp>

#include "support/small_stack.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// a model whose parameters: hold `depth` levels of brackets
std::string nested(int depth) {
  return "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\nparameters: " +
         std::string(std::size_t(depth), '[') + std::string(std::size_t(depth), ']') + "\n";
}

TEST(YamlNesting, DeepBracketsAreRefusedOnA64kBStack) {
  const std::string error = test::parse_on_stack(nested(490), 64 * 1024);
  EXPECT_NE(error.find("deep.yaml:3:"), std::string::npos) << error;
  EXPECT_NE(error.find("error: the YAML nests too deep for this process's stack"),
            std::string::npos)
      << error;
}

TEST(YamlNesting, ShallowNestingReadsOnA64kBStack) {
  // 8 levels get past the nesting check to the reader's own complaint about the value
  const std::string error = test::parse_on_stack(nested(8), 64 * 1024);
  EXPECT_EQ(error.find("nests too deep"), std::string::npos) << error;
  EXPECT_NE(error.find("deep.yaml:3:"), std::string::npos) << error;
  // and on a large stack, yaml-cpp's own limit still applies past 500 levels
  const std::string deeper = test::parse_on_stack(nested(600), 64 << 20);
  EXPECT_NE(deeper.find("the YAML nests too deep (more than"), std::string::npos) << deeper;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
