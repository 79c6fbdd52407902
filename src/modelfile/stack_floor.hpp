// SPDX-License-Identifier: BSD-3-Clause
// How deep a recursive reader may go on the calling thread's stack: shared by the YAML structure
// check (modelfile/yaml_structure.cpp) and the expression parser (modelfile/expression_parse.cpp),
// which both refuse, located, nesting the stack would not hold (under `ulimit -s 64` a model file
// used to crash the command with SIGSEGV).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include <pthread.h>

namespace ukdyn::detail {

/// The lowest address a recursive reader may reach on this thread's stack: its lowest address
/// (the guard page included) plus a reserve for what reading needs beyond the nesting itself (the
/// exception that reports it, the callers' frames); nullptr when the bounds are unknown (then
/// only the readers' own fixed limits apply). The reserve is a quarter of the stack, at most
/// 64 kB (a 64 kB stack keeps 16 kB).
inline const char* stack_floor() {
  pthread_attr_t attr;
  if (pthread_getattr_np(pthread_self(), &attr) != 0) return nullptr;
  void* base = nullptr;
  std::size_t size = 0;
  const bool known = pthread_attr_getstack(&attr, &base, &size) == 0 && base != nullptr;
  pthread_attr_destroy(&attr);
  const std::size_t reserve = std::min(size / 4, std::size_t(64) << 10);
  return known ? static_cast<const char*>(base) + reserve : nullptr;
}

/// The bytes of stack between `here` (an address in the caller's frame) and `floor` (from
/// stack_floor(); the stack grows down): 0 when `here` is at or below it, SIZE_MAX when the floor
/// is unknown.
inline std::size_t stack_left(const void* here, const char* floor) {
  if (floor == nullptr) return SIZE_MAX;
  const auto h = reinterpret_cast<std::uintptr_t>(here),
             f = reinterpret_cast<std::uintptr_t>(floor);
  return h > f ? std::size_t(h - f) : 0;
}

}  // namespace ukdyn::detail
