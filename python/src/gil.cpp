// SPDX-License-Identifier: BSD-3-Clause
// The GIL at interpreter exit (common.hpp, "the GIL, at interpreter exit too"): the gate that
// the module's atexit hook closes before Python finalizes, so that no thread of a run takes the
// GIL during or after finalization (CPython would end it with pthread_exit, which terminates a
// C++ program: "terminate called without an active exception").
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "common.hpp"

namespace ukdyn::python {
namespace {

// How long the hook waits for the work under way to stop (a run stops at its next step: it asks
// every InterruptCheck::kInterval) and for a Python callable under way to return; after that,
// finalization goes on regardless.
constexpr auto kDrainTimeout = std::chrono::seconds(2);

struct Gate {
  std::mutex mutex;
  std::condition_variable drained;  // notified when inside and working fall to 0
  bool closed = false;
  std::thread::id closer;  // the thread that closed it (it goes on finalizing: never stopped)
  int inside = 0;          // threads taking or holding the GIL through the gate
  int working = 0;         // threads in a ReleasedGil scope (C++ work without the GIL)
  void notify_if_drained() {
    if (inside == 0 && working == 0) drained.notify_all();
  }
};

// never destroyed: threads parked at exit may still look at it while static objects die
Gate& gate() {
  static Gate* const g = new Gate;
  return *g;
}

// counts this thread in, unless the gate is closed to it
bool enter() {
  Gate& g = gate();
  const std::lock_guard<std::mutex> lock(g.mutex);
  if (g.closed && std::this_thread::get_id() != g.closer) return false;
  ++g.inside;
  return true;
}

void leave() {
  Gate& g = gate();
  const std::lock_guard<std::mutex> lock(g.mutex);
  --g.inside;
  g.notify_if_drained();
}

void start_work() {
  Gate& g = gate();
  const std::lock_guard<std::mutex> lock(g.mutex);
  ++g.working;
}

// the end of a ReleasedGil scope: counts this thread in to take the GIL back, or false when it
// must not (the gate is closed to it)
bool end_work() {
  Gate& g = gate();
  const std::lock_guard<std::mutex> lock(g.mutex);
  --g.working;
  g.notify_if_drained();
  if (g.closed && std::this_thread::get_id() != g.closer) return false;
  ++g.inside;
  return true;
}

[[noreturn]] void park() {
  for (;;) std::this_thread::sleep_for(std::chrono::hours(24));
}

// the atexit hook: closes the gate, then waits (without the GIL) for the threads inside to give
// the GIL back and for the work under way to stop, its threads parked
void close_gate() {
  Gate& g = gate();
  {
    const std::lock_guard<std::mutex> lock(g.mutex);
    g.closed = true;
    g.closer = std::this_thread::get_id();
    if (g.inside == 0 && g.working == 0) return;
  }
  py::gil_scoped_release release;  // (the hook runs before finalization: this is safe)
  std::unique_lock<std::mutex> lock(g.mutex);
  g.drained.wait_for(lock, kDrainTimeout, [&] { return g.inside == 0 && g.working == 0; });
}

}  // namespace

ReleasedGil::ReleasedGil() {
  py::detail::get_internals();  // (as pybind11's own release: before any gil_scoped_acquire)
  start_work();
  state_ = PyEval_SaveThread();
}

ReleasedGil::~ReleasedGil() {
  if (!end_work()) park();
  PyEval_RestoreThread(state_);
  leave();
}

AcquiredGil::AcquiredGil() {
  if (enter()) gil_.emplace();
}

AcquiredGil::~AcquiredGil() {
  if (!gil_) return;
  gil_.reset();
  leave();
}

void register_gil_gate(py::module_& m) {
  py::module_::import("atexit").attr("register")(
      py::cpp_function(&close_gate, py::name("_close_gil_gate"), py::scope(m),
                       py::doc("Closes the module's GIL gate (an atexit hook; gil.cpp).")));
}

}  // namespace ukdyn::python
