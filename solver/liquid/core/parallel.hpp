#pragma once
// One parallel loop for the library's OpenMP drivers. An exception thrown inside an OpenMP region
// would terminate the program, so every iteration runs under a guard that keeps the first failure
// and skips the remaining work; the loop rethrows it, with its type, once the threads have joined.
// A liquid::Error stays the named bad-input or run-time error it was; std::bad_alloc stays an
// internal error (the programs tell the two apart).

#include <atomic>
#include <exception>
#include <mutex>
#include <utility>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace liquid {

/// The first exception thrown by any of a parallel loop's iterations.
class FirstFailure {
 public:
  /// Runs f(), unless a failure is already recorded; records what f throws.
  template <class F>
  void run(F&& f) noexcept {
    if (failed_.load(std::memory_order_relaxed)) return;
    try {
      std::forward<F>(f)();
    } catch (...) {
      std::lock_guard lock(mutex_);
      if (!first_) first_ = std::current_exception();
      failed_.store(true, std::memory_order_relaxed);
    }
  }
  bool failed() const { return failed_.load(std::memory_order_relaxed); }
  /// Rethrows the recorded exception, if any.
  void rethrow() const {
    if (first_) std::rethrow_exception(first_);
  }

 private:
  std::atomic<bool> failed_{false};
  std::mutex mutex_;
  std::exception_ptr first_;
};

/// body(state, i) for i in [0, n) on OpenMP threads (dynamic schedule in chunks of `chunk`), with one
/// `state = make_state()` per thread, handed to `merge(state)` one thread at a time at the end.
/// Rethrows the first exception any call threw. Runs serially when n < `serial_below`.
template <class MakeState, class Body, class Merge>
void parallel_for(long n, MakeState&& make_state, Body&& body, Merge&& merge, int chunk = 64,
                  long serial_below = 0) {
  FirstFailure failure;
  std::mutex merge_mutex;
#pragma omp parallel if (n >= serial_below && n > 1)
  {
    decltype(make_state()) state{};
    failure.run([&] { state = make_state(); });
#pragma omp for schedule(dynamic, chunk)
    for (long i = 0; i < n; ++i) failure.run([&] { body(state, i); });
    failure.run([&] {
      std::lock_guard lock(merge_mutex);
      merge(state);
    });
  }
  failure.rethrow();
}

/// body(i) for i in [0, n); the first exception is rethrown after the loop.
template <class Body>
void parallel_for(long n, Body&& body, int chunk = 64, long serial_below = 0) {
  struct None {};
  parallel_for(
      n, [] { return None{}; }, [&](None&, long i) { body(i); }, [](None&) {}, chunk, serial_below);
}

/// While it lives, the parallel loops its thread starts run on one thread when `serial` is true; the
/// thread count comes back when it ends. For steps too small to pay for waking a second thread.
class SerialScope {
 public:
  explicit SerialScope(bool serial) {
#ifdef _OPENMP
    if (!serial) return;
    before_ = omp_get_max_threads();
    omp_set_num_threads(1);
#else
    (void)serial;
#endif
  }
  ~SerialScope() {
#ifdef _OPENMP
    if (before_ > 0) omp_set_num_threads(before_);
#endif
  }
  SerialScope(const SerialScope&) = delete;
  SerialScope& operator=(const SerialScope&) = delete;

 private:
  int before_ = 0;
};

}  // namespace liquid
