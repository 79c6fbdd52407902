// The YAML reader's nesting on a small stack (modelfile/yaml_structure.cpp; reproducers
// 2026-11-28, limits_signals.sh: under `ulimit -s 64` 490 levels of brackets, below yaml-cpp's
// own limit of 500, overflowed the stack). The model is read on a thread whose whole stack is
// 64 kB: deep nesting is refused, located, instead of a crash; shallow nesting reads on.
#include <gtest/gtest.h>

#include <pthread.h>

#include <string>

#include <ukdyn/modelfile/model.hpp>

namespace ukdyn {
namespace {

// parse_model(text) on a thread with a stack of `bytes`: "" when it read, else the error's text
std::string parse_on_small_stack(const std::string& text, std::size_t bytes) {
  struct Job {
    const std::string* text;
    std::string error;
  } job{&text, {}};
  auto body = [](void* p) -> void* {
    Job& j = *static_cast<Job*>(p);
    try {
      parse_model(*j.text, "deep.yaml");
    } catch (const std::exception& e) {
      j.error = e.what();
    }
    return nullptr;
  };
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, bytes);
  pthread_t thread;
  EXPECT_EQ(pthread_create(&thread, &attr, body, &job), 0);
  pthread_attr_destroy(&attr);
  pthread_join(thread, nullptr);
  return job.error;
}

// a model whose parameters: hold `depth` levels of brackets
std::string nested(int depth) {
  return "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\nparameters: " +
         std::string(std::size_t(depth), '[') + std::string(std::size_t(depth), ']') + "\n";
}

TEST(YamlNesting, DeepBracketsAreRefusedOnA64kBStack) {
  const std::string error = parse_on_small_stack(nested(490), 64 * 1024);
  EXPECT_NE(error.find("deep.yaml:3:"), std::string::npos) << error;
  EXPECT_NE(error.find("error: the YAML nests too deep for this process's stack"),
            std::string::npos)
      << error;
}

TEST(YamlNesting, ShallowNestingReadsOnA64kBStack) {
  // 8 levels get past the nesting check to the reader's own complaint about the value
  const std::string error = parse_on_small_stack(nested(8), 64 * 1024);
  EXPECT_EQ(error.find("nests too deep"), std::string::npos) << error;
  EXPECT_NE(error.find("deep.yaml:3:"), std::string::npos) << error;
  // and on a large stack, yaml-cpp's own limit still applies past 500 levels
  const std::string deeper = parse_on_small_stack(nested(600), 64 << 20);
  EXPECT_NE(deeper.find("the YAML nests too deep (more than"), std::string::npos) << deeper;
}

}  // namespace
}  // namespace ukdyn
