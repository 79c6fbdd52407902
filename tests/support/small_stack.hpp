// SPDX-License-Identifier: BSD-3-Clause
// A model file read on a thread with a stack of a given size (the readers' nesting checks against
// the actual stack: tests/modelfile/test_yaml_nesting.cpp, test_expression_nesting.cpp).
#pragma once

#include <link.h>
#include <pthread.h>

#include <cstddef>
#include <exception>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>

namespace ukdyn::test {

// The static thread-local storage of every object loaded (the sum of their PT_TLS segments,
// each aligned): glibc places it at the top of a new thread's stack, so a thread asked for
// `bytes` has `bytes` minus this for its frames, and pthread_create refuses (EINVAL) a stack
// smaller than it. (It is large: libopenblas, pulled in by Siconos Numerics, alone has 60 kB.)
inline std::size_t static_tls_bytes() {
  std::size_t total = 0;
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        for (int i = 0; i < info->dlpi_phnum; ++i) {
          const auto& ph = info->dlpi_phdr[i];
          if (ph.p_type != PT_TLS) continue;
          const std::size_t align = ph.p_align > 0 ? ph.p_align : 1;
          *static_cast<std::size_t*>(data) += (ph.p_memsz + align - 1) / align * align;
        }
        return 0;
      },
      &total);
  return total;
}

// parse_model(text, "deep.yaml") on a thread whose frames have a stack of `bytes` (the thread is
// given `bytes` plus the static TLS that glibc takes from its top): "" when it read, else the
// error's text
inline std::string parse_on_stack(const std::string& text, std::size_t bytes) {
  bytes += static_tls_bytes();
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
