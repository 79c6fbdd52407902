// SPDX-License-Identifier: BSD-3-Clause
// A model file read on a thread with a stack of a given size (the readers' nesting checks against
// the actual stack: tests/modelfile/test_yaml_nesting.cpp, test_expression_nesting.cpp).
#pragma once

#include <pthread.h>

#include <cstddef>
#include <exception>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>

namespace ukdyn::test {

// parse_model(text, "deep.yaml") on a thread with a stack of `bytes`: "" when it read, else the
// error's text
inline std::string parse_on_stack(const std::string& text, std::size_t bytes) {
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

}  // namespace ukdyn::test
