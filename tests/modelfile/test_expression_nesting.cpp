// SPDX-License-Identifier: BSD-3-Clause
// Deep expressions on a small stack (reproducers 2026-11-28, limits_signals.sh: an expression
// nested 99 deep, within the parser's limit of 100, crashed the command under `ulimit -s 128`).
// The parser recurses once per level of parentheses, calls and signs, and so do GiNaC and the
// compiler afterwards (derivatives, evaluation, destruction); modelfile/expression_parse.cpp
// refuses, located, the nesting this thread's stack would not hold. Each model is read on a
// thread with a stack of a given size: a depth is either read whole or refused with the
// located error, never a crash; on a usual stack the fixed limit of 100 still decides.
#include <gtest/gtest.h>

#include <string>

#include <ukdyn/modelfile/model.hpp>

#include "support/small_stack.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// `depth` levels of one kind of nesting around x (every kind depends on x, so it is
// differentiated): sin(sin(…x…)), -(-(…x…)) written as --x, ((…x…)), and a mix of calls,
// signs, parentheses and powers
std::string nest(const std::string& kind, int depth) {
  std::string open, close;
  for (int i = 0; i < depth; ++i) {
    if (kind == "calls") {
      open += "sin(";
      close += ")";
    } else if (kind == "signs") {
      open += "-";
    } else if (kind == "parentheses") {
      open += "(";
      close += ")";
    } else {  // mixed, one level each
      const char* o[] = {"sqrt(2+", "- ", "(1+x*", "atan2(1, "};
      open += o[i % 4];
      if (i % 4 != 1) close += ")";
    }
  }
  return open + "x" + std::string(close.rbegin(), close.rend());
}

// a model holding the expression e where `place` says: in the potential (line 3, e one level
// deep), in the kinetic energy (the mass matrix then depends on x; line 2, e four levels deep)
// or in a constraint (line 6, e one level deep)
std::string model(const std::string& place, const std::string& e) {
  if (place == "potential")
    return "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\npotential_energy: " + e +
           "\n";
  if (place == "kinetic")
    return "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2*(3 + sin(" + e + ")) + y_dot^2)\n";
  return "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\npotential_energy: y\n"
         "constraints:\n  - name: c\n    holonomic: \"y - " +
         e + "\"\n";
}

// AddressSanitizer's redzones make every frame several times larger: the stacks below are
// scaled so that the same depths fit (the reader measures the stack it has, so an unscaled run
// under ASan refuses even shallow expressions, correctly, with the located error)
#if defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kStackFactor = 4;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr std::size_t kStackFactor = 4;
#else
constexpr std::size_t kStackFactor = 1;
#endif
#else
constexpr std::size_t kStackFactor = 1;
#endif

const char* const kKinds[] = {"calls", "signs", "parentheses", "mixed"};
const char* const kPlaces[] = {"potential", "kinetic", "constraint"};

TEST(ExpressionNesting, DeepExpressionsAreReadOrRefusedOnSmallStacks) {
  for (const std::size_t kb : {64, 96, 128, 256}) {
    for (const char* kind : kKinds) {
      for (const char* place : kPlaces) {
        for (const int depth : {30, 60, 99}) {
          const std::string error =
              test::parse_on_stack(model(place, nest(kind, depth)), (kb * kStackFactor) << 10);
          if (error.empty()) continue;
          SCOPED_TRACE(std::string(kind) + " in the " + place + ", " + std::to_string(depth) +
                       " deep, " + std::to_string(kb) + " kB");
          EXPECT_NE(error.find("deep.yaml:"), std::string::npos) << error;
          // refused for the stack, or (on a larger stack: ASan's are scaled) by the fixed limit of
          // 100 levels that the kinetic energy's own wrapping can reach: located either way
          EXPECT_TRUE(error.find("the expression nests too deep for this process's stack") !=
                          std::string::npos ||
                      error.find("the expression nests more than 100 deep") != std::string::npos)
              << error;
        }
      }
    }
  }
}

TEST(ExpressionNesting, ShallowExpressionsReadOnSmallStacks) {
  // 64 kB: what a pendulum needs (two levels in the potential and a constraint)
  for (const char* kind : kKinds) {
    EXPECT_EQ(test::parse_on_stack(model("potential", nest(kind, 2)), (64 * kStackFactor) << 10),
              "")
        << kind;
    EXPECT_EQ(test::parse_on_stack(model("constraint", nest(kind, 2)), (64 * kStackFactor) << 10),
              "")
        << kind;
  }
  // 256 kB: 40 levels anywhere
  for (const char* kind : kKinds)
    for (const char* place : kPlaces)
      EXPECT_EQ(test::parse_on_stack(model(place, nest(kind, 40)), (256 * kStackFactor) << 10), "")
          << kind << " in the " << place;
}

TEST(ExpressionNesting, OnAUsualStackTheFixedLimitDecides) {
  // 8 MB: 100 levels read (96 in the kinetic energy, which adds four), of every kind and in
  // every place; 101 are refused by the fixed limit
  for (const char* kind : kKinds) {
    for (const char* place : kPlaces) {
      const int depth = std::string(place) == "kinetic" ? 96 : 99;
      EXPECT_EQ(test::parse_on_stack(model(place, nest(kind, depth)), 8 << 20), "")
          << kind << " in the " << place;
      const std::string error = test::parse_on_stack(model(place, nest(kind, 101)), 8 << 20);
      EXPECT_NE(error.find("the expression nests more than 100 deep"), std::string::npos) << error;
    }
  }
  // the located error: line 3, the column of the operand that goes one level too deep
  const std::string error = test::parse_on_stack(model("potential", nest("calls", 300)), 64 << 10);
  EXPECT_NE(error.find("deep.yaml:3:"), std::string::npos) << error;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
